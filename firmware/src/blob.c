#include "metro_fw/blob.h"

#include <stddef.h>

#include "le.h"
#include "metro_fw/crc.h"

/* Bytes read per call while computing the CRC: small enough for the boot stack. */
#define METRO_FW_CHUNK 32u

/* Physical limits of section 3.1. */
#define METRO_FW_TEMP_MIN_C (-40.0f)
#define METRO_FW_TEMP_MAX_C 85.0f
#define METRO_FW_DEFAULT_T_REF_C 25.0f
/* 0.25 g in accel counts at fs_sel 0 (16384 LSB/g); 60 deg/s in gyro counts at fs_sel 0
 * (32768 / 250 = 131.072 LSB per deg/s). Both halve with each fs_sel step. */
#define METRO_FW_ACCEL_BIAS_LIMIT_LSB 4096
#define METRO_FW_GYRO_BIAS_LIMIT_LSB 7864
/* 9.80665 / 16384 m/s^2 per LSB and 250 / 32768 * pi / 180 rad/s per LSB at fs_sel 0. */
#define METRO_FW_ACCEL_SENS_FS0 5.98550415e-4f
#define METRO_FW_GYRO_SENS_FS0 1.33158055e-4f

int metro_fw_buffer_read(void* ctx, uint32_t offset, uint8_t* dst, uint32_t len) {
  const metro_fw_buffer* b = (const metro_fw_buffer*)ctx;
  uint32_t i;
  if (b == 0 || dst == 0) return METRO_FW_E_ARG;
  if (offset > b->len || len > b->len - offset) return METRO_FW_E_BOUNDS;
  for (i = 0; i < len; ++i) dst[i] = b->data[offset + i];
  return METRO_FW_OK;
}

/* The body offset, length and version of META, ACCEL and GYRO follow each other in
 * metro_fw_blob_info (three uint16_t each): the walker indexes them. Fails to compile if the
 * layout changes. */
typedef char metro_fw_info_layout_check[(offsetof(metro_fw_blob_info, gyro_version) -
                                             offsetof(metro_fw_blob_info, meta_off) ==
                                         16)
                                            ? 1
                                            : -1];

/* Section walk (section 2.2). Fills the section fields of info. */
static int WalkSections(metro_fw_read_fn read, void* ctx, metro_fw_blob_info* info) {
  const uint32_t end = (uint32_t)info->total_len - 4u;
  uint32_t off = info->header_len;
  uint8_t h[METRO_FW_SECTION_HEADER_LEN];
  while (off < end) {
    uint32_t type, version, body_len, known;
    int rc;
    if (end - off < METRO_FW_SECTION_HEADER_LEN) return METRO_FW_E_SECTION;
    rc = read(ctx, off, h, METRO_FW_SECTION_HEADER_LEN);
    if (rc != METRO_FW_OK) return rc;
    type = metro_fw_get_u16(h);
    version = metro_fw_get_u16(h + 2);
    body_len = metro_fw_get_u16(h + 4);
    off += METRO_FW_SECTION_HEADER_LEN;
    if (type == 0x0000u || type == 0xFFFFu) return METRO_FW_E_SECTION;
    if ((body_len & 3u) != 0u || body_len > end - off) return METRO_FW_E_SECTION;
    /* 0 META, 1 ACCEL, 2 GYRO, anything else unknown (skipped) */
    known = type == METRO_FW_SEC_META ? 0u : type - (METRO_FW_SEC_ACCEL - 1u);
    if (known < 3u) {
      uint16_t* f = (uint16_t*)(void*)((char*)info + offsetof(metro_fw_blob_info, meta_off)) +
                    3u * known;                  /* off, len, version */
      if (f[0] != 0u) return METRO_FW_E_SECTION; /* duplicate */
      /* A major this firmware knows must carry at least the v1.0 body. */
      if ((version >> 8) == (METRO_FW_SEC_VERSION_1_0 >> 8) &&
          body_len < (known == 0u ? METRO_FW_META_BODY_LEN : METRO_FW_SENSOR_BODY_LEN)) {
        return METRO_FW_E_SECTION;
      }
      f[0] = (uint16_t)off;
      f[1] = (uint16_t)body_len;
      f[2] = (uint16_t)version;
    }
    off += body_len;
  }
  return METRO_FW_OK; /* off == end: sections tile the blob exactly */
}

int metro_fw_blob_validate(metro_fw_read_fn read, void* ctx, uint32_t avail_len,
                           const uint32_t device_id[2], metro_fw_blob_info* info) {
  metro_fw_blob_info local;
  metro_fw_blob_info* in = info != 0 ? info : &local;
  uint8_t buf[METRO_FW_CHUNK];
  uint32_t magic, crc, off, crc_off;
  int rc;
  if (read == 0 || device_id == 0) return METRO_FW_E_ARG;
  {
    uint8_t* z = (uint8_t*)in;
    uint32_t i;
    for (i = 0; i < sizeof(*in); ++i) z[i] = 0;
  }
  if (avail_len < 4u) return METRO_FW_E_BOUNDS;
  rc = read(ctx, 0, buf, 4);
  if (rc != METRO_FW_OK) return rc;
  magic = metro_fw_get_u32(buf);
  if (magic == METRO_FW_ERASED_WORD) return METRO_FW_E_EMPTY;
  if (magic != METRO_FW_MAGIC) return METRO_FW_E_MAGIC;
  if (avail_len < METRO_FW_HEADER_LEN) return METRO_FW_E_BOUNDS;
  rc = read(ctx, 0, buf, METRO_FW_HEADER_LEN);
  if (rc != METRO_FW_OK) return rc;
  in->fmt_major = metro_fw_get_u16(buf + 4);
  in->fmt_minor = metro_fw_get_u16(buf + 6);
  in->total_len = metro_fw_get_u16(buf + 8);
  in->header_len = metro_fw_get_u16(buf + 10);
  in->seq = metro_fw_get_u32(buf + 12);
  in->device_id[0] = metro_fw_get_u32(buf + 16);
  in->device_id[1] = metro_fw_get_u32(buf + 20);
  in->flags = metro_fw_get_u32(buf + 24);
  if (in->fmt_major != METRO_FW_FMT_MAJOR) return METRO_FW_E_UNSUPPORTED;
  if ((in->header_len & 3u) != 0u || in->header_len < METRO_FW_HEADER_LEN) {
    return METRO_FW_E_BOUNDS;
  }
  if ((in->total_len & 3u) != 0u || in->total_len > METRO_FW_MAX_LEN || in->total_len > avail_len ||
      (uint32_t)in->header_len + 4u > in->total_len) {
    return METRO_FW_E_BOUNDS;
  }
  crc_off = (uint32_t)in->total_len - 4u;
  crc = 0;
  for (off = 0; off < crc_off; off += METRO_FW_CHUNK) {
    uint32_t n = crc_off - off < METRO_FW_CHUNK ? crc_off - off : METRO_FW_CHUNK;
    rc = read(ctx, off, buf, n);
    if (rc != METRO_FW_OK) return rc;
    crc = metro_fw_crc32(crc, buf, n);
  }
  rc = read(ctx, crc_off, buf, 4);
  if (rc != METRO_FW_OK) return rc;
  in->crc32 = metro_fw_get_u32(buf);
  if (crc != in->crc32) return METRO_FW_E_CRC;
  if (in->device_id[0] != device_id[0] || in->device_id[1] != device_id[1]) {
    return METRO_FW_E_FOREIGN;
  }
  if (in->seq < METRO_FW_SEQ_MIN || in->seq > METRO_FW_SEQ_MAX) return METRO_FW_E_SEQ;
  return WalkSections(read, ctx, in);
}

int metro_fw_slot_read(void* ctx, uint32_t offset, uint8_t* dst, uint32_t len) {
  const metro_fw_slot* s = (const metro_fw_slot*)ctx;
  if (s == 0 || s->flash == 0 || s->flash->read == 0 || dst == 0) return METRO_FW_E_ARG;
  if (offset > METRO_FW_PAGE_SIZE || len > METRO_FW_PAGE_SIZE - offset) return METRO_FW_E_BOUNDS;
  return s->flash->read(s->flash->ctx, s->base + offset, dst, len) == 0 ? METRO_FW_OK
                                                                        : METRO_FW_E_FLASH;
}

int metro_fw_choose_active(const metro_fw_flash* flash, const uint32_t device_id[2],
                           metro_fw_blob_info info[2], int result[2], int* active) {
  int i;
  if (flash == 0 || flash->read == 0 || device_id == 0 || info == 0 || result == 0 || active == 0) {
    return METRO_FW_E_ARG;
  }
  for (i = 0; i < 2; ++i) {
    metro_fw_slot s;
    s.flash = flash;
    s.base = flash->slot_addr[i];
    result[i] =
        metro_fw_blob_validate(metro_fw_slot_read, &s, METRO_FW_PAGE_SIZE, device_id, &info[i]);
  }
  if (result[0] == METRO_FW_OK && result[1] == METRO_FW_OK) {
    *active = info[1].seq > info[0].seq ? 1 : 0;
  } else if (result[0] == METRO_FW_OK) {
    *active = 0;
  } else if (result[1] == METRO_FW_OK) {
    *active = 1;
  } else {
    *active = METRO_FW_SLOT_NONE;
  }
  return METRO_FW_OK;
}

/* Float <-> bit pattern (C99 6.5.2.3 footnote 82): loads and stores only, no soft-float. */
static uint32_t F32Bits(float x) {
  union {
    float f;
    uint32_t u;
  } v;
  v.f = x;
  return v.u;
}

static float BitsF32(uint32_t u) {
  union {
    uint32_t u;
    float f;
  } v;
  v.u = u;
  return v.f;
}

float metro_fw_nominal_sensitivity(metro_fw_sensor_kind kind, uint8_t fs_sel) {
  /* s_nom(fs0) * 2^fs_sel: exact, by adding fs_sel to the (normal) exponent. */
  const float s0 = kind == METRO_FW_ACCEL ? METRO_FW_ACCEL_SENS_FS0 : METRO_FW_GYRO_SENS_FS0;
  return BitsF32(F32Bits(s0) + ((uint32_t)(fs_sel & 3u) << 23));
}

int metro_fw_sensor_defaults(metro_fw_sensor_kind kind, uint8_t fs_sel, metro_fw_sensor_cal* out) {
  uint8_t* z;
  uint32_t i;
  float s;
  if (out == 0 || fs_sel > 3u || (kind != METRO_FW_ACCEL && kind != METRO_FW_GYRO)) {
    return METRO_FW_E_ARG;
  }
  z = (uint8_t*)out;
  for (i = 0; i < sizeof(*out); ++i) z[i] = 0;
  s = metro_fw_nominal_sensitivity(kind, fs_sel);
  out->m[0] = s;
  out->m[4] = s;
  out->m[8] = s;
  out->t_ref_c = METRO_FW_DEFAULT_T_REF_C;
  out->t_valid_min_c = METRO_FW_TEMP_MIN_C;
  out->t_valid_max_c = METRO_FW_TEMP_MAX_C;
  out->status = METRO_FW_SENSOR_ABSENT;
  return METRO_FW_OK;
}

/* Section 3.1 limit checks without soft-float. Each float operation of the reference
 * evaluation (binary32, FLT_EVAL_METHOD 0) is done on the bit patterns, rounded to nearest,
 * ties to even (IEEE 754-2019 4.3.1), so the decisions are those of the float evaluation bit
 * for bit. Operands are finite (NONFINITE is checked first); an overflow rounds to Inf, which
 * absorbs. Inf - Inf, 0 * Inf (the NaN cases) cannot decide anything here: overflow only
 * happens in sums of non-negative terms, in products with a positive finite factor (D > 0
 * because t_valid_min_c < t_valid_max_c) and in det(M) from a row that then fails its norm. */
#define F32_SIGN 0x80000000u
#define F32_INF 0x7F800000u

/* sign | (sig * 2^exp rounded to binary32), sig != 0. */
static uint32_t F32Round(uint32_t sign, int32_t exp, uint64_t sig) {
  uint32_t s, m, rem, half;
  int32_t e;
  int32_t shift = 8;
  while ((sig >> 32) != 0u) { /* to 32 bits; the lowest bit keeps a sticky OR */
    sig = (sig >> 1) | (sig & 1u);
    ++exp;
  }
  s = (uint32_t)sig;
  while ((s & F32_SIGN) == 0u) {
    s <<= 1;
    --exp;
  }
  e = exp + 158; /* biased exponent of s * 2^exp, s in [2^31, 2^32) */
  if (e < 1) {   /* subnormal: fewer fraction bits */
    shift += 1 - e;
    e = 1;
  }
  if (shift > 32) return sign; /* below half the smallest subnormal */
  if (shift == 32) {
    m = 0;
    rem = s;
    half = F32_SIGN;
  } else {
    m = s >> shift;
    rem = s & ((1u << shift) - 1u);
    half = 1u << (shift - 1);
  }
  if (rem > half || (rem == half && (m & 1u) != 0u)) ++m;
  /* m carries the implicit bit, so a rounding carry moves up into the exponent. */
  m += (uint32_t)(e - 1) << 23;
  return sign | (m >= F32_INF ? F32_INF : m);
}

/* |x| = sig * 2^exp for a finite binary32 x (bits u). */
static uint32_t F32Unpack(uint32_t u, int32_t* exp) {
  uint32_t e = (u >> 23) & 0xFFu;
  uint32_t m = u & 0x7FFFFFu;
  if (e == 0u) {
    e = 1u;
  } else {
    m |= 0x800000u;
  }
  *exp = (int32_t)e - 150;
  return m;
}

static uint32_t F32Mul(uint32_t a, uint32_t b) {
  const uint32_t sign = (a ^ b) & F32_SIGN;
  int32_t ea, eb;
  uint32_t ma, mb;
  if ((a & F32_INF) == F32_INF || (b & F32_INF) == F32_INF) return sign | F32_INF;
  ma = F32Unpack(a, &ea);
  mb = F32Unpack(b, &eb);
  if (ma == 0u || mb == 0u) return sign;
  return F32Round(sign, ea + eb, (uint64_t)ma * mb);
}

static uint32_t F32Add(uint32_t a, uint32_t b) {
  int32_t ea, eb, d;
  uint32_t ma, mb, t, r;
  if ((a & F32_INF) == F32_INF) return a;
  if ((b & F32_INF) == F32_INF) return b;
  ma = F32Unpack(a, &ea);
  mb = F32Unpack(b, &eb);
  if (ma == 0u) return mb == 0u ? (a & b) : b; /* -0 only for (-0) + (-0) */
  if (mb == 0u) return a;
  if (ea < eb) { /* a has the larger exponent */
    t = a, a = b, b = t;
    t = ma, ma = mb, mb = t;
    d = ea, ea = eb, eb = d;
  }
  d = ea - eb;
  ma <<= 6; /* 6 guard bits; the smaller operand is shifted with a sticky bit */
  mb <<= 6;
  if (d > 31) {
    mb = 1u;
  } else if (d > 0) {
    mb = (mb >> d) | ((mb & ((1u << d) - 1u)) != 0u ? 1u : 0u);
  }
  if (((a ^ b) & F32_SIGN) == 0u) return F32Round(a & F32_SIGN, ea - 6, (uint64_t)ma + mb);
  if (ma == mb) return 0u; /* x - x = +0 when rounding to nearest */
  if (ma > mb) {
    r = ma - mb;
  } else {
    r = mb - ma;
    a = b;
  }
  return F32Round(a & F32_SIGN, ea - 6, r);
}

/* Orders binary32 bit patterns (finite) as the values: -0 and +0 are equal. */
static int32_t F32Key(uint32_t u) {
  return (u & F32_SIGN) != 0u ? -(int32_t)(u & ~F32_SIGN) : (int32_t)u;
}

/* Section 3.1 physical limits on decoded constants (model bits already applied). */
METRO_FW_NOINLINE static int WithinLimits(const metro_fw_sensor_cal* c, metro_fw_sensor_kind kind,
                                          uint8_t fs_sel) {
  const uint32_t s = F32Bits(metro_fw_nominal_sensitivity(kind, fs_sel));
  /* Row norm within +-10 % of s_nom: (1 - 0.1)^2 = 0.81, (1 + 0.1)^2 = 1.21. */
  const uint32_t n2_lo = F32Mul(F32Mul(F32Bits(0.81f), s), s);
  const uint32_t n2_hi = F32Mul(F32Mul(F32Bits(1.21f), s), s);
  const int32_t limit_fs0 =
      kind == METRO_FW_ACCEL ? METRO_FW_ACCEL_BIAS_LIMIT_LSB : METRO_FW_GYRO_BIAS_LIMIT_LSB;
  const uint32_t bias_limit = F32Round(0u, 0, (uint32_t)(limit_fs0 >> fs_sel)); /* exact */
  const int32_t t_lo = F32Key(F32Bits(METRO_FW_TEMP_MIN_C));
  const int32_t t_hi = F32Key(F32Bits(METRO_FW_TEMP_MAX_C));
  const uint32_t t_ref = F32Bits(c->t_ref_c);
  const int32_t k_ref = F32Key(t_ref);
  const int32_t k_min = F32Key(F32Bits(c->t_valid_min_c));
  const int32_t k_max = F32Key(F32Bits(c->t_valid_max_c));
  uint32_t det = 0u;
  uint32_t d_max, d_hi;
  int i, j;
  if (k_ref < t_lo || k_ref > t_hi || k_min < t_lo || k_min > t_hi || k_max < t_lo ||
      k_max > t_hi || !(k_min < k_max)) {
    return 0;
  }
  /* D = max(|t_valid_min_c - t_ref_c|, |t_valid_max_c - t_ref_c|); non-negative patterns
   * order as unsigned integers. */
  d_max = F32Add(F32Bits(c->t_valid_min_c), t_ref ^ F32_SIGN) & ~F32_SIGN;
  d_hi = F32Add(F32Bits(c->t_valid_max_c), t_ref ^ F32_SIGN) & ~F32_SIGN;
  if (d_hi > d_max) d_max = d_hi;
  for (i = 0; i < 3; ++i) {
    const int k1 = i == 2 ? 0 : i + 1; /* (i + 1) mod 3 without a libgcc division */
    const int k2 = i == 0 ? 2 : i - 1; /* (i + 2) mod 3 */
    uint32_t n2 = 0u, minor, bias;
    for (j = 0; j < 3; ++j) {
      const uint32_t mij = F32Bits(c->m[3 * i + j]);
      n2 = F32Add(n2, F32Mul(mij, mij));
    }
    if (n2 < n2_lo || n2 > n2_hi) return 0;
    /* det(M) = row0 . (row1 x row2) */
    minor = F32Add(F32Mul(F32Bits(c->m[3 + k1]), F32Bits(c->m[6 + k2])),
                   F32Mul(F32Bits(c->m[3 + k2]), F32Bits(c->m[6 + k1])) ^ F32_SIGN);
    det = F32Add(det, F32Mul(F32Bits(c->m[i]), minor));
    /* |b0| + |b1|*D + |b2|*D^2 bounds the bias over the validity range, D = max |dT|,
     * evaluated as |b0| + (|b1| + |b2| D) D. */
    bias = F32Mul(F32Bits(c->b2[i]) & ~F32_SIGN, d_max);
    bias = F32Mul(F32Add(F32Bits(c->b1[i]) & ~F32_SIGN, bias), d_max);
    bias = F32Add(F32Bits(c->b0[i]) & ~F32_SIGN, bias);
    if (bias > bias_limit) return 0;
  }
  return (det & F32_SIGN) == 0u && det != 0u; /* det > 0 */
}

/* Model bits a term of m[9], b0[3], b1[3], b2[3] needs (section 3): the diagonal of M none. */
#define FM METRO_FW_MODEL_FULL_M
static const uint8_t kTermBits[18] = {0,
                                      FM,
                                      FM,
                                      FM,
                                      0,
                                      FM,
                                      FM,
                                      FM,
                                      0,
                                      METRO_FW_MODEL_BIAS,
                                      METRO_FW_MODEL_BIAS,
                                      METRO_FW_MODEL_BIAS,
                                      METRO_FW_MODEL_LINEAR_T,
                                      METRO_FW_MODEL_LINEAR_T,
                                      METRO_FW_MODEL_LINEAR_T,
                                      METRO_FW_MODEL_QUADRATIC_T,
                                      METRO_FW_MODEL_QUADRATIC_T,
                                      METRO_FW_MODEL_QUADRATIC_T};
#undef FM
typedef char metro_fw_cal_terms_check[(offsetof(metro_fw_sensor_cal, b2) -
                                           offsetof(metro_fw_sensor_cal, m) ==
                                       15 * sizeof(float))
                                          ? 1
                                          : -1];

int metro_fw_sensor_decode(metro_fw_read_fn read, void* ctx, uint32_t body_off, uint32_t body_len,
                           uint16_t version, metro_fw_sensor_kind kind, const metro_fw_config* cfg,
                           metro_fw_sensor_cal* out) {
  uint8_t b[METRO_FW_SENSOR_BODY_LEN];
  uint8_t fs_sel, bits;
  uint32_t i;
  int rc;
  if (read == 0 || cfg == 0 || out == 0) return METRO_FW_E_ARG;
  fs_sel = kind == METRO_FW_ACCEL ? cfg->accel_fs_sel : cfg->gyro_fs_sel;
  rc = metro_fw_sensor_defaults(kind, fs_sel, out);
  if (rc != METRO_FW_OK) return rc;
  if (body_off == 0u) return METRO_FW_OK; /* ABSENT */
  if ((version >> 8) != (METRO_FW_SEC_VERSION_1_0 >> 8)) {
    out->status = METRO_FW_SENSOR_UNSUPPORTED;
    return METRO_FW_OK;
  }
  if (body_len < METRO_FW_SENSOR_BODY_LEN) return METRO_FW_E_ARG; /* validator forbids */
  rc = read(ctx, body_off, b, METRO_FW_SENSOR_BODY_LEN);
  if (rc != METRO_FW_OK) return rc;
  /* Every f32 from t_ref_c (4) to t_valid_max_c (160) finite; from u_M (80) to resid_rms
   * (152) also not negative. Checked on the bits: exponent 0xFF is Inf or NaN; a pattern
   * above 0x80000000 is negative and not -0. */
  for (i = 4; i < 164; i += 4) {
    const uint32_t u = metro_fw_get_u32(b + i);
    if ((u & 0x7F800000u) == 0x7F800000u || (i - 80u < 76u && u > 0x80000000u)) {
      out->status = METRO_FW_SENSOR_NONFINITE;
      return METRO_FW_OK;
    }
  }
  bits = b[2];
  if ((bits & (uint8_t) ~(METRO_FW_MODEL_BIAS | METRO_FW_MODEL_FULL_M | METRO_FW_MODEL_LINEAR_T |
                          METRO_FW_MODEL_QUADRATIC_T | METRO_FW_MODEL_HW_OFFSETS)) != 0u) {
    out->status = METRO_FW_SENSOR_BAD_MODEL;
    return METRO_FW_OK;
  }
  if (b[0] != fs_sel || b[1] != cfg->dlpf_cfg) {
    out->status = METRO_FW_SENSOR_CONFIG_MISMATCH;
    return METRO_FW_OK;
  }
  /* Decoded in place (no struct copy: on the M0 that links memcpy); a LIMITS failure
   * restores the defaults. m, b0, b1, b2 are body bytes 8 ... 79 and 18 consecutive floats of
   * out; a term is read only if its model bits are set (the diagonal of M always). */
  out->model_bits = bits;
  for (i = 0; i < 18; ++i) {
    float* f = (float*)(void*)((char*)out + offsetof(metro_fw_sensor_cal, m)) + i;
    *f = (bits & kTermBits[i]) == kTermBits[i] ? metro_fw_get_f32(b + 8 + 4 * i) : 0.0f;
  }
  for (i = 0; i < 3; ++i) out->hw_offs[i] = metro_fw_get_i16(b + 164 + 2 * i);
  out->t_ref_c = metro_fw_get_f32(b + 4);
  out->t_valid_min_c = metro_fw_get_f32(b + 156);
  out->t_valid_max_c = metro_fw_get_f32(b + 160);
  if (!WithinLimits(out, kind, fs_sel)) {
    (void)metro_fw_sensor_defaults(kind, fs_sel, out);
    out->status = METRO_FW_SENSOR_LIMITS;
    return METRO_FW_OK;
  }
  out->status = METRO_FW_SENSOR_OK;
  return METRO_FW_OK;
}

int metro_fw_load(const metro_fw_flash* flash, const metro_fw_config* cfg,
                  metro_fw_calibration* out) {
  metro_fw_blob_info info[2];
  int active, rc;
  metro_fw_slot s;
  if (flash == 0 || cfg == 0 || out == 0 || cfg->accel_fs_sel > 3u || cfg->gyro_fs_sel > 3u) {
    return METRO_FW_E_ARG;
  }
  rc = metro_fw_choose_active(flash, cfg->device_id, info, out->slot_result, &active);
  if (rc != METRO_FW_OK) return rc;
  metro_fw_sensor_defaults(METRO_FW_ACCEL, cfg->accel_fs_sel, &out->accel);
  metro_fw_sensor_defaults(METRO_FW_GYRO, cfg->gyro_fs_sel, &out->gyro);
  out->slot = active;
  out->seq = 0;
  out->crc32 = 0;
  out->flags = 0;
  if (active == METRO_FW_SLOT_NONE) return METRO_FW_OK;
  out->seq = info[active].seq;
  out->crc32 = info[active].crc32;
  out->flags = info[active].flags;
  s.flash = flash;
  s.base = flash->slot_addr[active];
  /* A read failing here leaves that sensor at its defaults; the other is still decoded. */
  (void)metro_fw_sensor_decode(metro_fw_slot_read, &s, info[active].accel_off,
                               info[active].accel_len, info[active].accel_version, METRO_FW_ACCEL,
                               cfg, &out->accel);
  (void)metro_fw_sensor_decode(metro_fw_slot_read, &s, info[active].gyro_off, info[active].gyro_len,
                               info[active].gyro_version, METRO_FW_GYRO, cfg, &out->gyro);
  return METRO_FW_OK;
}

int metro_fw_apply(const metro_fw_sensor_cal* cal, const int16_t raw_lsb[3], float temp_c,
                   float out_si[3]) {
  float d[3];
  float t = temp_c;
  float dt;
  int i;
  if (cal == 0 || raw_lsb == 0 || out_si == 0) return METRO_FW_E_ARG;
  if (t != t) t = cal->t_ref_c; /* NaN */
  if (t < cal->t_valid_min_c) t = cal->t_valid_min_c;
  if (t > cal->t_valid_max_c) t = cal->t_valid_max_c;
  dt = t - cal->t_ref_c;
  for (i = 0; i < 3; ++i) {
    d[i] = (float)raw_lsb[i] - cal->b0[i] - (cal->b1[i] + cal->b2[i] * dt) * dt;
  }
  for (i = 0; i < 3; ++i) {
    out_si[i] = cal->m[3 * i] * d[0] + cal->m[3 * i + 1] * d[1] + cal->m[3 * i + 2] * d[2];
  }
  return METRO_FW_OK;
}

float metro_fw_mpu6050_temp_c(int16_t raw_lsb) { return (float)raw_lsb * (1.0f / 340.0f) + 36.53f; }
