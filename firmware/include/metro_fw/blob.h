/* Calibration blob format v1: validation, active-slot choice, load at boot and the model.
 *
 * Model (docs/calibration-blob.md section 3), raw int16 counts in, SI out (accelerometer
 * m/s^2, gyroscope rad/s):
 *
 *   y = M * (r - b0 - b1*dT - b2*dT^2),  dT = clamp(T, t_valid_min_c, t_valid_max_c) - t_ref_c
 *
 * Bias is removed before scaling, in raw counts; M (row-major, SI per LSB) holds nominal
 * sensitivity, scale, misalignment and any sensor-to-body rotation. M = diag(s_nom), b = 0 is
 * the identity used when a sensor is uncalibrated.
 *
 * Nothing here allocates or touches stdio; the caller owns every struct. */
#ifndef METRO_FW_BLOB_H_
#define METRO_FW_BLOB_H_

#include <stdint.h>

#include "metro_fw/error.h"
#include "metro_fw/flash.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Header (section 2.1). */
#define METRO_FW_MAGIC 0x4C414349u /* "ICAL" little-endian */
#define METRO_FW_ERASED_WORD 0xFFFFFFFFu
#define METRO_FW_FMT_MAJOR 1u
#define METRO_FW_FMT_MINOR 0u
#define METRO_FW_HEADER_LEN 32u
#define METRO_FW_MAX_LEN 1024u
#define METRO_FW_SEQ_MIN 1u
#define METRO_FW_SEQ_MAX 0xFFFFFFFEu
#define METRO_FW_FLAG_ACCEL 0x01u
#define METRO_FW_FLAG_GYRO 0x02u
#define METRO_FW_FLAG_TEMP_MODEL 0x04u
#define METRO_FW_FLAG_PROVISIONAL 0x08u

/* Sections (section 2.2). */
#define METRO_FW_SECTION_HEADER_LEN 8u
#define METRO_FW_SEC_META 0x0001u
#define METRO_FW_SEC_ACCEL 0x0010u
#define METRO_FW_SEC_GYRO 0x0011u
#define METRO_FW_SEC_VERSION_1_0 0x0100u
/* Sensor section v2.0 (issue #25, docs/calibration-blob.md 2.4): the v1.0 body whose reserved
 * byte 3 is the raw input's encoding and whose reserved u32 at 172 is the declared nominal
 * sensitivity s_nom (binary32, SI per LSB). A firmware that knows only major 1 refuses a blob
 * that declares such a sensor (section 2.2), so it never applies these constants. */
#define METRO_FW_SEC_VERSION_2_0 0x0200u
#define METRO_FW_META_BODY_LEN 128u
#define METRO_FW_SENSOR_BODY_LEN 176u
#define METRO_FW_V1_TOTAL_LEN 540u

/* Sensor model bits (section 2.4). */
#define METRO_FW_MODEL_BIAS 0x01u
#define METRO_FW_MODEL_FULL_M 0x02u
#define METRO_FW_MODEL_LINEAR_T 0x04u
#define METRO_FW_MODEL_QUADRATIC_T 0x08u
#define METRO_FW_MODEL_HW_OFFSETS 0x80u

#define METRO_FW_SLOT_NONE (-1)

/* Raw input encodings of a sensor (v2.0 byte 3; a v1.0 section is METRO_FW_INPUT_INT16). The
 * applies take signed counts about the input's zero: an int16 sample as it is, an unsigned
 * 16-bit (offset-binary) ADC word u as METRO_FW_OFFSET_BINARY_TO_INT16(u) = u - 32768. */
#define METRO_FW_INPUT_INT16 0u
#define METRO_FW_INPUT_OFFSET_BINARY 1u
#define METRO_FW_OFFSET_BINARY_TO_INT16(u) ((int16_t)((int32_t)(uint16_t)(u)-32768))

/* The nominal sensitivity a v2.0 section may declare, SI per LSB: 2^-14 <= s_nom < 2^-7
 * (6.1e-5 ... 7.8e-3; accelerometer 160 000 ... 1255 LSB/g, gyroscope 286 ... 2.24
 * LSB/(deg/s)), i.e. M in Q(141 - e) for s_nom's biased binary32 exponent e, 22 ... 28. The
 * upper end keeps M and the output inside the fixed-point apply's formats (3.2), the lower
 * end its error below 0.1 LSB. Every MPU6050 setting lies inside. */
#define METRO_FW_S_NOM_MIN_Q 22
#define METRO_FW_S_NOM_MAX_Q 28

/* Plausibility limits of a sensor section (section 3.1), which the host tools also apply when
 * they build a blob.
 * - The temperature coefficient of the bias anywhere in the validity range, |b1| + 2 |b2| D
 *   (D = max |t_valid - t_ref_c|), in LSB/degC at fs_sel 0 (halved per fs_sel step): twice the
 *   steepest slope around 25 degC that the MPU6050 datasheet (PS-MPU-6000A rev 3.4 sections
 *   6.1, 6.2) allows, rounded up to a multiple of 8 LSB. Accelerometer: zero-g level change
 *   +-60 mg (z; x, y +-35 mg) over 0..70 degC, 60 mg / 25 degC = 2.4 mg/degC, twice that is
 *   78.6 LSB/degC -> 80 (4.9 mg/degC). Gyroscope: ZRO variation +-20 deg/s over -40..85 degC,
 *   20 deg/s / 60 degC = 0.33 deg/s/degC, twice that is 87.4 LSB/degC -> 88 (0.67 deg/s/degC).
 * - The narrowest validity range, degC: twice the +-1 degC linearity of the MPU6050
 *   temperature sensor (section 6.3).
 * With these the fixed-point apply stays within 0.1 LSB of the exact model (section 3.2). */
#define METRO_FW_ACCEL_TEMPCO_LIMIT_LSB 80
#define METRO_FW_GYRO_TEMPCO_LIMIT_LSB 88
#define METRO_FW_T_VALID_MIN_SPAN_C 2

/* Reads len bytes at offset of a blob into dst; 0 on success, negative on failure. The
 * validator reads through this so a slot is never copied whole into RAM. */
typedef int (*metro_fw_read_fn)(void* ctx, uint32_t offset, uint8_t* dst, uint32_t len);

/* A blob in RAM, for metro_fw_buffer_read. */
typedef struct {
  const uint8_t* data;
  uint32_t len;
} metro_fw_buffer;

/* metro_fw_read_fn over a metro_fw_buffer (ctx). Returns METRO_FW_E_BOUNDS past its end. */
int metro_fw_buffer_read(void* ctx, uint32_t offset, uint8_t* dst, uint32_t len);

/* What the validator learned about a valid blob. Body offsets are from the blob start; an
 * offset of 0 means the section is absent. */
typedef struct {
  uint16_t fmt_major;
  uint16_t fmt_minor;
  uint16_t total_len;
  uint16_t header_len;
  uint32_t seq;
  uint32_t device_id[2];
  uint32_t flags;
  uint32_t crc32;
  uint16_t meta_off, meta_len, meta_version;
  uint16_t accel_off, accel_len, accel_version;
  uint16_t gyro_off, gyro_len, gyro_version;
} metro_fw_blob_info;

/* Validates the blob readable through read/ctx, of which avail_len bytes exist (1024 for a
 * flash slot), against the chip's device_id[2], in the order of section 4:
 * METRO_FW_E_EMPTY, METRO_FW_E_MAGIC, METRO_FW_E_UNSUPPORTED, METRO_FW_E_BOUNDS (also
 * fmt_minor 0 with header_len != 32), METRO_FW_E_CRC, METRO_FW_E_FOREIGN, METRO_FW_E_SEQ,
 * METRO_FW_E_SECTION (also a v1.0 section whose body is not exactly the v1.0 length), then the
 * sensors: METRO_FW_E_UNSUPPORTED for a declared sensor section of unknown major,
 * METRO_FW_E_SENSOR when flags b0/b1 do not name exactly the sensor sections present (at least
 * one), a declared section fails 3.1 on its own fs_sel/dlpf_cfg (fs_sel 0..3, dlpf_cfg 0..6)
 * or flag b2 disagrees with the sections' temperature terms; METRO_FW_E_ARG for NULL pointers;
 * a failing read returns its code. info may be NULL; it is filled (header
 * fields at least) whenever the header could be read. Never reads outside [0, avail_len). */
int metro_fw_blob_validate(metro_fw_read_fn read, void* ctx, uint32_t avail_len,
                           const uint32_t device_id[2], metro_fw_blob_info* info);

/* Per-sensor status after loading (section 3.1). */
enum metro_fw_sensor_status {
  METRO_FW_SENSOR_OK = 0,              /* calibrated from the active slot */
  METRO_FW_SENSOR_ABSENT = 1,          /* no active slot or no section: defaults */
  METRO_FW_SENSOR_UNSUPPORTED = 2,     /* section major unknown: defaults */
  METRO_FW_SENSOR_NONFINITE = 3,       /* NaN/Inf, or a negative uncertainty: defaults */
  METRO_FW_SENSOR_BAD_MODEL = 4,       /* unknown model bits: defaults */
  METRO_FW_SENSOR_CONFIG_MISMATCH = 5, /* fs_sel/dlpf_cfg/input differ from the firmware's */
  METRO_FW_SENSOR_LIMITS = 6           /* constants outside physical limits: defaults */
};

typedef enum { METRO_FW_ACCEL = 0, METRO_FW_GYRO = 1 } metro_fw_sensor_kind;

/* The constants the firmware applies. Terms whose model bit is clear are zero (and M is
 * diagonal without METRO_FW_MODEL_FULL_M), so metro_fw_apply needs no branches on bits. */
typedef struct {
  float m[9];  /* row-major, SI per LSB */
  float b0[3]; /* LSB */
  float b1[3]; /* LSB/degC */
  float b2[3]; /* LSB/degC^2 */
  float t_ref_c;
  float t_valid_min_c;
  float t_valid_max_c;
  int16_t hw_offs[3]; /* MPU6050 offset register values (informational) */
  uint8_t model_bits;
  uint8_t status; /* enum metro_fw_sensor_status */
  uint8_t input;  /* METRO_FW_INPUT_*: how the driver turns a sample into the applies' int16 */
} metro_fw_sensor_cal;

/* The firmware's own configuration, which a section must match. */
typedef struct {
  uint32_t device_id[2]; /* FICR DEVICEID[0], DEVICEID[1] */
  uint8_t accel_fs_sel;  /* 0..3 */
  uint8_t gyro_fs_sel;   /* 0..3 */
  uint8_t dlpf_cfg;      /* 0..6 */
  uint8_t accel_input;   /* METRO_FW_INPUT_* of the accelerometer's driver (0: int16) */
  uint8_t gyro_input;    /* METRO_FW_INPUT_* of the gyroscope's driver (0: int16) */
} metro_fw_config;

/* The result of loading at boot: what the firmware publishes. */
typedef struct {
  metro_fw_sensor_cal accel;
  metro_fw_sensor_cal gyro;
  int slot;           /* 0 = A, 1 = B, METRO_FW_SLOT_NONE = uncalibrated */
  int slot_result[2]; /* validator code of each slot */
  uint32_t seq;       /* of the active slot, 0 if none */
  uint32_t crc32;     /* of the active slot, 0 if none */
  uint32_t flags;     /* header flags of the active slot, 0 if none */
} metro_fw_calibration;

/* Identity defaults for fs_sel: M = diag(s_nom), b = 0, t_ref 25 degC, valid -40..85 degC,
 * status METRO_FW_SENSOR_ABSENT. s_nom is the nominal sensitivity, SI per LSB: accel
 * 9.80665 / (16384 >> fs_sel) m/s^2, gyro (250 << fs_sel) / 32768 * pi / 180 rad/s (MPU6050
 * PS-MPU-6000A rev 3.4 tables 6.1, 6.2), each the binary32 nearest the fs_sel 0 value times
 * 2^fs_sel. Returns METRO_FW_E_ARG for NULL, fs_sel > 3 or a bad kind. */
int metro_fw_sensor_defaults(metro_fw_sensor_kind kind, uint8_t fs_sel, metro_fw_sensor_cal* out);

/* Decodes the section of sensor `kind` (its body offset, length and version in info, as
 * metro_fw_blob_validate found them) of a blob the validator accepted, and checks it against
 * cfg (section 3.1). Section majors 1 and 2 are read; a v2.0 section's limits are relative to
 * its declared s_nom and input (an input code above 1 is BAD_MODEL, an input other than cfg's
 * CONFIG_MISMATCH; a v1.0 section's input is METRO_FW_INPUT_INT16). On a usable section *out holds
 * its constants with status METRO_FW_SENSOR_OK; otherwise *out holds the defaults and the status
 * says why (a body offset of 0: METRO_FW_SENSOR_ABSENT). cfg NULL is the validator's form: the
 * section is checked on its own fs_sel and dlpf_cfg, which must be 0..3 and 0..6 (else
 * CONFIG_MISMATCH), and the defaults are fs_sel 0's. Returns METRO_FW_OK (whatever the status),
 * METRO_FW_E_ARG for NULL read/info/out, a bad kind or a body shorter than v1.0's, or a failing
 * read's code (out then holds the defaults). */
int metro_fw_sensor_decode(metro_fw_read_fn read, void* ctx, const metro_fw_blob_info* info,
                           metro_fw_sensor_kind kind, const metro_fw_config* cfg,
                           metro_fw_sensor_cal* out);

/* Boot: chooses the active slot and decodes both sensors (never writes flash). Without a
 * valid slot both sensors get the defaults and out->slot is METRO_FW_SLOT_NONE. Returns
 * METRO_FW_OK, or METRO_FW_E_ARG for NULL pointers / fs_sel > 3 (out is then untouched). */
int metro_fw_load(const metro_fw_flash* flash, const metro_fw_config* cfg,
                  metro_fw_calibration* out);

/* y = M * (r - b0 - b1*dT - b2*dT^2) with dT = clamp(temp_c, valid range) - t_ref_c; a NaN
 * temp_c counts as t_ref_c. Returns METRO_FW_OK or METRO_FW_E_ARG for NULL pointers. */
int metro_fw_apply(const metro_fw_sensor_cal* cal, const int16_t raw_lsb[3], float temp_c,
                   float out_si[3]);

/* MPU6050 die temperature: T = raw / 340 + 36.53 degC (PS-MPU-6000A rev 3.4 sec. 6.4). */
float metro_fw_mpu6050_temp_c(int16_t raw_lsb);

#ifdef __cplusplus
}
#endif

#endif /* METRO_FW_BLOB_H_ */
