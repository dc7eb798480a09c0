#include "le.h"

uint16_t metro_fw_get_u16(const uint8_t* p) {
  return (uint16_t)((uint16_t)p[0] | (uint16_t)((uint16_t)p[1] << 8));
}

uint32_t metro_fw_get_u32(const uint8_t* p) {
  return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}

int64_t metro_fw_mul(int64_t a, int32_t b) {
  const uint32_t lo = (uint32_t)a, hi = (uint32_t)((uint64_t)a >> 32), ub = (uint32_t)b;
  const uint32_t a0 = lo & 0xFFFFu, a1 = lo >> 16, b0 = ub & 0xFFFFu, b1 = ub >> 16;
  const uint32_t p00 = a0 * b0;
  const uint32_t mid = a1 * b0 + (p00 >> 16);      /* < 2^32 */
  const uint32_t mid2 = a0 * b1 + (mid & 0xFFFFu); /* < 2^32 */
  uint32_t rhi = a1 * b1 + (mid >> 16) + (mid2 >> 16) + hi * ub;
  if (b < 0) rhi -= lo;
  return (int64_t)(((uint64_t)rhi << 32) | (mid2 << 16) | (p00 & 0xFFFFu));
}
