/* libFuzzer target: the blob validator, the sensor decoder and both applies on arbitrary bytes.
 * The validator is given the device id found in the input itself, so the fuzzer can reach
 * the section walker and the decoder. Run by fuzz/run.sh under ASan and UBSan. */
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "metro_fw/blob.h"
#include "metro_fw/crc.h"
#include "metro_fw/fixed.h"

int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size);

static void Check(const uint8_t* data, size_t size);

/* Each input is checked as is and, so the fuzzer gets past the CRC, with a correct CRC word
 * written at total_len - 4 when total_len lies inside the input. */
int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static uint8_t copy[2 * METRO_FW_MAX_LEN];
  uint32_t total, crc;
  if (size > sizeof(copy)) return 0;
  Check(data, size);
  if (size < 12) return 0;
  total = (uint32_t)data[8] | ((uint32_t)data[9] << 8);
  if (total < 8 || total > size) return 0;
  memcpy(copy, data, size);
  crc = metro_fw_crc32(0, copy, total - 4);
  copy[total - 4] = (uint8_t)crc;
  copy[total - 3] = (uint8_t)(crc >> 8);
  copy[total - 2] = (uint8_t)(crc >> 16);
  copy[total - 1] = (uint8_t)(crc >> 24);
  Check(copy, size);
  return 0;
}

static void Check(const uint8_t* data, size_t size) {
  metro_fw_buffer buf;
  metro_fw_blob_info info;
  metro_fw_config cfg;
  metro_fw_sensor_cal cal;
  uint32_t id[2] = {0, 0};
  int i;
  if (size >= 24) {
    for (i = 0; i < 4; ++i) {
      id[0] |= (uint32_t)data[16 + i] << (8 * i);
      id[1] |= (uint32_t)data[20 + i] << (8 * i);
    }
  }
  buf.data = data;
  buf.len = (uint32_t)size;
  if (metro_fw_blob_validate(metro_fw_buffer_read, &buf, (uint32_t)size, id, &info) !=
      METRO_FW_OK) {
    return;
  }
  /* Issue #20: an accepted blob declares at least one sensor, exactly the sections present,
   * and every declared sensor is usable on its own configuration. */
  if ((info.flags & 3u) == 0u) abort();
  for (i = 0; i < 2; ++i) {
    const int declared = (int)((info.flags >> i) & 1u);
    if (metro_fw_sensor_decode(metro_fw_buffer_read, &buf, &info, (metro_fw_sensor_kind)i, 0,
                               &cal) != METRO_FW_OK ||
        cal.status != (declared ? METRO_FW_SENSOR_OK : METRO_FW_SENSOR_ABSENT)) {
      abort();
    }
  }
  cfg.device_id[0] = id[0];
  cfg.device_id[1] = id[1];
  cfg.accel_fs_sel = 0;
  cfg.gyro_fs_sel = 0;
  cfg.dlpf_cfg = 3;
  cfg.accel_input = METRO_FW_INPUT_INT16;
  cfg.gyro_input = METRO_FW_INPUT_OFFSET_BINARY;
  if (metro_fw_sensor_decode(metro_fw_buffer_read, &buf, &info, METRO_FW_ACCEL, &cfg, &cal) ==
      METRO_FW_OK) {
    const int16_t raw[3] = {32767, -32768, 1};
    float y[3];
    metro_fw_sensor_fixed fx;
    int32_t y_q20[3];
    (void)metro_fw_apply(&cal, raw, 30.0f, y);
    /* Every section that passes 3.1 (and the defaults) converts to the fixed-point formats
     * (3.1 bounds |b1| < 2^15 and |b2| < 2^7), and applies without UB at the int16 corners and
     * beyond the validity range. */
    if (metro_fw_fixed_from_cal(&cal, &fx) != METRO_FW_OK) abort();
    (void)metro_fw_apply_fixed(&fx, raw, 200 * 4096, y_q20);
    (void)metro_fw_apply_fixed(&fx, raw, -100 * 4096, y_q20);
  }
  (void)metro_fw_sensor_decode(metro_fw_buffer_read, &buf, &info, METRO_FW_GYRO, &cfg, &cal);
}
