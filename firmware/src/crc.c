#include "metro_fw/crc.h"

/* Nibble table for the reflected polynomial 0xEDB88320: 64 bytes of flash instead of 1 KiB,
 * two lookups per byte. Entry i is the CRC register after shifting nibble i through. */
static const uint32_t kCrc32Nibble[16] = {0x00000000u, 0x1DB71064u, 0x3B6E20C8u, 0x26D930ACu,
                                          0x76DC4190u, 0x6B6B51F4u, 0x4DB26158u, 0x5005713Cu,
                                          0xEDB88320u, 0xF00F9344u, 0xD6D6A3E8u, 0xCB61B38Cu,
                                          0x9B64C2B0u, 0x86D3D2D4u, 0xA00AE278u, 0xBDBDF21Cu};

uint32_t metro_fw_crc32(uint32_t crc, const uint8_t* data, uint32_t len) {
  uint32_t c = crc ^ 0xFFFFFFFFu;
  uint32_t i;
  for (i = 0; i < len; ++i) {
    c ^= data[i];
    c = (c >> 4) ^ kCrc32Nibble[c & 0x0Fu];
    c = (c >> 4) ^ kCrc32Nibble[c & 0x0Fu];
  }
  return c ^ 0xFFFFFFFFu;
}

uint16_t metro_fw_crc16(uint16_t crc, const uint8_t* data, uint32_t len) {
  /* The 16-bit register in the top half of a word: the bit shifted out is the sign bit. */
  uint32_t c = (uint32_t)crc << 16;
  uint32_t i;
  int bit;
  for (i = 0; i < len; ++i) {
    c ^= (uint32_t)data[i] << 24;
    for (bit = 0; bit < 8; ++bit) c = (c & 0x80000000u) != 0u ? (c << 1) ^ 0x10210000u : c << 1;
  }
  return (uint16_t)(c >> 16);
}
