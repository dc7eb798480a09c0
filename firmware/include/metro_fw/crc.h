/* Checksums of the calibration blob and of the push protocol frames.
 *
 * CRC-32/ISO-HDLC (zlib's crc32): poly 0x04C11DB7 reflected, init 0xFFFFFFFF, reflected in
 * and out, xorout 0xFFFFFFFF; check CRC("123456789") = 0xCBF43926.
 * CRC-16/CCITT-FALSE: poly 0x1021, init 0xFFFF, not reflected, xorout 0; check 0x29B1.
 * (Parameters and check values from the Greg Cook "Catalogue of parametrised CRC
 * algorithms".) */
#ifndef METRO_FW_CRC_H_
#define METRO_FW_CRC_H_

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* zlib convention: pass 0 for the first chunk, then the previous return value to continue;
 * metro_fw_crc32(metro_fw_crc32(0, a, na), b, nb) == CRC of a followed by b.
 * data may be NULL only when len is 0. */
uint32_t metro_fw_crc32(uint32_t crc, const uint8_t* data, uint32_t len);

/* Pass METRO_FW_CRC16_INIT for the first chunk, then the previous return value. */
#define METRO_FW_CRC16_INIT 0xFFFFu
uint16_t metro_fw_crc16(uint16_t crc, const uint8_t* data, uint32_t len);

#ifdef __cplusplus
}
#endif

#endif /* METRO_FW_CRC_H_ */
