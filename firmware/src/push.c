#include "metro_fw/push.h"

#include "le.h"
#include "metro_fw/crc.h"
#include "metro_fw/update.h"

/* Little-endian store of the low n bytes of v at w; returns the next free byte. */
static uint8_t* PutLe(uint8_t* w, uint32_t v, uint32_t n) {
  for (; n != 0u; --n) {
    *w++ = (uint8_t)v;
    v >>= 8;
  }
  return w;
}

int metro_fw_frame_encode(uint8_t op, uint8_t txn, const uint8_t* payload, uint32_t payload_len,
                          uint8_t* out, uint32_t out_cap, uint32_t* out_len) {
  uint8_t f[METRO_FW_PUSH_MAX_FRAME];
  uint32_t i, n = 0;
  if (out == 0 || out_len == 0 || (payload == 0 && payload_len != 0u) ||
      payload_len > METRO_FW_PUSH_MAX_PAYLOAD ||
      out_cap < 2u * (payload_len + METRO_FW_PUSH_FRAME_OVERHEAD) + 2u) {
    return METRO_FW_E_ARG;
  }
  f[0] = op;
  f[1] = txn;
  f[2] = (uint8_t)payload_len;
  f[3] = 0;
  for (i = 0; i < payload_len; ++i) f[4 + i] = payload[i];
  (void)PutLe(f + 4 + payload_len, metro_fw_crc16(METRO_FW_CRC16_INIT, f, 4u + payload_len), 2);
  out[n++] = METRO_FW_SLIP_END;
  for (i = 0; i < payload_len + METRO_FW_PUSH_FRAME_OVERHEAD; ++i) {
    uint8_t c = f[i];
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

int metro_fw_frame_parse(const uint8_t* frame, uint32_t len) {
  uint32_t n;
  if (frame == 0) return METRO_FW_E_ARG;
  if (len < METRO_FW_PUSH_FRAME_OVERHEAD || len > METRO_FW_PUSH_MAX_FRAME) return METRO_FW_E_FRAME;
  n = metro_fw_get_u16(frame + 2);
  if (n != len - METRO_FW_PUSH_FRAME_OVERHEAD ||
      metro_fw_crc16(METRO_FW_CRC16_INIT, frame, 4u + n) != metro_fw_get_u16(frame + 4 + n)) {
    return METRO_FW_E_FRAME;
  }
  return (int)n;
}

int metro_fw_push_init(metro_fw_push* p, const metro_fw_flash* flash, const uint32_t device_id[2],
                       metro_fw_send_fn send, void* send_ctx) {
  uint8_t* z;
  uint32_t i;
  if (p == 0 || flash == 0 || flash->read == 0 || device_id == 0 || send == 0) {
    return METRO_FW_E_ARG;
  }
  z = (uint8_t*)p;
  for (i = 0; i < sizeof(*p); ++i) z[i] = 0;
  p->flash = flash;
  p->device_id[0] = device_id[0];
  p->device_id[1] = device_id[1];
  p->send = send;
  p->send_ctx = send_ctx;
  return METRO_FW_OK;
}

/* Push result of metro_fw_update's code, indexed by 1 - code (codes 1 ... -14). LIVE_UNVERIFIED:
 * the new calibration is live (SUCCESS with slot and seq); the PC's read-back of every byte is
 * the verification the tag could not make. */
static const uint8_t kResultOfError[16] = {
    METRO_FW_RES_SUCCESS,            /* LIVE_UNVERIFIED */
    METRO_FW_RES_SUCCESS,            /* OK */
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
    METRO_FW_RES_INVALID_BLOB,       /* E_FRAME */
    METRO_FW_RES_INVALID_BLOB        /* E_SENSOR */
};

/* Request payload length of ops 0x01 ... 0x07 (section 7): at least the low nibble of
 * kRequestLen[op] bytes and at most the high nibble more (CAL_WRITE: offset u16 and 1 ... 16
 * data bytes). */
#define METRO_FW_REQ_LEN(min, extra) (uint8_t)((min) | (extra) << 4)
static const uint8_t kRequestLen[8] = {
    0,
    METRO_FW_REQ_LEN(0u, 0u),                           /* GET_INFO */
    METRO_FW_REQ_LEN(10u, 0u),                          /* CAL_CREATE */
    METRO_FW_REQ_LEN(3u, METRO_FW_PUSH_MAX_CHUNK - 1u), /* CAL_WRITE */
    METRO_FW_REQ_LEN(0u, 0u),                           /* CAL_GET_CRC */
    METRO_FW_REQ_LEN(0u, 0u),                           /* CAL_EXECUTE */
    METRO_FW_REQ_LEN(3u, 0u),                           /* CAL_READ */
    METRO_FW_REQ_LEN(0u, 0u)};                          /* ABORT */
#undef METRO_FW_REQ_LEN

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
  return (uint32_t)(1 - rc) < 16u ? kResultOfError[1 - rc] : METRO_FW_RES_INVALID_BLOB;
}

/* Executes one request (payload in, n bytes; in is followed by the frame's CRC, so in[0] and
 * in[1] are readable) and writes the response payload (result byte, then the op's fields) into
 * the response cache p->last_resp; returns its length. A request
 * it refuses as malformed (INVALID_PARAM) gets the result byte only. */
METRO_FW_NOINLINE static uint32_t Execute(metro_fw_push* p, uint32_t op, const uint8_t* in,
                                          uint32_t n) {
  uint8_t* const r = p->last_resp;
  uint8_t* w = r + 1;
  metro_fw_blob_info info[2];
  int result[2];
  int active;
  const uint32_t off = metro_fw_get_u16(in);
  const metro_fw_blob_info* act = info;
  uint32_t res = METRO_FW_RES_UNKNOWN_OP;
  /* Without an active slot, act points at info[0] with seq and crc32 0 (what GET_INFO reports
   * then). */
  active = metro_fw_choose_active(p->flash, p->device_id, info, result);
  if (active == METRO_FW_SLOT_NONE) {
    info[0].seq = 0;
    info[0].crc32 = 0;
  } else {
    act = &info[active];
  }
  if (op - 1u > 6u) goto done;
  res = METRO_FW_RES_BAD_STATE;
  if (op == METRO_FW_OP_CAL_WRITE && !p->receiving) goto done;
  res = METRO_FW_RES_INVALID_PARAM;
  if (n - (kRequestLen[op] & 15u) > (uint32_t)(kRequestLen[op] >> 4)) goto done;
  res = METRO_FW_RES_SUCCESS;
  if (op == METRO_FW_OP_GET_INFO) {
    /* fmt_major, fmt_minor, active_slot, max_len u16, device_id u32[2], seq, crc32 */
    w = PutLe(w, METRO_FW_FMT_MAJOR | METRO_FW_FMT_MINOR << 8 | (uint32_t)(uint8_t)active << 16, 3);
    w = PutLe(w, METRO_FW_MAX_LEN, 2);
    w = PutLe(w, p->device_id[0], 4);
    w = PutLe(w, p->device_id[1], 4);
    w = PutLe(w, act->seq, 4);
    w = PutLe(w, act->crc32, 4);
  } else if (op == METRO_FW_OP_CAL_CREATE) {
    const uint32_t seq = metro_fw_get_u32(in + 6);
    uint32_t i;
    p->receiving = 0;
    res = METRO_FW_RES_INVALID_PARAM;
    if ((off & 3u) != 0u || off < METRO_FW_HEADER_LEN + 4u || off > METRO_FW_MAX_LEN) goto done;
    res = METRO_FW_RES_STALE_SEQ;
    /* without an active slot act->seq is 0 < METRO_FW_SEQ_MIN */
    if (seq < METRO_FW_SEQ_MIN || seq > METRO_FW_SEQ_MAX || seq <= act->seq) goto done;
    for (i = 0; i < METRO_FW_MAX_LEN; ++i) p->blob[i] = 0xFFu;
    p->total_len = (uint16_t)off;
    p->received_len = 0;
    p->expect_crc32 = metro_fw_get_u32(in + 2);
    p->expect_seq = seq;
    p->receiving = 1;
    res = METRO_FW_RES_SUCCESS;
  } else if (op == METRO_FW_OP_CAL_WRITE) {
    const uint32_t len = n - 2u;
    uint32_t i;
    res = METRO_FW_RES_INVALID_PARAM;
    if (off + len > p->total_len) goto done;
    res = METRO_FW_RES_INVALID_OFFSET;
    if (off <= p->received_len) { /* contiguous; rewriting a received range is allowed */
      for (i = 0; i < len; ++i) p->blob[off + i] = in[2 + i];
      if (off + len > p->received_len) p->received_len = (uint16_t)(off + len);
      res = METRO_FW_RES_SUCCESS;
    }
    w = PutLe(w, p->received_len, 2);
  } else if (op == METRO_FW_OP_CAL_GET_CRC) {
    res = METRO_FW_RES_BAD_STATE;
    if (!p->receiving) goto done;
    w = PutLe(w, p->received_len, 2);
    w = PutLe(w, metro_fw_crc32(0, p->blob, p->received_len), 4);
    res = METRO_FW_RES_SUCCESS;
  } else if (op == METRO_FW_OP_CAL_EXECUTE) {
    int slot = METRO_FW_SLOT_NONE;
    res = Commit(p, &slot);
    /* slot u8 (0xFF unless written: metro_fw_update sets it), seq u32 (0 unless done) */
    w = PutLe(w, (uint32_t)slot, 1);
    w = PutLe(w, res == METRO_FW_RES_SUCCESS ? p->expect_seq : 0u, 4);
    if (res == METRO_FW_RES_SUCCESS) p->updated = 1;
  } else if (op == METRO_FW_OP_CAL_READ) {
    const uint32_t len = in[2];
    metro_fw_slot s;
    res = METRO_FW_RES_NO_CALIBRATION;
    if (active == METRO_FW_SLOT_NONE) goto done;
    res = METRO_FW_RES_INVALID_PARAM;
    if (len - 1u >= METRO_FW_PUSH_MAX_CHUNK || off + len > act->total_len) goto done;
    s.flash = p->flash;
    s.base = p->flash->slot_addr[active];
    res = METRO_FW_RES_FLASH_ERROR;
    if (metro_fw_slot_read(&s, off, w, len) != METRO_FW_OK) goto done;
    w += len;
    res = METRO_FW_RES_SUCCESS;
  } else { /* ABORT */
    p->receiving = 0;
  }
done:
  r[0] = (uint8_t)res;
  return (uint32_t)(w - r);
}

/* Handles the frame in p->rx: a NAK for a bad one (section 7: op 0xFF, txn 0, payload
 * FRAME_ERROR), else the response (from the cache for a retry), SLIP-encoded and sent. Returns
 * METRO_FW_OK, METRO_FW_E_FRAME (NAK sent) or METRO_FW_E_FLASH (the send callback failed). */
static int HandleFrame(metro_fw_push* p) {
  static const uint8_t kFrameError = METRO_FW_RES_FRAME_ERROR;
  const uint8_t* payload = &kFrameError;
  uint8_t op = METRO_FW_OP_NAK, txn = 0;
  uint32_t n = 1;
  int status = METRO_FW_E_FRAME;
  /* a frame marked bad is parsed as an empty one, which fails */
  const int len = metro_fw_frame_parse(p->rx, p->rx_bad ? 0u : p->rx_len);
  uint8_t enc[2u * METRO_FW_PUSH_MAX_FRAME + 2u];
  if (len >= 0) {
    /* A retry repeats op, txn and the request's CRC-16: answered from the cache, not redone. */
    const uint32_t key =
        metro_fw_get_u16(p->rx) | (uint32_t)metro_fw_get_u16(p->rx + p->rx_len - 2u) << 16;
    if (!p->have_last || key != p->last_key) {
      p->last_resp_len = (uint8_t)Execute(p, p->rx[0], p->rx + 4, (uint32_t)len);
      p->have_last = 1;
      p->last_key = key;
    }
    op = (uint8_t)(p->rx[0] | METRO_FW_PUSH_RESPONSE_BIT);
    txn = p->rx[1];
    payload = p->last_resp;
    n = p->last_resp_len;
    status = METRO_FW_OK;
  }
  /* enc holds any frame of at most METRO_FW_PUSH_MAX_PAYLOAD bytes: the encoding succeeds */
  (void)metro_fw_frame_encode(op, txn, payload, n, enc, sizeof(enc), &n);
  return p->send(p->send_ctx, enc, n) != 0 ? METRO_FW_E_FLASH : status;
}

int metro_fw_push_rx(metro_fw_push* p, const uint8_t* data, uint32_t len) {
  int status = METRO_FW_OK;
  if (p == 0 || (data == 0 && len != 0u)) return METRO_FW_E_ARG;
  for (; len != 0u; --len) {
    uint32_t c = *data++;
    if (c == METRO_FW_SLIP_END) {
      if (p->rx_len != 0u || p->rx_bad) {
        int rc = HandleFrame(p);
        if (status == METRO_FW_OK) status = rc; /* the first failure */
      }
      p->rx_len = 0;
      p->rx_escape = 0;
      p->rx_bad = 0;
      continue;
    }
    if (p->rx_escape) {
      p->rx_escape = 0;
      if (c - METRO_FW_SLIP_ESC_END > 1u) { /* neither ESC_END nor ESC_ESC */
        p->rx_bad = 1;
        continue;
      }
      c = c == METRO_FW_SLIP_ESC_END ? METRO_FW_SLIP_END : METRO_FW_SLIP_ESC;
    } else if (c == METRO_FW_SLIP_ESC) {
      p->rx_escape = 1;
      continue;
    }
    if (p->rx_len < sizeof(p->rx)) {
      p->rx[p->rx_len++] = (uint8_t)c;
    } else {
      p->rx_bad = 1;
    }
  }
  return status;
}
