/* libFuzzer target: the push receiver (SLIP decoder, frame parser, every operation, the
 * update into a RAM flash) on arbitrary byte streams. Run by fuzz/run.sh. */
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "metro_fw/push.h"

int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size);

static uint8_t g_flash[2 * METRO_FW_PAGE_SIZE];

static int InRange(uint32_t addr, uint32_t len) {
  return addr >= METRO_FW_SLOT_A_ADDR && addr - METRO_FW_SLOT_A_ADDR <= sizeof(g_flash) &&
         len <= sizeof(g_flash) - (addr - METRO_FW_SLOT_A_ADDR);
}
static int Read(void* ctx, uint32_t addr, uint8_t* dst, uint32_t len) {
  (void)ctx;
  if (!InRange(addr, len)) return -1;
  memcpy(dst, g_flash + (addr - METRO_FW_SLOT_A_ADDR), len);
  return 0;
}
static int Erase(void* ctx, uint32_t addr) {
  (void)ctx;
  if (!InRange(addr, METRO_FW_PAGE_SIZE) || addr % METRO_FW_PAGE_SIZE != 0) return -1;
  memset(g_flash + (addr - METRO_FW_SLOT_A_ADDR), 0xFF, METRO_FW_PAGE_SIZE);
  return 0;
}
static int Write(void* ctx, uint32_t addr, const uint8_t* src, uint32_t len) {
  uint32_t i;
  (void)ctx;
  if (!InRange(addr, len) || addr % 4 != 0 || len % 4 != 0) return -1;
  for (i = 0; i < len; ++i) g_flash[addr - METRO_FW_SLOT_A_ADDR + i] &= src[i];
  return 0;
}
static int Send(void* ctx, const uint8_t* data, uint32_t len) {
  (void)ctx;
  (void)data;
  return len > 2u * METRO_FW_PUSH_MAX_FRAME + 2u ? -1 : 0;
}

int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static metro_fw_push push;
  static const uint32_t id[2] = {0x12345678u, 0x9ABCDEF0u};
  metro_fw_flash flash;
  memset(g_flash, 0xFF, sizeof(g_flash));
  flash.read = Read;
  flash.erase_page = Erase;
  flash.write = Write;
  flash.ctx = 0;
  flash.slot_addr[0] = METRO_FW_SLOT_A_ADDR;
  flash.slot_addr[1] = METRO_FW_SLOT_B_ADDR;
  if (metro_fw_push_init(&push, &flash, id, Send, 0) != METRO_FW_OK) return 0;
  if (size == 0) return 0;
  if ((data[0] & 1u) != 0u) {
    (void)metro_fw_push_rx(&push, data + 1, (uint32_t)(size - 1)); /* raw byte stream */
    return 0;
  }
  /* Structured: [n % 33][op][txn][n payload bytes]... become valid frames (correct CRC-16),
   * so the fuzzer reaches the operations and the update. */
  {
    size_t i = 1;
    while (i + 3 <= size) {
      uint8_t enc[2 * METRO_FW_PUSH_MAX_FRAME + 2];
      uint32_t n = data[i] % (METRO_FW_PUSH_MAX_PAYLOAD + 1u), elen;
      const uint8_t op = data[i + 1], txn = data[i + 2];
      i += 3;
      if (n > size - i) n = (uint32_t)(size - i);
      if (metro_fw_frame_encode(op, txn, data + i, n, enc, sizeof(enc), &elen) != 0) break;
      (void)metro_fw_push_rx(&push, enc, elen);
      i += n;
    }
  }
  return 0;
}
