/* Flash interface of the tag: three callbacks and a context, so host tests plug in a RAM fake
 * with fault injection and the nRF51 port wraps sd_flash_page_erase / sd_flash_write (waiting
 * for the SoC event) or NVMC. */
#ifndef METRO_FW_FLASH_H_
#define METRO_FW_FLASH_H_

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define METRO_FW_PAGE_SIZE 1024u      /* nRF51 flash page, bytes */
#define METRO_FW_SLOT_A_ADDR 0x3B000u /* page 236 */
#define METRO_FW_SLOT_B_ADDR 0x3B400u /* page 237 */

typedef struct {
  /* Copies len bytes at absolute address addr into dst. 0 or a negative value on failure. */
  int (*read)(void* ctx, uint32_t addr, uint8_t* dst, uint32_t len);
  /* Erases the page starting at addr (a multiple of METRO_FW_PAGE_SIZE) to 0xFF. */
  int (*erase_page)(void* ctx, uint32_t addr);
  /* Programs len bytes at addr; addr and len are multiples of 4 (word writes). Flash can
   * only clear bits: the result is old & new. */
  int (*write)(void* ctx, uint32_t addr, const uint8_t* src, uint32_t len);
  void* ctx;
  /* Page-aligned addresses of slot A ([0]) and slot B ([1]), normally
   * METRO_FW_SLOT_A_ADDR and METRO_FW_SLOT_B_ADDR. */
  uint32_t slot_addr[2];
} metro_fw_flash;

#ifdef __cplusplus
}
#endif

#endif /* METRO_FW_FLASH_H_ */
