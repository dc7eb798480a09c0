/* Little-endian byte-by-byte decode/encode helpers (private to the library). Never cast a
 * buffer to a struct: the M0 faults on unaligned word access and struct layout is the
 * compiler's. Out of line on purpose: one copy is smaller on the M0 than many inlined ones. */
#ifndef METRO_FW_LE_H_
#define METRO_FW_LE_H_

#include <stdint.h>

/* Keeps a static function called once out of line: GCC -Os inlines such functions, which on
 * the Cortex-M0 (8 low registers) costs more spills than the call saves (measured with
 * firmware/cross-build.sh: WithinLimits 88 bytes, the push request handler 78 bytes). */
#if defined(__GNUC__)
#define METRO_FW_NOINLINE __attribute__((noinline))
#else
#define METRO_FW_NOINLINE
#endif

uint16_t metro_fw_get_u16(const uint8_t* p);
uint32_t metro_fw_get_u32(const uint8_t* p);
int16_t metro_fw_get_i16(const uint8_t* p);
float metro_fw_get_f32(const uint8_t* p);
void metro_fw_put_u16(uint8_t* p, uint16_t v);
void metro_fw_put_u32(uint8_t* p, uint32_t v);

#endif /* METRO_FW_LE_H_ */
