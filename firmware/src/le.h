/* Private helpers of the library: little-endian byte-by-byte decoding, the fixed-point
 * conversion, a 64 x 32-bit multiply, and the slot reader and active-slot choice shared by
 * blob.c, update.c and push.c. Never cast a buffer to a struct: the M0 faults on unaligned word
 * access and struct layout is the compiler's. Out of line on purpose: one copy is smaller on
 * the M0 than many inlined ones. */
#ifndef METRO_FW_LE_H_
#define METRO_FW_LE_H_

#include <stdint.h>

#include "metro_fw/blob.h"

/* Keeps a static function called once out of line: GCC -Os inlines such functions, which on
 * the Cortex-M0 (8 low registers) costs more spills than the call saves (measured with
 * firmware/cross-build.sh: WithinLimits 88 bytes, the push request handler 78 bytes). */
#if defined(__GNUC__)
#define METRO_FW_NOINLINE __attribute__((noinline))
#else
#define METRO_FW_NOINLINE
#endif

/* Keeps the next loop a loop: GCC -Os peels short constant-count loops completely, which on
 * the M0 costs more than the loop (measured with firmware/cross-build.sh). */
#if defined(__GNUC__) && (__GNUC__ >= 8 || defined(__clang__))
#define METRO_FW_NO_UNROLL _Pragma("GCC unroll 1")
#else
#define METRO_FW_NO_UNROLL
#endif

uint16_t metro_fw_get_u16(const uint8_t* p);
uint32_t metro_fw_get_u32(const uint8_t* p);

/* The 21 constants of a metro_fw_sensor_cal (m[9], b0[3], b1[3], b2[3], t_ref_c,
 * t_valid_min_c, t_valid_max_c; a const metro_fw_sensor_cal* passed as cal) as fixed-point
 * integers q[i] = round(x_i 2^frac_i), to nearest, half away from zero, from the bit patterns
 * (no soft-float): M in Q(m_frac), b0 and b1 Q16, b2 Q24, temperatures Q12. Returns 0, or -1 at
 * the first constant with |x| 2^frac >= 2^cap (before rounding; cap = m_cap_bits for M, 31 for
 * the rest; NaN and Inf always fail). Then |q[i]| <= 2^cap. Defined in blob.c; used by the
 * limit checks (docs/calibration-blob.md 3.1) and the fixed-point apply (3.2). */
int metro_fw_cal_to_q(const void* cal, int m_frac, int m_cap_bits, int32_t q[21]);

/* a * b modulo 2^64 (the exact product whenever |a b| < 2^63), from four 16 x 16-bit products
 * and one 32 x 32 (low word): 64 bytes on the M0 instead of libgcc's 92-byte __aeabi_lmul,
 * whose 64 x 64 generality the limit checks and the fixed apply do not need, and fewer
 * registers to set up per call. Defined in le.c. */
int64_t metro_fw_mul(int64_t a, int32_t b);

/* A flash slot seen as a blob: reads at slot offsets go to flash->read at base + offset. */
typedef struct {
  const metro_fw_flash* flash;
  uint32_t base;
} metro_fw_slot;

/* metro_fw_read_fn over a metro_fw_slot (ctx, whose flash->read is set; dst not NULL).
 * Returns METRO_FW_E_BOUNDS past the page end, METRO_FW_E_FLASH when flash->read fails. */
int metro_fw_slot_read(void* ctx, uint32_t offset, uint8_t* dst, uint32_t len);

/* Validates both slots of flash (flash->read set) and picks the active one: the larger seq,
 * slot A on a tie (section 4). result[i] receives slot i's validator code, info[i] its info.
 * Returns the active slot, 0, 1 or METRO_FW_SLOT_NONE. */
int metro_fw_choose_active(const metro_fw_flash* flash, const uint32_t device_id[2],
                           metro_fw_blob_info info[2], int result[2]);

#endif /* METRO_FW_LE_H_ */
