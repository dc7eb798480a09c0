#include "metro_fw/blob.h"

#include <stddef.h>

#include "le.h"
#include "metro_fw/crc.h"

/* Bytes read per call while computing the CRC: small enough for the boot stack; a multiple
 * of 4 (the stored CRC is never split between two chunks). */
#define METRO_FW_CHUNK 32u
/* CRC-32/ISO-HDLC of any byte string followed by its own CRC, little-endian. */
#define METRO_FW_CRC32_RESIDUE 0x2144DF1Cu

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

/* The header's u16 fields fmt_major ... header_len and u32 fields seq ... flags are consecutive
 * in metro_fw_blob_info, in header order; the validator reads them in two loops. */
typedef char metro_fw_info_header_check[(offsetof(metro_fw_blob_info, header_len) == 6 &&
                                         offsetof(metro_fw_blob_info, flags) -
                                                 offsetof(metro_fw_blob_info, seq) ==
                                             12)
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
      /* A major this firmware knows (1; 2 for a sensor) carries at least the v1.0 body, whose
       * length v2.0 keeps; x.0 exactly that. */
      if ((version >> 8) == 1u || (known != 0u && (version >> 8) == 2u)) {
        const uint32_t v1_len = known == 0u ? METRO_FW_META_BODY_LEN : METRO_FW_SENSOR_BODY_LEN;
        if (body_len < v1_len || ((version & 0xFFu) == 0u && body_len != v1_len)) {
          return METRO_FW_E_SECTION;
        }
      }
      f[0] = (uint16_t)off;
      f[1] = (uint16_t)body_len;
      f[2] = (uint16_t)version;
    }
    off += body_len;
  }
  return METRO_FW_OK; /* off == end: sections tile the blob exactly */
}

/* Step 8 of section 4: flags b0/b1 name exactly the sensor sections present (at least one),
 * each of them passes 3.1 on its own fs_sel and dlpf_cfg (metro_fw_sensor_decode without a
 * configuration), and flag b2 is set exactly when one of them has a temperature term. */
METRO_FW_NOINLINE static int CheckSensors(metro_fw_read_fn read, void* ctx,
                                          const metro_fw_blob_info* in) {
  metro_fw_sensor_cal cal;
  uint32_t k, temp = 0u;
  int rc;
  if ((in->flags & (METRO_FW_FLAG_ACCEL | METRO_FW_FLAG_GYRO)) == 0u) return METRO_FW_E_SENSOR;
  for (k = 0; k < 2u; ++k) {
    rc = metro_fw_sensor_decode(read, ctx, in, (metro_fw_sensor_kind)k, 0, &cal);
    if (rc != METRO_FW_OK) return rc;
    /* declared: usable (OK = 0); not declared: no section (ABSENT = 1) */
    if (cal.status != (((in->flags >> k) & 1u) ^ 1u)) return METRO_FW_E_SENSOR;
    temp |= cal.model_bits; /* 0 for an absent sensor */
  }
  /* flag b2 against model bit 0x04 or 0x08 of either sensor */
  return (((temp | temp >> 1) ^ in->flags) & METRO_FW_FLAG_TEMP_MODEL) == 0u ? METRO_FW_OK
                                                                             : METRO_FW_E_SENSOR;
}

int metro_fw_blob_validate(metro_fw_read_fn read, void* ctx, uint32_t avail_len,
                           const uint32_t device_id[2], metro_fw_blob_info* info) {
  metro_fw_blob_info local;
  metro_fw_blob_info* in = info != 0 ? info : &local;
  uint8_t buf[METRO_FW_CHUNK];
  uint32_t magic, crc, off, n, i;
  int rc;
  if (read == 0 || device_id == 0) return METRO_FW_E_ARG;
  for (i = 0; i < sizeof(*in); ++i) ((uint8_t*)in)[i] = 0;
  if (avail_len < 4u) return METRO_FW_E_BOUNDS;
  /* One read of the header, or of all there is when avail_len is shorter: EMPTY and MAGIC
   * still come before BOUNDS (section 4). */
  rc = read(ctx, 0, buf, avail_len < METRO_FW_HEADER_LEN ? avail_len : METRO_FW_HEADER_LEN);
  if (rc != METRO_FW_OK) return rc;
  magic = metro_fw_get_u32(buf);
  if (magic == METRO_FW_ERASED_WORD) return METRO_FW_E_EMPTY;
  if (magic != METRO_FW_MAGIC) return METRO_FW_E_MAGIC;
  if (avail_len < METRO_FW_HEADER_LEN) return METRO_FW_E_BOUNDS;
  /* fmt_major, fmt_minor, total_len, header_len (u16) and seq, device_id[2], flags (u32)
   * follow each other in metro_fw_blob_info as in the header (layout checked above). */
  for (i = 0; i < 4; ++i) {
    (&in->fmt_major)[i] = metro_fw_get_u16(buf + 4 + 2 * i);
    (&in->seq)[i] = metro_fw_get_u32(buf + 12 + 4 * i);
  }
  if (in->fmt_major != METRO_FW_FMT_MAJOR) return METRO_FW_E_UNSUPPORTED;
  if (((in->header_len | in->total_len) & 3u) != 0u || in->header_len < METRO_FW_HEADER_LEN ||
      in->total_len > METRO_FW_MAX_LEN || in->total_len > avail_len ||
      (uint32_t)in->header_len + 4u > in->total_len ||
      (in->fmt_minor == 0u && in->header_len != METRO_FW_HEADER_LEN)) {
    return METRO_FW_E_BOUNDS;
  }
  /* The CRC-32 runs over the whole blob, stored CRC included: the CRC of bytes followed by
   * their own CRC (little-endian) is the constant 0x2144DF1C (the catalogue residue 0xDEBB20E3
   * of CRC-32/ISO-HDLC, before the final XOR), and only the right CRC gives it (the last four
   * bytes enter the register bijectively). total_len is a multiple of 4, so the stored CRC lies
   * in the last chunk read. */
  crc = 0;
  off = 0;
  do { /* total_len >= 36 */
    n = in->total_len - off;
    if (n > METRO_FW_CHUNK) n = METRO_FW_CHUNK;
    rc = read(ctx, off, buf, n);
    if (rc != METRO_FW_OK) return rc;
    crc = metro_fw_crc32(crc, buf, n);
    off += n;
  } while (off < in->total_len);
  in->crc32 = metro_fw_get_u32(buf + n - 4u);
  if (crc != METRO_FW_CRC32_RESIDUE) return METRO_FW_E_CRC;
  if (in->device_id[0] != device_id[0] || in->device_id[1] != device_id[1]) {
    return METRO_FW_E_FOREIGN;
  }
  if (in->seq < METRO_FW_SEQ_MIN || in->seq > METRO_FW_SEQ_MAX) return METRO_FW_E_SEQ;
  rc = WalkSections(read, ctx, in);
  return rc != METRO_FW_OK ? rc : CheckSensors(read, ctx, in);
}

int metro_fw_slot_read(void* ctx, uint32_t offset, uint8_t* dst, uint32_t len) {
  const metro_fw_slot* s = (const metro_fw_slot*)ctx;
  if (offset > METRO_FW_PAGE_SIZE || len > METRO_FW_PAGE_SIZE - offset) return METRO_FW_E_BOUNDS;
  return s->flash->read(s->flash->ctx, s->base + offset, dst, len) == 0 ? METRO_FW_OK
                                                                        : METRO_FW_E_FLASH;
}

int metro_fw_choose_active(const metro_fw_flash* flash, const uint32_t device_id[2],
                           metro_fw_blob_info info[2], int result[2]) {
  int i, active = METRO_FW_SLOT_NONE;
  for (i = 0; i < 2; ++i) {
    metro_fw_slot s;
    s.flash = flash;
    s.base = flash->slot_addr[i];
    result[i] =
        metro_fw_blob_validate(metro_fw_slot_read, &s, METRO_FW_PAGE_SIZE, device_id, &info[i]);
    /* the larger seq; slot A on a tie */
    if (result[i] == METRO_FW_OK && (active == METRO_FW_SLOT_NONE || info[i].seq > info[0].seq)) {
      active = i;
    }
  }
  return active;
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

int metro_fw_sensor_defaults(metro_fw_sensor_kind kind, uint8_t fs_sel, metro_fw_sensor_cal* out) {
  uint8_t* z;
  uint32_t i;
  float s;
  if (out == 0 || fs_sel > 3u || (kind != METRO_FW_ACCEL && kind != METRO_FW_GYRO)) {
    return METRO_FW_E_ARG;
  }
  z = (uint8_t*)out;
  for (i = 0; i < sizeof(*out); ++i) z[i] = 0;
  /* s_nom(fs 0) * 2^fs_sel: exact, by adding fs_sel to the (normal) exponent */
  s = BitsF32(F32Bits(kind == METRO_FW_ACCEL ? METRO_FW_ACCEL_SENS_FS0 : METRO_FW_GYRO_SENS_FS0) +
              ((uint32_t)fs_sel << 23));
  out->m[0] = s;
  out->m[4] = s;
  out->m[8] = s;
  out->t_ref_c = METRO_FW_DEFAULT_T_REF_C;
  out->t_valid_min_c = METRO_FW_TEMP_MIN_C;
  out->t_valid_max_c = METRO_FW_TEMP_MAX_C;
  out->status = METRO_FW_SENSOR_ABSENT;
  return METRO_FW_OK;
}

/* round(x 2^frac) for the binary32 x at p, to nearest, half away from zero, from the bit
 * pattern: x = (-1)^s (2^23 + f) 2^(e - 150), so x 2^frac is the 24-bit significand shifted by
 * e - 150 + frac. Fails (-1, *out untouched) when |x| 2^frac >= 2^cap_bits before rounding;
 * NaN and Inf (e = 255) always fail for frac >= 0, zero and subnormals give 0 (frac <= 100). */
static int F32ToQ(const float* p, int frac, int cap_bits, int32_t* out) {
  const uint32_t u = F32Bits(*p);
  const int shift = (int)((u >> 23) & 0xFFu) - 150 + frac;
  /* The implicit bit is set for zero and subnormals too: their shift is below -24, so they
   * round to 0 either way. */
  const uint32_t mant = (u & 0x7FFFFFu) | 0x800000u;
  uint32_t q;
  if (shift > cap_bits - 24) return -1; /* mant 2^shift >= 2^(23 + shift) >= 2^cap_bits */
  if (shift >= 0) {
    q = mant << shift;
  } else if (shift < -24) {
    q = 0u; /* mant 2^shift < 1/2 */
  } else {
    q = (mant + (1u << (-shift - 1))) >> -shift;
  }
  *out = (u & 0x80000000u) != 0u ? -(int32_t)q : (int32_t)q;
  return 0;
}

/* gyro_input follows accel_input in metro_fw_config: the decoder indexes them by kind. */
typedef char metro_fw_config_input_check
    [(offsetof(metro_fw_config, gyro_input) - offsetof(metro_fw_config, accel_input) == 1) ? 1
                                                                                           : -1];

/* The 21 floats of metro_fw_sensor_cal from m[0] to t_valid_max_c are consecutive. */
typedef char metro_fw_cal_q_layout_check[(offsetof(metro_fw_sensor_cal, m) == 0 &&
                                          offsetof(metro_fw_sensor_cal, t_valid_max_c) == 80)
                                             ? 1
                                             : -1];

int metro_fw_cal_to_q(const void* cal, int m_frac, int m_cap_bits, int32_t q[21]) {
  int i;
  for (i = 0; i < 21; ++i) {
    /* M Q(m_frac), b0 and b1 Q16, b2 Q24, temperatures Q12 */
    const int frac = i < 9 ? m_frac : i < 15 ? 16 : i < 18 ? 24 : 12;
    if (F32ToQ((const float*)cal + i, frac, i < 9 ? m_cap_bits : 31, &q[i]) != 0) return -1;
  }
  return 0;
}

/* Section 3.1 limit checks in exact integer arithmetic on fixed-point forms of the binary32
 * constants (no soft-float), each rounded once by metro_fw_cal_to_q:
 *  *   M        Q(141 - e) SI/LSB, e the biased binary32 exponent of the nominal sensitivity
 *            s_nom (v1.0: the MPU6050's of the section's fs_sel, binary32, so Q(25 - fs_sel)
 *            accel, Q(27 - fs_sel) gyro; v2.0: the declared one, issue #25): s_nom becomes
 *            S = mant / 2^9 in [2^14, 2^15) (mant its 24-bit significand); |M_ij| < 2^16
 *            (> 2 S: a larger entry fails its row norm anyway); squared row norms in int64;
 *   b0, b1   Q16 LSB, LSB/degC, below 2^31 (|b1| < 2^15 LSB/degC: the fixed apply's range);
 *   b2       Q24 LSB/degC^2, below 2^31 (|b2| < 2^7 LSB/degC^2: the fixed apply's range);
 *   T        Q12 degC (t_ref_c, t_valid_min_c, t_valid_max_c).
 * Every step below is exact except |b2| D, truncated from Q36 to Q28 (by less than 2^-28; in
 * the temperature coefficient |b1| + 2 |b2| D it counts twice).
 * The decision band (where it can differ from the real-number rule) is in 3.1. */
#define METRO_FW_TEMP_MIN_Q12 (-40 * 4096)
#define METRO_FW_TEMP_MAX_Q12 (85 * 4096)
#define METRO_FW_MIN_SPAN_Q12 (METRO_FW_T_VALID_MIN_SPAN_C * 4096)

/* |x| for |x| < 2^31 (what metro_fw_cal_to_q gives with cap 31). */
static uint32_t AbsU32(int32_t x) { return x < 0 ? 0u - (uint32_t)x : (uint32_t)x; }

/* Section 3.1 physical limits on decoded constants (model bits already applied), for the
 * nominal sensitivity with binary32 bits s_bits (SI per LSB) and the bias and
 * temperature-coefficient limits at fs_sel 0 shifted right by limit_shift. */
METRO_FW_NOINLINE static int WithinLimits(const metro_fw_sensor_cal* c, metro_fw_sensor_kind kind,
                                          uint32_t s_bits, uint8_t limit_shift) {
  int32_t q[21]; /* m[9], b0[3], b1[3], b2[3], t_ref, t_valid_min, t_valid_max */
  /* s_nom = mant 2^(e - 150), so with M in Q(141 - e) it is S = mant / 2^9, 2^14 <= S < 2^15 */
  const int m_frac = 141 - (int)((s_bits >> 23) & 0xFFu);
  const int64_t mant2 = metro_fw_mul((int32_t)((s_bits & 0x7FFFFFu) | 0x800000u),
                                     (int32_t)((s_bits & 0x7FFFFFu) | 0x800000u)); /* < 2^48 */
  const int64_t n2_lo = metro_fw_mul(mant2, 81), n2_hi = metro_fw_mul(mant2, 121);
  const int32_t limit_fs0 =
      kind == METRO_FW_ACCEL ? METRO_FW_ACCEL_BIAS_LIMIT_LSB : METRO_FW_GYRO_BIAS_LIMIT_LSB;
  const uint32_t tempco_fs0 =
      kind == METRO_FW_ACCEL ? METRO_FW_ACCEL_TEMPCO_LIMIT_LSB : METRO_FW_GYRO_TEMPCO_LIMIT_LSB;
  int64_t det = 0;
  int32_t d;
  int i, j;
  /* s_nom > 0 with 22 <= 141 - e <= 28 (NaN, Inf, 0 and subnormals fall outside) */
  if ((s_bits >> 31) != 0u || m_frac < METRO_FW_S_NOM_MIN_Q || m_frac > METRO_FW_S_NOM_MAX_Q ||
      metro_fw_cal_to_q(c, m_frac, 16, q) != 0) {
    return 0;
  }
  if (q[18] < METRO_FW_TEMP_MIN_Q12 || q[18] > METRO_FW_TEMP_MAX_Q12 ||
      q[19] < METRO_FW_TEMP_MIN_Q12 || q[20] > METRO_FW_TEMP_MAX_Q12 || q[19] >= q[20] ||
      q[20] - q[19] < METRO_FW_MIN_SPAN_Q12) { /* no overflow: -40 <= t_min < t_max <= 85 */
    return 0;
  }
  /* D = max(|t_valid_min - t_ref|, |t_valid_max - t_ref|) = max(t_max - t_ref, t_ref - t_min)
   * since t_min < t_max; Q12, 0 < D <= 125 * 4096 < 2^19. */
  d = q[20] - q[18];
  if (q[18] - q[19] > d) d = q[18] - q[19];
  for (i = 0; i < 3; ++i) {
    const int k1 = i == 2 ? 0 : i + 1; /* (i + 1) mod 3 without a libgcc division */
    const int k2 = i == 0 ? 2 : i - 1; /* (i + 2) mod 3 */
    uint64_t n2 = 0u;
    int64_t n2s;
    uint32_t minor;
    uint64_t b2d_q28, c_q28;
    /* 0.81 S^2 <= n2 <= 1.21 S^2 as 81 mant^2 <= 100 2^18 n2 <= 121 mant^2, exactly (each
     * q^2 < 2^32 in uint32, n2 < 3 2^32, so 100 2^18 n2 < 2^59) */
    for (j = 0; j < 3; ++j) n2 += (uint32_t)q[3 * i + j] * (uint32_t)q[3 * i + j];
    n2s = metro_fw_mul((int64_t)n2, 100 << 18);
    if (n2s < n2_lo || n2s > n2_hi) return 0;
    /* det(M) = row0 . (row1 x row2). The minor fits int32 once rows 1 and 2 pass their norms
     * (|minor| <= 1.21 S^2 < 2^31); before that it may wrap (unsigned, no overflow) but then
     * a later row fails and det is not used. */
    minor = (uint32_t)q[3 + k1] * (uint32_t)q[6 + k2] - (uint32_t)q[3 + k2] * (uint32_t)q[6 + k1];
    det += metro_fw_mul(q[i], (int32_t)minor);
    /* |b0| + (|b1| + |b2| D) D <= limit: c = |b1| + |b2| D in Q28 (< 2^44), the sum in Q40
     * (< 2^63); all terms are not negative, so unsigned 64-bit. The temperature coefficient
     * |b1| + 2 |b2| D = c + |b2| D (Q28) <= tempco limit (Q28, < 2^35). */
    b2d_q28 = (uint64_t)metro_fw_mul(AbsU32(q[15 + i]), d) >> 8;
    c_q28 = (uint64_t)AbsU32(q[12 + i]) * 4096u + b2d_q28;
    if (((uint64_t)AbsU32(q[9 + i]) << 24) + (uint64_t)metro_fw_mul((int64_t)c_q28, d) >
            ((uint64_t)(uint32_t)(limit_fs0 >> limit_shift) << 40) ||
        c_q28 + b2d_q28 > ((uint64_t)(tempco_fs0 >> limit_shift) << 28)) {
      return 0;
    }
  }
  return det > 0;
}

/* Model bits a term of m[9], b0[3], b1[3], b2[3], t_ref_c, t_valid_min_c, t_valid_max_c needs
 * (section 3): the diagonal of M and the temperatures none. */
#define FM METRO_FW_MODEL_FULL_M
static const uint8_t kTermBits[21] = {0,
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
                                      METRO_FW_MODEL_QUADRATIC_T,
                                      0,
                                      0,
                                      0};
#undef FM
typedef char metro_fw_cal_terms_check[(offsetof(metro_fw_sensor_cal, b2) -
                                           offsetof(metro_fw_sensor_cal, m) ==
                                       15 * sizeof(float))
                                          ? 1
                                          : -1];

int metro_fw_sensor_decode(metro_fw_read_fn read, void* ctx, const metro_fw_blob_info* info,
                           metro_fw_sensor_kind kind, const metro_fw_config* cfg,
                           metro_fw_sensor_cal* out) {
  uint8_t b[METRO_FW_SENSOR_BODY_LEN];
  const uint16_t* sec;
  uint8_t fs_sel, bits, status, major, input;
  uint32_t i;
  int rc;
  if (read == 0 || info == 0 || out == 0) return METRO_FW_E_ARG;
  fs_sel = cfg == 0 ? 0u : kind == METRO_FW_ACCEL ? cfg->accel_fs_sel : cfg->gyro_fs_sel;
  rc = metro_fw_sensor_defaults(kind, fs_sel, out);
  if (rc != METRO_FW_OK) return rc;
  /* off, len, version of ACCEL or GYRO (layout checked at the top; kind is 0 or 1, checked by
   * the defaults) */
  sec =
      (const uint16_t*)(const void*)((const char*)info + offsetof(metro_fw_blob_info, accel_off)) +
      3u * kind;
  if (sec[0] == 0u) return METRO_FW_OK; /* ABSENT */
  status = METRO_FW_SENSOR_UNSUPPORTED;
  major = (uint8_t)(sec[2] >> 8);
  if (major - 1u > 1u) goto done;                               /* majors 1 and 2 */
  if (sec[1] < METRO_FW_SENSOR_BODY_LEN) return METRO_FW_E_ARG; /* validator forbids */
  rc = read(ctx, sec[0], b, METRO_FW_SENSOR_BODY_LEN);
  if (rc != METRO_FW_OK) return rc;
  /* Every f32 from t_ref_c (4) to t_valid_max_c (160) finite; from u_M (80) to resid_rms
   * (152) also not negative. Checked on the bits: exponent 0xFF is Inf or NaN; a pattern
   * above 0x80000000 is negative and not -0. */
  status = METRO_FW_SENSOR_NONFINITE;
  for (i = 4; i < 164; i += 4) {
    const uint32_t u = metro_fw_get_u32(b + i);
    if ((u & 0x7F800000u) == 0x7F800000u || (i - 80u < 76u && u > 0x80000000u)) goto done;
  }
  bits = b[2];
  /* v2.0: byte 3 is the input encoding, the u32 at 172 s_nom; v1.0: reserved (not read), the
   * input int16 and s_nom the MPU6050's of fs_sel (set below) */
  input = major == 2u ? b[3] : 0u;
  status = METRO_FW_SENSOR_BAD_MODEL;
  if ((bits & (uint8_t) ~(METRO_FW_MODEL_BIAS | METRO_FW_MODEL_FULL_M | METRO_FW_MODEL_LINEAR_T |
                          METRO_FW_MODEL_QUADRATIC_T | METRO_FW_MODEL_HW_OFFSETS)) != 0u ||
      input > METRO_FW_INPUT_OFFSET_BINARY) {
    goto done;
  }
  status = METRO_FW_SENSOR_CONFIG_MISMATCH;
  if (cfg == 0) { /* the section's own configuration (the validator) */
    fs_sel = b[0];
    if (fs_sel > 3u || b[1] > 6u) goto done;
  } else if (b[0] != fs_sel || b[1] != cfg->dlpf_cfg || input != (&cfg->accel_input)[kind]) {
    goto done;
  }
  /* Decoded in place (no struct copy: on the M0 that links memcpy); a LIMITS failure
   * restores the defaults. m, b0, b1, b2 (body bytes 8 ... 79), t_ref_c (4), t_valid_min_c
   * and t_valid_max_c (156, 160) are 21 consecutive floats of out; a term is read only if its
   * model bits are set (the diagonal of M and the temperatures always). */
  out->model_bits = bits;
  for (i = 0; i < 21; ++i) {
    const uint32_t at = i < 18 ? 8u + 4u * i : i == 18 ? 4u : 80u + 4u * i;
    ((float*)(void*)out)[i] =
        (bits & kTermBits[i]) == kTermBits[i] ? BitsF32(metro_fw_get_u32(b + at)) : 0.0f;
  }
  METRO_FW_NO_UNROLL
  for (i = 0; i < 3; ++i) {
    const int32_t u = metro_fw_get_u16(b + 164 + 2 * i);
    out->hw_offs[i] = (int16_t)(u - ((u & 0x8000) << 1)); /* two's complement */
  }
  status = METRO_FW_SENSOR_OK;
  /* v1.0: the MPU6050's s_nom of fs_sel and its limits (shifted by fs_sel); v2.0: the declared
   * s_nom and the fs_sel 0 limits in counts (3.1) */
  if (!WithinLimits(out, kind,
                    major == 2u ? metro_fw_get_u32(b + 172)
                                : F32Bits(kind == METRO_FW_ACCEL ? METRO_FW_ACCEL_SENS_FS0
                                                                 : METRO_FW_GYRO_SENS_FS0) +
                                      ((uint32_t)fs_sel << 23),
                    major == 2u ? 0u : fs_sel)) {
    (void)metro_fw_sensor_defaults(kind, fs_sel, out); /* input 0 */
    status = METRO_FW_SENSOR_LIMITS;
  } else {
    out->input = input;
  }
done:
  out->status = status;
  return METRO_FW_OK;
}

int metro_fw_load(const metro_fw_flash* flash, const metro_fw_config* cfg,
                  metro_fw_calibration* out) {
  metro_fw_blob_info info[2];
  metro_fw_blob_info* a = &info[0];
  int active;
  metro_fw_slot s;
  if (flash == 0 || flash->read == 0 || cfg == 0 || out == 0 || cfg->accel_fs_sel > 3u ||
      cfg->gyro_fs_sel > 3u) {
    return METRO_FW_E_ARG;
  }
  active = metro_fw_choose_active(flash, cfg->device_id, info, out->slot_result);
  out->slot = active;
  s.flash = flash;
  s.base = 0;
  if (active == METRO_FW_SLOT_NONE) {
    /* nothing active: zeros out, and both sensors absent (defaults) */
    uint32_t i;
    for (i = 0; i < sizeof(*a); ++i) ((uint8_t*)a)[i] = 0;
  } else {
    a = &info[active];
    s.base = flash->slot_addr[active];
  }
  out->seq = a->seq;
  out->crc32 = a->crc32;
  out->flags = a->flags;
  /* The decoder sets the defaults first: a body offset of 0 leaves them with status ABSENT,
   * and a read failing here leaves that sensor at its defaults (the other is still decoded). */
  (void)metro_fw_sensor_decode(metro_fw_slot_read, &s, a, METRO_FW_ACCEL, cfg, &out->accel);
  (void)metro_fw_sensor_decode(metro_fw_slot_read, &s, a, METRO_FW_GYRO, cfg, &out->gyro);
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
