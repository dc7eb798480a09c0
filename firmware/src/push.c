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
    uint8_t c = frame[i];
    if (c == METRO_FW_SLIP_END || c == METRO_FW_SLIP_ESC) {
      out[n++] = METRO_FW_SLIP_ESC;
      c = c == METRO_FW_SLIP_END ? METRO_FW_SLIP_ESC_END : METRO_FW_SLIP_ESC_ESC;
    }
    out[n++] = c;
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

/* Little-endian store of the low n bytes of v at w; returns the next free byte. */
static uint8_t* PutLe(uint8_t* w, uint32_t v, uint32_t n) {
  for (; n != 0u; --n) {
    *w++ = (uint8_t)v;
    v >>= 8;
  }
  return w;
}

/* Push result for a failed metro_fw_update, indexed by -code (codes -1 ... -13). */
static const uint8_t kResultOfError[14] = {
    0,
    METRO_FW_RES_INVALID_BLOB,       /* E_ARG */
    METRO_FW_RES_INVALID_BLOB,       /* E_EMPTY */
    METRO_FW_RES_INVALID_BLOB,       /* E_MAGIC */
    METRO_FW_RES_UNSUPPORTED_FORMAT, /* E_UNSUPPORTED */
    METRO_FW_RES_INVALID_BLOB,       /* E_BOUNDS */
    METRO_FW_RES_CRC_MISMATCH,       /* E_CRC */
    METRO_FW_RES_FOREIGN_DEVICE,     /* E_FOREIGN */
    METRO_FW_RES_INVALID_BLOB,       /* E_SEQ */
    METRO_FW_RES_INVALID_BLOB,       /* E_SECTION */
    METRO_FW_RES_FLASH_ERROR,        /* E_FLASH */
    METRO_FW_RES_FLASH_ERROR,        /* E_VERIFY */
    METRO_FW_RES_STALE_SEQ,          /* E_STALE_SEQ */
    METRO_FW_RES_INVALID_BLOB        /* E_FRAME */
};

/* Request payload length of ops 0x01 ... 0x07 (section 7): at least kRequestMin[op] bytes and
 * at most kRequestExtra[op] more (CAL_WRITE: offset u16 and 1 ... 16 data bytes). */
static const uint8_t kRequestMin[8] = {0, 0, 10, 3, 0, 0, 3, 0};
static const uint8_t kRequestExtra[8] = {0, 0, 0, METRO_FW_PUSH_MAX_CHUNK - 1u, 0, 0, 0, 0};

/* CAL_EXECUTE's checks and the update (section 7); returns the result. */
METRO_FW_NOINLINE static uint8_t Commit(metro_fw_push* p, int* slot) {
  int rc;
  if (!p->receiving || p->received_len != p->total_len) return METRO_FW_RES_BAD_STATE;
  p->receiving = 0;
  if (metro_fw_crc32(0, p->blob, p->total_len) != p->expect_crc32) {
    return METRO_FW_RES_CRC_MISMATCH;
  }
  /* the blob's seq is not CREATE's */
  if (metro_fw_get_u32(p->blob + 12) != p->expect_seq) return METRO_FW_RES_INVALID_PARAM;
  rc = metro_fw_update(p->flash, p->device_id, p->blob, p->total_len, slot);
  return rc == METRO_FW_OK     ? METRO_FW_RES_SUCCESS
         : (uint32_t)-rc < 14u ? kResultOfError[-rc]
                               : METRO_FW_RES_INVALID_BLOB;
}

/* Executes one request (payload in, n bytes; in is followed by the frame's CRC, so in[0] and
 * in[1] are readable). Appends the response fields after the result byte at *w and returns
 * the result; a request it refuses as malformed (INVALID_PARAM) appends nothing. */
METRO_FW_NOINLINE static uint8_t Execute(metro_fw_push* p, uint32_t op, const uint8_t* in,
                                         uint32_t n, uint8_t** w) {
  metro_fw_blob_info info[2];
  int result[2];
  int active = METRO_FW_SLOT_NONE;
  const uint32_t off = metro_fw_get_u16(in);
  const metro_fw_blob_info* act = 0;
  if (metro_fw_choose_active(p->flash, p->device_id, info, result, &active) == METRO_FW_OK &&
      active != METRO_FW_SLOT_NONE) {
    act = &info[active];
  }
  if (op - 1u > 6u) return METRO_FW_RES_UNKNOWN_OP;
  if (op == METRO_FW_OP_CAL_WRITE && !p->receiving) return METRO_FW_RES_BAD_STATE;
  if (n - kRequestMin[op] > kRequestExtra[op]) return METRO_FW_RES_INVALID_PARAM;
  if (op == METRO_FW_OP_GET_INFO) {
    /* fmt_major, fmt_minor, active_slot, max_len u16, device_id u32[2], seq, crc32 */
    *w = PutLe(*w,
               METRO_FW_FMT_MAJOR | METRO_FW_FMT_MINOR << 8 | (uint32_t)(uint8_t)active << 16 |
                   (METRO_FW_MAX_LEN & 0xFFu) << 24,
               4);
    *w = PutLe(*w, METRO_FW_MAX_LEN >> 8, 1);
    *w = PutLe(*w, p->device_id[0], 4);
    *w = PutLe(*w, p->device_id[1], 4);
    *w = PutLe(*w, act != 0 ? act->seq : 0u, 4);
    *w = PutLe(*w, act != 0 ? act->crc32 : 0u, 4);
  } else if (op == METRO_FW_OP_CAL_CREATE) {
    const uint32_t seq = metro_fw_get_u32(in + 6);
    uint32_t i;
    p->receiving = 0;
    if ((off & 3u) != 0u || off < METRO_FW_HEADER_LEN + 4u || off > METRO_FW_MAX_LEN) {
      return METRO_FW_RES_INVALID_PARAM;
    }
    if (seq < METRO_FW_SEQ_MIN || seq > METRO_FW_SEQ_MAX || (act != 0 && seq <= act->seq)) {
      return METRO_FW_RES_STALE_SEQ;
    }
    for (i = 0; i < METRO_FW_MAX_LEN; ++i) p->blob[i] = 0xFFu;
    p->total_len = (uint16_t)off;
    p->received_len = 0;
    p->expect_crc32 = metro_fw_get_u32(in + 2);
    p->expect_seq = seq;
    p->receiving = 1;
  } else if (op == METRO_FW_OP_CAL_WRITE) {
    const uint32_t len = n - 2u;
    uint8_t res = METRO_FW_RES_INVALID_OFFSET;
    uint32_t i;
    if (off + len > p->total_len) return METRO_FW_RES_INVALID_PARAM;
    if (off <= p->received_len) { /* contiguous; rewriting a received range is allowed */
      for (i = 0; i < len; ++i) p->blob[off + i] = in[2 + i];
      if (off + len > p->received_len) p->received_len = (uint16_t)(off + len);
      res = METRO_FW_RES_SUCCESS;
    }
    *w = PutLe(*w, p->received_len, 2);
    return res;
  } else if (op == METRO_FW_OP_CAL_GET_CRC) {
    if (!p->receiving) return METRO_FW_RES_BAD_STATE;
    *w = PutLe(*w, p->received_len, 2);
    *w = PutLe(*w, metro_fw_crc32(0, p->blob, p->received_len), 4);
  } else if (op == METRO_FW_OP_CAL_EXECUTE) {
    int slot = METRO_FW_SLOT_NONE;
    const uint8_t res = Commit(p, &slot);
    /* slot u8 (0xFF unless written: metro_fw_update sets it), seq u32 (0 unless done) */
    *w = PutLe(*w, (uint32_t)slot, 1);
    *w = PutLe(*w, res == METRO_FW_RES_SUCCESS ? p->expect_seq : 0u, 4);
    if (res == METRO_FW_RES_SUCCESS) p->updated = 1;
    return res;
  } else if (op == METRO_FW_OP_CAL_READ) {
    const uint32_t len = in[2];
    metro_fw_slot s;
    if (act == 0) return METRO_FW_RES_NO_CALIBRATION;
    if (len - 1u >= METRO_FW_PUSH_MAX_CHUNK || off + len > act->total_len) {
      return METRO_FW_RES_INVALID_PARAM;
    }
    s.flash = p->flash;
    s.base = p->flash->slot_addr[active];
    if (metro_fw_slot_read(&s, off, *w, len) != METRO_FW_OK) return METRO_FW_RES_FLASH_ERROR;
    *w += len;
  } else { /* ABORT */
    p->receiving = 0;
  }
  return METRO_FW_RES_SUCCESS;
}

METRO_FW_NOINLINE static int HandleFrame(metro_fw_push* p) {
  uint8_t op, txn;
  const uint8_t* payload;
  uint32_t n, rn, flen;
  uint16_t req_crc;
  uint8_t r[METRO_FW_PUSH_MAX_PAYLOAD];
  uint8_t* w;
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
  w = r + 1;
  r[0] = Execute(p, op, payload, n, &w);
  rn = (uint32_t)(w - r);
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
