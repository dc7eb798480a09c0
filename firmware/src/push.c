#include "metro_fw/push.h"

#include "le.h"
#include "metro_fw/crc.h"
#include "metro_fw/update.h"

int metro_fw_slip_encode(const uint8_t* frame, uint32_t len, uint8_t* out, uint32_t out_cap,
                         uint32_t* out_len) {
  uint32_t i, n = 0;
  if (frame == 0 || out == 0 || out_len == 0 || out_cap < 2u * len + 2u) return METRO_FW_E_ARG;
  out[n++] = METRO_FW_SLIP_END;
  for (i = 0; i < len; ++i) {
    if (frame[i] == METRO_FW_SLIP_END) {
      out[n++] = METRO_FW_SLIP_ESC;
      out[n++] = METRO_FW_SLIP_ESC_END;
    } else if (frame[i] == METRO_FW_SLIP_ESC) {
      out[n++] = METRO_FW_SLIP_ESC;
      out[n++] = METRO_FW_SLIP_ESC_ESC;
    } else {
      out[n++] = frame[i];
    }
  }
  out[n++] = METRO_FW_SLIP_END;
  *out_len = n;
  return METRO_FW_OK;
}

int metro_fw_frame_build(uint8_t op, uint8_t txn, const uint8_t* payload, uint32_t payload_len,
                         uint8_t* out, uint32_t out_cap, uint32_t* out_len) {
  uint32_t i;
  uint16_t crc;
  if (out == 0 || out_len == 0 || (payload == 0 && payload_len != 0u) ||
      payload_len > METRO_FW_PUSH_MAX_PAYLOAD ||
      out_cap < payload_len + METRO_FW_PUSH_FRAME_OVERHEAD) {
    return METRO_FW_E_ARG;
  }
  out[0] = op;
  out[1] = txn;
  metro_fw_put_u16(out + 2, (uint16_t)payload_len);
  for (i = 0; i < payload_len; ++i) out[4 + i] = payload[i];
  crc = metro_fw_crc16(METRO_FW_CRC16_INIT, out, 4u + payload_len);
  metro_fw_put_u16(out + 4 + payload_len, crc);
  *out_len = payload_len + METRO_FW_PUSH_FRAME_OVERHEAD;
  return METRO_FW_OK;
}

int metro_fw_frame_parse(const uint8_t* frame, uint32_t len, uint8_t* op, uint8_t* txn,
                         const uint8_t** payload, uint32_t* payload_len) {
  uint32_t n;
  if (frame == 0 || op == 0 || txn == 0 || payload == 0 || payload_len == 0) {
    return METRO_FW_E_ARG;
  }
  if (len < METRO_FW_PUSH_FRAME_OVERHEAD || len > METRO_FW_PUSH_MAX_FRAME) return METRO_FW_E_FRAME;
  n = metro_fw_get_u16(frame + 2);
  if (n != len - METRO_FW_PUSH_FRAME_OVERHEAD) return METRO_FW_E_FRAME;
  if (metro_fw_crc16(METRO_FW_CRC16_INIT, frame, 4u + n) != metro_fw_get_u16(frame + 4 + n)) {
    return METRO_FW_E_FRAME;
  }
  *op = frame[0];
  *txn = frame[1];
  *payload = frame + 4;
  *payload_len = n;
  return METRO_FW_OK;
}

int metro_fw_push_init(metro_fw_push* p, const metro_fw_flash* flash, const uint32_t device_id[2],
                       metro_fw_send_fn send, void* send_ctx) {
  uint8_t* z;
  uint32_t i;
  if (p == 0 || flash == 0 || device_id == 0 || send == 0) return METRO_FW_E_ARG;
  z = (uint8_t*)p;
  for (i = 0; i < sizeof(*p); ++i) z[i] = 0;
  p->flash = flash;
  p->device_id[0] = device_id[0];
  p->device_id[1] = device_id[1];
  p->send = send;
  p->send_ctx = send_ctx;
  return METRO_FW_OK;
}

static int SendFrame(metro_fw_push* p, const uint8_t* frame, uint32_t len) {
  uint8_t enc[2u * METRO_FW_PUSH_MAX_FRAME + 2u];
  uint32_t n;
  int rc = metro_fw_slip_encode(frame, len, enc, sizeof(enc), &n);
  if (rc != METRO_FW_OK) return rc;
  return p->send(p->send_ctx, enc, n) == 0 ? METRO_FW_OK : METRO_FW_E_FLASH;
}

static uint8_t ResultFromError(int rc) {
  switch (rc) {
    case METRO_FW_E_FOREIGN:
      return METRO_FW_RES_FOREIGN_DEVICE;
    case METRO_FW_E_UNSUPPORTED:
      return METRO_FW_RES_UNSUPPORTED_FORMAT;
    case METRO_FW_E_STALE_SEQ:
      return METRO_FW_RES_STALE_SEQ;
    case METRO_FW_E_FLASH:
    case METRO_FW_E_VERIFY:
      return METRO_FW_RES_FLASH_ERROR;
    case METRO_FW_E_CRC:
      return METRO_FW_RES_CRC_MISMATCH;
    default:
      return METRO_FW_RES_INVALID_BLOB;
  }
}

/* Executes one request; writes the response payload into r (capacity 32) and its length. */
static void Execute(metro_fw_push* p, uint8_t op, const uint8_t* in, uint32_t n, uint8_t* r,
                    uint32_t* rn) {
  metro_fw_blob_info info[2];
  int result[2];
  int active = METRO_FW_SLOT_NONE;
  int have_active =
      metro_fw_choose_active(p->flash, p->device_id, info, result, &active) == METRO_FW_OK &&
      active != METRO_FW_SLOT_NONE;
  r[0] = METRO_FW_RES_SUCCESS;
  *rn = 1;
  switch (op) {
    case METRO_FW_OP_GET_INFO:
      if (n != 0u) break;
      r[1] = (uint8_t)METRO_FW_FMT_MAJOR;
      r[2] = (uint8_t)METRO_FW_FMT_MINOR;
      r[3] = have_active ? (uint8_t)active : 0xFFu;
      metro_fw_put_u16(r + 4, (uint16_t)METRO_FW_MAX_LEN);
      metro_fw_put_u32(r + 6, p->device_id[0]);
      metro_fw_put_u32(r + 10, p->device_id[1]);
      metro_fw_put_u32(r + 14, have_active ? info[active].seq : 0u);
      metro_fw_put_u32(r + 18, have_active ? info[active].crc32 : 0u);
      *rn = 22;
      return;
    case METRO_FW_OP_CAL_CREATE: {
      uint16_t total;
      uint32_t seq, i;
      if (n != 10u) break;
      total = metro_fw_get_u16(in);
      seq = metro_fw_get_u32(in + 6);
      p->receiving = 0;
      if ((total & 3u) != 0u || total < METRO_FW_HEADER_LEN + 4u || total > METRO_FW_MAX_LEN) {
        break;
      }
      if (seq < METRO_FW_SEQ_MIN || seq > METRO_FW_SEQ_MAX ||
          (have_active && seq <= info[active].seq)) {
        r[0] = METRO_FW_RES_STALE_SEQ;
        return;
      }
      for (i = 0; i < METRO_FW_MAX_LEN; ++i) p->blob[i] = 0xFFu;
      p->total_len = total;
      p->received_len = 0;
      p->expect_crc32 = metro_fw_get_u32(in + 2);
      p->expect_seq = seq;
      p->receiving = 1;
      return;
    }
    case METRO_FW_OP_CAL_WRITE: {
      uint32_t off, len, i;
      if (!p->receiving) {
        r[0] = METRO_FW_RES_BAD_STATE;
        return;
      }
      if (n < 3u || n > 2u + METRO_FW_PUSH_MAX_CHUNK) break;
      off = metro_fw_get_u16(in);
      len = n - 2u;
      if (off + len > p->total_len) break;
      metro_fw_put_u16(r + 1, p->received_len);
      *rn = 3;
      if (off > p->received_len) {
        r[0] = METRO_FW_RES_INVALID_OFFSET;
        return;
      }
      for (i = 0; i < len; ++i) p->blob[off + i] = in[2 + i];
      if (off + len > p->received_len) p->received_len = (uint16_t)(off + len);
      metro_fw_put_u16(r + 1, p->received_len);
      return;
    }
    case METRO_FW_OP_CAL_GET_CRC:
      if (n != 0u) break;
      if (!p->receiving) {
        r[0] = METRO_FW_RES_BAD_STATE;
        return;
      }
      metro_fw_put_u16(r + 1, p->received_len);
      metro_fw_put_u32(r + 3, metro_fw_crc32(0, p->blob, p->received_len));
      *rn = 7;
      return;
    case METRO_FW_OP_CAL_EXECUTE: {
      int slot = METRO_FW_SLOT_NONE;
      int rc;
      if (n != 0u) break;
      r[1] = 0xFFu;
      metro_fw_put_u32(r + 2, 0u);
      *rn = 6;
      if (!p->receiving || p->received_len != p->total_len) {
        r[0] = METRO_FW_RES_BAD_STATE;
        return;
      }
      p->receiving = 0;
      if (metro_fw_crc32(0, p->blob, p->total_len) != p->expect_crc32) {
        r[0] = METRO_FW_RES_CRC_MISMATCH;
        return;
      }
      if (metro_fw_get_u32(p->blob + 12) != p->expect_seq) {
        r[0] = METRO_FW_RES_INVALID_PARAM;
        return;
      }
      rc = metro_fw_update(p->flash, p->device_id, p->blob, p->total_len, &slot);
      if (rc != METRO_FW_OK) {
        r[0] = ResultFromError(rc);
        return;
      }
      p->updated = 1;
      r[1] = (uint8_t)slot;
      metro_fw_put_u32(r + 2, p->expect_seq);
      return;
    }
    case METRO_FW_OP_CAL_READ: {
      uint32_t off, len;
      metro_fw_slot s;
      if (n != 3u) break;
      off = metro_fw_get_u16(in);
      len = in[2];
      if (!have_active) {
        r[0] = METRO_FW_RES_NO_CALIBRATION;
        return;
      }
      if (len == 0u || len > METRO_FW_PUSH_MAX_CHUNK || off + len > info[active].total_len) break;
      s.flash = p->flash;
      s.base = p->flash->slot_addr[active];
      if (metro_fw_slot_read(&s, off, r + 1, len) != METRO_FW_OK) {
        r[0] = METRO_FW_RES_FLASH_ERROR;
        return;
      }
      *rn = 1u + len;
      return;
    }
    case METRO_FW_OP_ABORT:
      if (n != 0u) break;
      p->receiving = 0;
      return;
    default:
      r[0] = METRO_FW_RES_UNKNOWN_OP;
      return;
  }
  r[0] = METRO_FW_RES_INVALID_PARAM; /* every `break` above: malformed request */
  *rn = 1;
}

static int HandleFrame(metro_fw_push* p) {
  uint8_t op, txn;
  const uint8_t* payload;
  uint32_t n, rn, flen;
  uint16_t req_crc;
  uint8_t r[METRO_FW_PUSH_MAX_PAYLOAD];
  int rc;
  if (p->rx_bad || metro_fw_frame_parse(p->rx, p->rx_len, &op, &txn, &payload, &n) != METRO_FW_OK) {
    uint8_t nak[METRO_FW_PUSH_FRAME_OVERHEAD + 1u];
    r[0] = METRO_FW_RES_FRAME_ERROR;
    (void)metro_fw_frame_build(METRO_FW_OP_NAK, 0, r, 1, nak, sizeof(nak), &flen);
    rc = SendFrame(p, nak, flen);
    return rc != METRO_FW_OK ? rc : METRO_FW_E_FRAME;
  }
  req_crc = metro_fw_get_u16(p->rx + p->rx_len - 2u);
  if (p->have_last && op == p->last_op && txn == p->last_txn && req_crc == p->last_req_crc) {
    return SendFrame(p, p->last_resp, p->last_resp_len); /* a retry: answer, do not redo */
  }
  Execute(p, op, payload, n, r, &rn);
  rc = metro_fw_frame_build((uint8_t)(op | METRO_FW_PUSH_RESPONSE_BIT), txn, r, rn, p->last_resp,
                            sizeof(p->last_resp), &flen);
  if (rc != METRO_FW_OK) return rc;
  p->have_last = 1;
  p->last_op = op;
  p->last_txn = txn;
  p->last_req_crc = req_crc;
  p->last_resp_len = (uint8_t)flen;
  return SendFrame(p, p->last_resp, flen);
}

int metro_fw_push_rx(metro_fw_push* p, const uint8_t* data, uint32_t len) {
  uint32_t i;
  int status = METRO_FW_OK;
  if (p == 0 || (data == 0 && len != 0u)) return METRO_FW_E_ARG;
  for (i = 0; i < len; ++i) {
    uint8_t c = data[i];
    if (c == METRO_FW_SLIP_END) {
      if (p->rx_len != 0u || p->rx_bad) {
        int rc = HandleFrame(p);
        if (rc != METRO_FW_OK && status == METRO_FW_OK) status = rc;
      }
      p->rx_len = 0;
      p->rx_escape = 0;
      p->rx_bad = 0;
      continue;
    }
    if (p->rx_escape) {
      p->rx_escape = 0;
      if (c == METRO_FW_SLIP_ESC_END) {
        c = METRO_FW_SLIP_END;
      } else if (c == METRO_FW_SLIP_ESC_ESC) {
        c = METRO_FW_SLIP_ESC;
      } else {
        p->rx_bad = 1;
        continue;
      }
    } else if (c == METRO_FW_SLIP_ESC) {
      p->rx_escape = 1;
      continue;
    }
    if (p->rx_len < sizeof(p->rx)) {
      p->rx[p->rx_len++] = c;
    } else {
      p->rx_bad = 1;
    }
  }
  return status;
}
