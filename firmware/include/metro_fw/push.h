/* Receive side of the calibration push protocol (docs/calibration-blob.md section 7).
 *
 * Bytes arriving from BLE NUS (any chunking) go to metro_fw_push_rx; SLIP frames
 * `op, txn, len u16, payload, crc16 u16` are decoded, executed against the flash and
 * answered through the send callback. The caller owns the metro_fw_push struct (about
 * 1.2 KiB: it holds the blob being received). */
#ifndef METRO_FW_PUSH_H_
#define METRO_FW_PUSH_H_

#include <stdint.h>

#include "metro_fw/blob.h"
#include "metro_fw/flash.h"

#ifdef __cplusplus
extern "C" {
#endif

/* SLIP (RFC 1055). */
#define METRO_FW_SLIP_END 0xC0u
#define METRO_FW_SLIP_ESC 0xDBu
#define METRO_FW_SLIP_ESC_END 0xDCu
#define METRO_FW_SLIP_ESC_ESC 0xDDu

#define METRO_FW_PUSH_MAX_PAYLOAD 32u
#define METRO_FW_PUSH_FRAME_OVERHEAD 6u /* op, txn, len u16, crc16 u16 */
#define METRO_FW_PUSH_MAX_FRAME (METRO_FW_PUSH_MAX_PAYLOAD + METRO_FW_PUSH_FRAME_OVERHEAD)
#define METRO_FW_PUSH_MAX_CHUNK 16u /* data bytes per CAL_WRITE / CAL_READ */
#define METRO_FW_PUSH_RESPONSE_BIT 0x80u

enum metro_fw_push_op {
  METRO_FW_OP_GET_INFO = 0x01,
  METRO_FW_OP_CAL_CREATE = 0x02,
  METRO_FW_OP_CAL_WRITE = 0x03,
  METRO_FW_OP_CAL_GET_CRC = 0x04,
  METRO_FW_OP_CAL_EXECUTE = 0x05,
  METRO_FW_OP_CAL_READ = 0x06,
  METRO_FW_OP_ABORT = 0x07,
  METRO_FW_OP_NAK = 0xFF
};

enum metro_fw_push_result {
  METRO_FW_RES_SUCCESS = 0x01,
  METRO_FW_RES_BAD_STATE = 0x02,
  METRO_FW_RES_CRC_MISMATCH = 0x03,
  METRO_FW_RES_FOREIGN_DEVICE = 0x04,
  METRO_FW_RES_STALE_SEQ = 0x05,
  METRO_FW_RES_UNSUPPORTED_FORMAT = 0x06,
  METRO_FW_RES_FLASH_ERROR = 0x07,
  METRO_FW_RES_INVALID_PARAM = 0x08,
  METRO_FW_RES_INVALID_OFFSET = 0x09,
  METRO_FW_RES_INVALID_BLOB = 0x0A,
  METRO_FW_RES_UNKNOWN_OP = 0x0B,
  METRO_FW_RES_FRAME_ERROR = 0x0C,
  METRO_FW_RES_NO_CALIBRATION = 0x0D
};

/* Sends len encoded bytes towards the PC; returns 0 on success. */
typedef int (*metro_fw_send_fn)(void* ctx, const uint8_t* data, uint32_t len);

typedef struct {
  /* Set by metro_fw_push_init. */
  const metro_fw_flash* flash;
  uint32_t device_id[2];
  metro_fw_send_fn send;
  void* send_ctx;
  /* Set to 1 when CAL_EXECUTE committed a new calibration: the application reloads it
   * (metro_fw_load) and clears the flag. */
  uint8_t updated;
  /* Private state below; the scalars come first so the M0's short load/store offsets reach
   * them. */
  uint8_t rx_escape;
  uint8_t rx_bad;
  uint8_t receiving;
  uint8_t have_last;
  uint8_t last_resp_len;
  uint16_t rx_len;
  uint16_t total_len;
  uint16_t received_len;
  uint32_t last_key; /* op | txn << 8 | CRC-16 << 16 of the last request answered */
  uint32_t expect_crc32;
  uint32_t expect_seq;
  uint8_t rx[METRO_FW_PUSH_MAX_FRAME];
  uint8_t last_resp[METRO_FW_PUSH_MAX_PAYLOAD]; /* payload of the last response */
  uint8_t blob[METRO_FW_MAX_LEN];
} metro_fw_push;

/* Initialises p (IDLE, empty buffers). Returns METRO_FW_OK, or METRO_FW_E_ARG when p, flash,
 * flash->read, device_id or send is NULL (every request reads the slots). */
int metro_fw_push_init(metro_fw_push* p, const metro_fw_flash* flash, const uint32_t device_id[2],
                       metro_fw_send_fn send, void* send_ctx);

/* Feeds received bytes; every complete frame is executed and answered. Returns METRO_FW_OK,
 * METRO_FW_E_ARG, METRO_FW_E_FRAME if a frame was rejected (a NAK was sent), or
 * METRO_FW_E_FLASH if the send callback failed. Flash errors inside an operation are
 * reported to the PC in the response, not here. */
int metro_fw_push_rx(metro_fw_push* p, const uint8_t* data, uint32_t len);

/* Builds the frame op, txn, len u16, payload[payload_len], crc16 u16 (section 7) and writes it
 * SLIP-encoded, with END before and after, into out (capacity out_cap, at least
 * 2 * (payload_len + METRO_FW_PUSH_FRAME_OVERHEAD) + 2). *out_len receives the encoded length.
 * Returns METRO_FW_OK or METRO_FW_E_ARG (NULL, payload longer than METRO_FW_PUSH_MAX_PAYLOAD,
 * or out too small). Used by the tag and by the host tools. */
int metro_fw_frame_encode(uint8_t op, uint8_t txn, const uint8_t* payload, uint32_t payload_len,
                          uint8_t* out, uint32_t out_cap, uint32_t* out_len);

/* Checks an unencoded (SLIP-decoded) frame of len bytes: its length field and CRC-16. Returns
 * the payload length (0 ... METRO_FW_PUSH_MAX_PAYLOAD; op is frame[0], txn frame[1], the
 * payload starts at frame + 4), METRO_FW_E_ARG for NULL or METRO_FW_E_FRAME. */
int metro_fw_frame_parse(const uint8_t* frame, uint32_t len);

#ifdef __cplusplus
}
#endif

#endif /* METRO_FW_PUSH_H_ */
