/* Fixed-point apply for the Cortex-M0 (no FPU): the model of blob.h,
 *
 *   y = M * (r - b0 - b1*dT - b2*dT^2),  dT = clamp(T, t_valid_min_c, t_valid_max_c) - t_ref_c
 *
 * evaluated in integers only. The float32 constants of a loaded metro_fw_sensor_cal are
 * converted once (metro_fw_fixed_from_cal) by IEEE-754 bit manipulation, rounded to nearest,
 * so neither the conversion nor the apply links a soft-float routine. Formats (two's
 * complement int32; Qn means value * 2^n; docs/calibration-blob.md section 3.2):
 *
 *   temperatures T, t_ref, t_valid_min, t_valid_max   Q12 degC      (1/4096 degC)
 *   b0                                                Q16 LSB
 *   b1                                                Q16 LSB/degC
 *   b2                                                Q24 LSB/degC^2
 *   M                                                 Q36 SI/LSB
 *   output y                                          Q20 SI        (m/s^2 or rad/s)
 *
 * Worst-case difference from the model evaluated exactly on the float32 constants (3.2):
 *   |dy_i| <= 2^-37 * sum_j (|r_j| + |bias_j| + 1)
 *           + sum_j |M_ij| * (2^-11 + 2^-16 * (1 + |dT|) + 2^-25 * dT^2
 *                             + 2^-12 * (|b1_j| + 2 * |b2_j| * (|dT| + 2^-12)))
 *           + 2^-21                                                            [SI]
 * about 0.002 LSB-equivalent for an MPU6050 calibration, below 0.02 LSB for any section
 * that passes section 3.1 with |b1| <= 8 LSB/degC and |b2| <= 0.05 LSB/degC^2, and at most
 * 0.063 LSB for every section v1.0 that passes 3.1 (its temperature-coefficient limit bounds
 * |b1| + 2 |b2| |dT|; docs/calibration-blob.md 3.2), 0.076 LSB for every section v2.0 (issue
 * #25: s_nom down to 2^-14 SI/LSB makes the Q36 and Q20 roundings larger in LSB).
 *
 * raw_lsb are signed counts about the input's zero: a section v2.0 with offset-binary input
 * takes METRO_FW_OFFSET_BINARY_TO_INT16(u) of the ADC word u (blob.h). */
#ifndef METRO_FW_FIXED_H_
#define METRO_FW_FIXED_H_

#include <stdint.h>

#include "metro_fw/blob.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
  int32_t m_q36[9]; /* row-major */
  int32_t b0_q16[3];
  int32_t b1_q16[3];
  int32_t b2_q24[3];
  int32_t t_ref_q12;
  int32_t t_valid_min_q12;
  int32_t t_valid_max_q12;
} metro_fw_sensor_fixed;

/* Converts cal's constants to the formats above. Returns METRO_FW_OK, or METRO_FW_E_ARG for
 * NULL pointers or a constant outside its format (|M_ij| >= 2^-5 SI/LSB, |b0| or |b1| >=
 * 2^15, |b2| >= 2^7, |T| >= 2^19 degC, NaN or Inf); out is then all zero. Every section that
 * passes section 3.1 converts (3.1 bounds |b1| < 2^15 LSB/degC and |b2| < 2^7 LSB/degC^2), and
 * so do the defaults. */
int metro_fw_fixed_from_cal(const metro_fw_sensor_cal* cal, metro_fw_sensor_fixed* out);

/* out_q20[i] = y_i * 2^20 for raw counts raw_lsb and die temperature temp_q12 (degC * 4096,
 * e.g. from metro_fw_mpu6050_temp_q12). fx must come from a section that passed 3.1 (or the
 * defaults): then every intermediate fits its integer. Returns METRO_FW_OK or METRO_FW_E_ARG for
 * NULL. */
int metro_fw_apply_fixed(const metro_fw_sensor_fixed* fx, const int16_t raw_lsb[3],
                         int32_t temp_q12, int32_t out_q20[3]);

/* MPU6050 die temperature in Q12 degC: 4096 * (raw / 340 + 36.53) within 3 units
 * (PS-MPU-6000A rev 3.4 sec. 6.4), by a multiply with 2^12 * 1024 / 85 (no divide). */
int32_t metro_fw_mpu6050_temp_q12(int16_t raw_lsb);

#ifdef __cplusplus
}
#endif

#endif /* METRO_FW_FIXED_H_ */
