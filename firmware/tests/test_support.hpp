// Test support for metro_fw: a byte-level blob builder written from docs/calibration-blob.md
// (independent of the library's decoder and of the C++ writer), a bitwise CRC-32 (not the
// library's nibble table) and a RAM flash fake with fault injection.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
#include <vector>

#include "metro_fw/blob.h"
#include "metro_fw/flash.h"

namespace fwtest {

constexpr uint32_t kDeviceId[2] = {0x12345678u, 0x9ABCDEF0u};
constexpr double kStandardGravity_mps2 = 9.80665;
constexpr double kPi = 3.14159265358979323846;

// Bitwise CRC-32/ISO-HDLC, one bit per step, straight from the parameter set.
inline uint32_t BitwiseCrc32(const uint8_t* p, size_t n) {
  uint32_t c = 0xFFFFFFFFu;
  for (size_t i = 0; i < n; ++i) {
    c ^= p[i];
    for (int k = 0; k < 8; ++k) c = (c & 1u) ? (c >> 1) ^ 0xEDB88320u : c >> 1;
  }
  return c ^ 0xFFFFFFFFu;
}

inline void Put16(std::vector<uint8_t>& b, size_t off, uint16_t v) {
  b[off] = static_cast<uint8_t>(v);
  b[off + 1] = static_cast<uint8_t>(v >> 8);
}
inline void Put32(std::vector<uint8_t>& b, size_t off, uint32_t v) {
  for (int i = 0; i < 4; ++i) b[off + i] = static_cast<uint8_t>(v >> (8 * i));
}
inline void PutF32(std::vector<uint8_t>& b, size_t off, float f) {
  uint32_t u;
  std::memcpy(&u, &f, 4);
  Put32(b, off, u);
}
inline uint32_t Get32(const std::vector<uint8_t>& b, size_t off) {
  return uint32_t{b[off]} | uint32_t{b[off + 1]} << 8 | uint32_t{b[off + 2]} << 16 |
         uint32_t{b[off + 3]} << 24;
}

// Constants of one sensor section in the units of the spec.
struct Sensor {
  uint8_t fs_sel = 0;
  uint8_t dlpf_cfg = 3;
  uint8_t model_bits = 0x0F;
  float t_ref_c = 25.0f;
  std::array<float, 9> m{};
  std::array<float, 3> b0{}, b1{}, b2{};
  std::array<float, 9> u_m{};
  std::array<float, 3> u_b0{}, u_b1{}, u_b2{};
  float resid_rms = 0.01f;
  float t_valid_min_c = 0.0f;
  float t_valid_max_c = 50.0f;
  std::array<int16_t, 3> hw_offs{};
};

// A plausible accelerometer at fs_sel 0: 1 % scale, small misalignment, biases in counts.
inline Sensor GoodAccel() {
  Sensor s;
  const float k = static_cast<float>(kStandardGravity_mps2 / 16384.0);
  s.m = {1.01f * k, 0.002f * k, -0.001f * k, 0.0f, 0.99f * k, 0.003f * k, 0.0f, 0.0f, 1.005f * k};
  s.b0 = {120.0f, -80.0f, 300.0f};
  s.b1 = {1.5f, -0.5f, 2.0f};
  s.b2 = {0.01f, 0.0f, -0.02f};
  s.u_m = {1e-7f, 1e-8f, 1e-8f, 1e-8f, 1e-7f, 1e-8f, 1e-8f, 1e-8f, 1e-7f};
  s.u_b0 = {2.0f, 2.0f, 3.0f};
  s.u_b1 = {0.1f, 0.1f, 0.1f};
  s.u_b2 = {0.001f, 0.001f, 0.001f};
  return s;
}

// A plausible gyroscope at fs_sel 0 (250 deg/s).
inline Sensor GoodGyro() {
  Sensor s;
  const float k = static_cast<float>(250.0 / 32768.0 * kPi / 180.0);
  s.m = {0.98f * k, 0.01f * k, 0.0f, -0.01f * k, 1.02f * k, 0.0f, 0.0f, 0.005f * k, 1.0f * k};
  s.b0 = {-40.0f, 25.0f, 10.0f};
  s.b1 = {0.3f, -0.2f, 0.1f};
  s.b2 = {0.0f, 0.0f, 0.001f};
  s.u_b0 = {0.5f, 0.5f, 0.5f};
  return s;
}

// The loaded form of a test section, as metro_fw_sensor_decode would fill it for a section
// that passes (no limit checks here: apply tests use it directly).
inline metro_fw_sensor_cal CalOf(const Sensor& s) {
  metro_fw_sensor_cal c{};
  for (int i = 0; i < 9; ++i) c.m[i] = s.m[i];
  for (int i = 0; i < 3; ++i) {
    c.b0[i] = s.b0[i];
    c.b1[i] = s.b1[i];
    c.b2[i] = s.b2[i];
  }
  c.t_ref_c = s.t_ref_c;
  c.t_valid_min_c = s.t_valid_min_c;
  c.t_valid_max_c = s.t_valid_max_c;
  c.model_bits = s.model_bits;
  return c;
}

inline std::vector<uint8_t> SensorBody(const Sensor& s) {
  std::vector<uint8_t> b(176, 0);
  b[0] = s.fs_sel;
  b[1] = s.dlpf_cfg;
  b[2] = s.model_bits;
  PutF32(b, 4, s.t_ref_c);
  for (int i = 0; i < 9; ++i) PutF32(b, 8 + 4 * i, s.m[i]);
  for (int i = 0; i < 3; ++i) {
    PutF32(b, 44 + 4 * i, s.b0[i]);
    PutF32(b, 56 + 4 * i, s.b1[i]);
    PutF32(b, 68 + 4 * i, s.b2[i]);
  }
  for (int i = 0; i < 9; ++i) PutF32(b, 80 + 4 * i, s.u_m[i]);
  for (int i = 0; i < 3; ++i) {
    PutF32(b, 116 + 4 * i, s.u_b0[i]);
    PutF32(b, 128 + 4 * i, s.u_b1[i]);
    PutF32(b, 140 + 4 * i, s.u_b2[i]);
  }
  PutF32(b, 152, s.resid_rms);
  PutF32(b, 156, s.t_valid_min_c);
  PutF32(b, 160, s.t_valid_max_c);
  for (int i = 0; i < 3; ++i) Put16(b, 164 + 2 * i, static_cast<uint16_t>(s.hw_offs[i]));
  return b;
}

struct Section {
  uint16_t type;
  uint16_t version;
  std::vector<uint8_t> body;
};

struct Blob {
  uint32_t magic = METRO_FW_MAGIC;
  uint16_t fmt_major = 1;
  uint16_t fmt_minor = 0;
  uint16_t header_len = 32;
  uint32_t seq = 1;
  uint32_t device_id[2] = {kDeviceId[0], kDeviceId[1]};
  uint32_t flags = 0x07;
  std::vector<Section> sections;
};

inline Blob StandardBlob(uint32_t seq) {
  Blob b;
  b.seq = seq;
  std::vector<uint8_t> meta(128, 0);
  PutF32(meta, 96, 9.80665f);
  b.sections.push_back({METRO_FW_SEC_META, 0x0100, meta});
  b.sections.push_back({METRO_FW_SEC_ACCEL, 0x0100, SensorBody(GoodAccel())});
  b.sections.push_back({METRO_FW_SEC_GYRO, 0x0100, SensorBody(GoodGyro())});
  return b;
}

// Serialises a Blob: header, sections in order, CRC over everything before it.
inline std::vector<uint8_t> Build(const Blob& in) {
  size_t total = in.header_len + 4;
  for (const auto& s : in.sections) total += 8 + s.body.size();
  std::vector<uint8_t> b(total, 0);
  Put32(b, 0, in.magic);
  Put16(b, 4, in.fmt_major);
  Put16(b, 6, in.fmt_minor);
  Put16(b, 8, static_cast<uint16_t>(total));
  Put16(b, 10, in.header_len);
  Put32(b, 12, in.seq);
  Put32(b, 16, in.device_id[0]);
  Put32(b, 20, in.device_id[1]);
  Put32(b, 24, in.flags);
  size_t off = in.header_len;
  for (const auto& s : in.sections) {
    Put16(b, off, s.type);
    Put16(b, off + 2, s.version);
    Put16(b, off + 4, static_cast<uint16_t>(s.body.size()));
    std::copy(s.body.begin(), s.body.end(), b.begin() + static_cast<long>(off + 8));
    off += 8 + s.body.size();
  }
  Put32(b, total - 4, BitwiseCrc32(b.data(), total - 4));
  return b;
}

// Recomputes the CRC word at total_len - 4 after a test edited the bytes.
inline void Reseal(std::vector<uint8_t>& b, size_t total) {
  Put32(b, total - 4, BitwiseCrc32(b.data(), total - 4));
}

inline int Validate(const std::vector<uint8_t>& b, metro_fw_blob_info* info = nullptr,
                    const uint32_t* device_id = kDeviceId) {
  metro_fw_buffer buf{b.data(), static_cast<uint32_t>(b.size())};
  return metro_fw_blob_validate(metro_fw_buffer_read, &buf, static_cast<uint32_t>(b.size()),
                                device_id, info);
}

// RAM flash covering slots A and B with nRF51 semantics (erase to 0xFF, word writes that only
// clear bits) and fault injection. Operations (erase, write) are numbered from 0.
class FakeFlash {
 public:
  enum class Tear { kNothing, kFirstHalf, kSecondHalf };

  FakeFlash() : mem_(2 * METRO_FW_PAGE_SIZE, 0xFF) {}

  metro_fw_flash Interface() {
    metro_fw_flash f{};
    f.read = &FakeFlash::Read;
    f.erase_page = &FakeFlash::Erase;
    f.write = &FakeFlash::Write;
    f.ctx = this;
    f.slot_addr[0] = METRO_FW_SLOT_A_ADDR;
    f.slot_addr[1] = METRO_FW_SLOT_B_ADDR;
    return f;
  }

  // Places bytes directly (the programmer), bypassing the operation counter.
  void Program(uint32_t addr, const std::vector<uint8_t>& bytes) {
    std::memcpy(mem_.data() + (addr - METRO_FW_SLOT_A_ADDR), bytes.data(), bytes.size());
  }
  uint8_t* Slot(int i) { return mem_.data() + i * METRO_FW_PAGE_SIZE; }
  std::vector<uint8_t>& Memory() { return mem_; }
  const std::vector<uint8_t>& Memory() const { return mem_; }

  int ops = 0;       // erase and write calls seen so far
  int fail_at = -1;  // this operation returns an error and changes nothing
  int cut_at = -1;   // power is cut during this operation (torn as `tear`)
  Tear tear = Tear::kNothing;
  bool dead = false;            // after a cut every erase/write fails and changes nothing
  int stuck_byte = -1;          // a write to this slot-A/B offset leaves the byte unchanged
  int lands_but_fails_at = -1;  // this operation does its work but returns an error
  int reads_fail_from = -1;     // every read fails once this many operations were seen

  void Revive() {
    dead = false;
    cut_at = -1;
    fail_at = -1;
  }

 private:
  bool InRange(uint32_t addr, uint32_t len) const {
    return addr >= METRO_FW_SLOT_A_ADDR && addr - METRO_FW_SLOT_A_ADDR + len <= mem_.size();
  }
  // Returns false if the operation must fail; sets `torn` when this is the cut operation.
  bool Begin(bool* torn) {
    const int op = ops++;
    *torn = false;
    if (dead || op == fail_at) return false;
    if (op == cut_at) {
      *torn = true;
      dead = true;
    }
    return true;
  }
  static int Read(void* ctx, uint32_t addr, uint8_t* dst, uint32_t len) {
    auto* self = static_cast<FakeFlash*>(ctx);
    if (!self->InRange(addr, len)) return -1;
    if (self->reads_fail_from >= 0 && self->ops >= self->reads_fail_from) return -1;
    std::memcpy(dst, self->mem_.data() + (addr - METRO_FW_SLOT_A_ADDR), len);
    return 0;
  }
  static int Erase(void* ctx, uint32_t addr) {
    auto* self = static_cast<FakeFlash*>(ctx);
    if (addr % METRO_FW_PAGE_SIZE != 0 || !self->InRange(addr, METRO_FW_PAGE_SIZE)) return -1;
    bool torn;
    if (!self->Begin(&torn)) return -1;
    uint8_t* p = self->mem_.data() + (addr - METRO_FW_SLOT_A_ADDR);
    const uint32_t half = METRO_FW_PAGE_SIZE / 2;
    if (!torn) {
      std::memset(p, 0xFF, METRO_FW_PAGE_SIZE);
      return 0;
    }
    if (self->tear == Tear::kFirstHalf) std::memset(p, 0xFF, half);
    if (self->tear == Tear::kSecondHalf) std::memset(p + half, 0xFF, half);  // magic survives
    return -1;
  }
  static int Write(void* ctx, uint32_t addr, const uint8_t* src, uint32_t len) {
    auto* self = static_cast<FakeFlash*>(ctx);
    if (addr % 4 != 0 || len % 4 != 0 || !self->InRange(addr, len)) return -1;
    bool torn;
    const bool lands_but_fails = self->ops == self->lands_but_fails_at;
    if (!self->Begin(&torn)) return -1;
    uint32_t words = len / 4;
    uint32_t first = 0, last = words;
    if (torn) {
      if (self->tear == Tear::kNothing) return -1;
      // A torn single word (the commit) loses half its bits: bytes 0-1 or 2-3 only.
      if (words == 1) {
        const uint32_t off = addr - METRO_FW_SLOT_A_ADDR;
        const int from = self->tear == Tear::kFirstHalf ? 0 : 2;
        for (int i = from; i < from + 2; ++i) self->mem_[off + i] &= src[i];
        return -1;
      }
      if (self->tear == Tear::kFirstHalf) last = words / 2;
      if (self->tear == Tear::kSecondHalf) first = words / 2;
    }
    for (uint32_t i = first * 4; i < last * 4; ++i) {
      const uint32_t off = addr - METRO_FW_SLOT_A_ADDR + i;
      if (static_cast<int>(off % METRO_FW_PAGE_SIZE) == self->stuck_byte) continue;
      self->mem_[off] &= src[i];
    }
    return torn || lands_but_fails ? -1 : 0;
  }

  std::vector<uint8_t> mem_;
};

inline metro_fw_config Config() {
  metro_fw_config c{};
  c.device_id[0] = kDeviceId[0];
  c.device_id[1] = kDeviceId[1];
  c.accel_fs_sel = 0;
  c.gyro_fs_sel = 0;
  c.dlpf_cfg = 3;
  return c;
}

}  // namespace fwtest
