// Private: a bounds-checked little-endian reader over bytes, for the binary log readers
// (mcap.cpp, ros1_bag.cpp, imu_message.cpp). Every read returns false, and reads nothing,
// when the bytes left are too few; bytes are assembled one by one (no casts of the buffer).
#pragma once

#include <cstdint>
#include <cstring>
#include <string_view>

namespace metro::internal {

class LeCursor {
 public:
  explicit LeCursor(std::string_view bytes, size_t pos = 0) : bytes_(bytes), pos_(pos) {}

  size_t pos() const { return pos_; }
  size_t left() const { return pos_ <= bytes_.size() ? bytes_.size() - pos_ : 0; }
  std::string_view bytes() const { return bytes_; }
  void Seek(size_t pos) { pos_ = pos; }

  bool U8(uint8_t* v) { return Load(1, v); }
  bool U16(uint16_t* v) { return Load(2, v); }
  bool U32(uint32_t* v) { return Load(4, v); }
  bool U64(uint64_t* v) { return Load(8, v); }
  bool F64(double* v) {
    uint64_t bits = 0;
    if (!U64(&bits)) return false;
    std::memcpy(v, &bits, 8);
    return true;
  }
  // n raw bytes.
  bool Bytes(uint64_t n, std::string_view* out) {
    if (n > left()) return false;
    *out = bytes_.substr(pos_, static_cast<size_t>(n));
    pos_ += static_cast<size_t>(n);
    return true;
  }
  // A uint32 length, then that many bytes (MCAP strings and byte arrays, ROS 1 fields).
  bool Prefixed32(std::string_view* out) {
    const size_t start = pos_;
    uint32_t n = 0;
    if (!U32(&n) || !Bytes(n, out)) {
      pos_ = start;
      return false;
    }
    return true;
  }
  bool Skip(uint64_t n) {
    if (n > left()) return false;
    pos_ += static_cast<size_t>(n);
    return true;
  }

 private:
  template <typename T>
  bool Load(int n, T* v) {
    if (static_cast<size_t>(n) > left()) return false;
    uint64_t x = 0;
    for (int i = n - 1; i >= 0; --i) {
      x = (x << 8) | static_cast<unsigned char>(bytes_[pos_ + static_cast<size_t>(i)]);
    }
    *v = static_cast<T>(x);
    pos_ += static_cast<size_t>(n);
    return true;
  }

  std::string_view bytes_;
  size_t pos_ = 0;
};

}  // namespace metro::internal
