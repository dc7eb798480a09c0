#include "metro_fw/fixed.h"

#include <stddef.h>

#include "le.h"

/* Both structs hold 21 four-byte values in the same order: m[9], b0[3], b1[3], b2[3], t_ref,
 * t_valid_min, t_valid_max. The conversion walks them as one table; these typedefs fail to
 * compile if either layout changes. */
typedef char metro_fw_cal_layout_check[(sizeof(((metro_fw_sensor_cal*)0)->m) == 36 &&
                                        offsetof(metro_fw_sensor_cal, m) == 0 &&
                                        offsetof(metro_fw_sensor_cal, t_valid_max_c) == 80)
                                           ? 1
                                           : -1];
typedef char metro_fw_fixed_layout_check[(sizeof(metro_fw_sensor_fixed) == 84 &&
                                          offsetof(metro_fw_sensor_fixed, t_valid_max_q12) == 80)
                                             ? 1
                                             : -1];

int metro_fw_fixed_from_cal(const metro_fw_sensor_cal* cal, metro_fw_sensor_fixed* out) {
  int32_t* q = (int32_t*)(void*)out;
  int i;
  if (cal == 0 || out == 0) return METRO_FW_E_ARG;
  /* M Q36, b0 and b1 Q16, b2 Q24, temperatures Q12, each below 2^31 */
  if (metro_fw_cal_to_q(cal, 36, 31, q) != 0) {
    for (i = 0; i < 21; ++i) q[i] = 0;
    return METRO_FW_E_ARG;
  }
  return METRO_FW_OK;
}

/* round(a * b / 2^shift), shift >= 1 */
static int64_t MulRound(int64_t a, int32_t b, int shift) {
  return (metro_fw_mul(a, b) + ((int64_t)1 << (shift - 1))) >> shift;
}

int metro_fw_apply_fixed(const metro_fw_sensor_fixed* fx, const int16_t raw_lsb[3],
                         int32_t temp_q12, int32_t out_q20[3]) {
  int32_t e_q10[3];
  int32_t t = temp_q12;
  int32_t dt_q12;
  int i, j;
  if (fx == 0 || raw_lsb == 0 || out_q20 == 0) return METRO_FW_E_ARG;
  if (t < fx->t_valid_min_q12) t = fx->t_valid_min_q12;
  if (t > fx->t_valid_max_q12) t = fx->t_valid_max_q12;
  dt_q12 = t - fx->t_ref_q12;
  for (i = 0; i < 3; ++i) {
    /* bias = b0 + (b1 + b2*dT)*dT (Horner), each product rounded to Q16 LSB, and
     * e = round((r 2^16 - bias) / 2^6) in Q10 = r 2^10 - floor((bias + 31) / 2^6), since r 2^16
     * is a multiple of 2^6. c = b1 + b2 dT may exceed 2^31 in Q16 and stays 64-bit; bias fits
     * int32: section 3.1 bounds |b0| + |b1| D + |b2| D^2 by the bias limit (< 2^13 LSB) and
     * |dT| <= D after the clamp, so |bias| < 2^30 in Q16 (docs/calibration-blob.md 3.2). */
    const int64_t c_q16 = fx->b1_q16[i] + MulRound(fx->b2_q24[i], dt_q12, 20);
    const int32_t bias_q16 = fx->b0_q16[i] + (int32_t)MulRound(c_q16, dt_q12, 12);
    e_q10[i] = raw_lsb[i] * 1024 - ((bias_q16 + 31) >> 6);
  }
  for (i = 0; i < 3; ++i) {
    int64_t acc_q46 = 0x2000000; /* rounds the shift below to nearest */
    for (j = 0; j < 3; ++j) acc_q46 += metro_fw_mul(fx->m_q36[3 * i + j], e_q10[j]);
    out_q20[i] = (int32_t)(acc_q46 >> 26);
  }
  return METRO_FW_OK;
}

int32_t metro_fw_mpu6050_temp_q12(int16_t raw_lsb) {
  /* 4096 / 340 = 1024 / 85 = 49345 / 2^12 - 0.25 / 2^12: at most 2 units off at |raw| =
   * 32768, plus 1/2 for the rounding; 36.53 * 4096 = 149626.88 -> 149627.
   * |raw| * 49345 <= 1.62e9 < 2^31. */
  return ((raw_lsb * (int32_t)49345 + 0x800) >> 12) + 149627;
}
