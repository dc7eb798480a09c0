// A RAM model of the tag's two calibration pages for the firmware's loader and update code:
// erased state 0xFF, writes can only clear bits (old & new), as on the nRF51.
#pragma once

#include <cstdint>
#include <cstring>
#include <vector>

#include "metro/blob/blob.hpp"
#include "metro_fw/blob.h"
#include "metro_fw/flash.h"

namespace metro::blob::testing {

struct RamFlash2 {
  std::vector<uint8_t> mem = std::vector<uint8_t>(2 * kPageSize, 0xFF);

  static bool InRange(uint32_t addr, uint32_t len, size_t size) {
    return addr >= kSlotAAddress && addr - kSlotAAddress + len <= size;
  }
  static int Read(void* ctx, uint32_t addr, uint8_t* dst, uint32_t len) {
    auto* self = static_cast<RamFlash2*>(ctx);
    if (!InRange(addr, len, self->mem.size())) return -1;
    std::memcpy(dst, self->mem.data() + (addr - kSlotAAddress), len);
    return 0;
  }
  static int Erase(void* ctx, uint32_t addr) {
    auto* self = static_cast<RamFlash2*>(ctx);
    if (!InRange(addr, kPageSize, self->mem.size())) return -1;
    std::memset(self->mem.data() + (addr - kSlotAAddress), 0xFF, kPageSize);
    return 0;
  }
  static int Write(void* ctx, uint32_t addr, const uint8_t* src, uint32_t len) {
    auto* self = static_cast<RamFlash2*>(ctx);
    if (!InRange(addr, len, self->mem.size())) return -1;
    for (uint32_t i = 0; i < len; ++i) self->mem[addr - kSlotAAddress + i] &= src[i];
    return 0;
  }
  metro_fw_flash Interface() {
    metro_fw_flash f{};
    f.read = &RamFlash2::Read;
    f.erase_page = &RamFlash2::Erase;
    f.write = &RamFlash2::Write;
    f.ctx = this;
    f.slot_addr[0] = kSlotAAddress;
    f.slot_addr[1] = kSlotBAddress;
    return f;
  }
  // Places bytes at slot `slot` (0 = A, 1 = B) as a programmer would.
  void Program(int slot, const std::vector<uint8_t>& bytes) {
    std::memcpy(mem.data() + static_cast<size_t>(slot) * kPageSize, bytes.data(), bytes.size());
  }
};

}  // namespace metro::blob::testing
