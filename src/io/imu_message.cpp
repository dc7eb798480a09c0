#include "io/imu_message.hpp"

#include <fmt/format.h>

#include <cstring>

#include "io/le_cursor.hpp"

namespace metro::internal {
namespace {

constexpr size_t kDoubles = 4 + 9 + 3 + 9 + 3 + 9;  // After the header, in field order.

// The 37 float64 after the header, from `at` (aligned as the caller requires).
void ReadDoubles(std::string_view data, size_t at, bool big_endian, ImuMessage* m) {
  double* dst[] = {m->orientation_xyzw,         m->orientation_covariance,
                   m->angular_velocity_rads,    m->angular_velocity_covariance,
                   m->linear_acceleration_mps2, m->linear_acceleration_covariance};
  const size_t sizes[] = {4, 9, 3, 9, 3, 9};
  for (size_t f = 0; f < 6; ++f) {
    for (size_t i = 0; i < sizes[f]; ++i, at += 8) {
      uint64_t bits = 0;
      for (int b = 0; b < 8; ++b) {
        const int k = big_endian ? b : 7 - b;
        bits = (bits << 8) | static_cast<unsigned char>(data[at + static_cast<size_t>(k)]);
      }
      std::memcpy(&dst[f][i], &bits, 8);
    }
  }
}

std::string CheckStamp(int64_t sec, uint32_t nsec, ImuMessage* m) {
  if (nsec >= 1000000000u) {
    return fmt::format("header.stamp nanoseconds {}: expected below 1000000000", nsec);
  }
  m->stamp_ns = sec * 1000000000 + static_cast<int64_t>(nsec);
  return "";
}

uint32_t Load32(std::string_view data, size_t at, bool big_endian) {
  uint32_t v = 0;
  for (int b = 0; b < 4; ++b) {
    const int k = big_endian ? b : 3 - b;
    v = (v << 8) | static_cast<unsigned char>(data[at + static_cast<size_t>(k)]);
  }
  return v;
}

}  // namespace

bool IsImuType(std::string_view type) {
  return type == "sensor_msgs/msg/Imu" || type == "sensor_msgs/Imu";
}

std::string DecodeImuCdr(std::string_view data, ImuMessage* m) {
  if (data.size() < 4 + 12) {
    return fmt::format("{} bytes: expected a CDR sensor_msgs/msg/Imu of at least 312", data.size());
  }
  if (data[0] != 0 || (data[1] != 0 && data[1] != 1)) {
    return fmt::format(
        "encapsulation {:02x} {:02x}: expected CDR (00 01 little endian or 00 00 "
        "big endian)",
        static_cast<unsigned char>(data[0]), static_cast<unsigned char>(data[1]));
  }
  const bool be = data[1] == 0;
  const std::string_view body = data.substr(4);  // Alignment counts from here.
  const int32_t sec = static_cast<int32_t>(Load32(body, 0, be));
  const uint32_t nsec = Load32(body, 4, be);
  const uint32_t len = Load32(body, 8, be);
  if (len == 0 || len > body.size() - 12 || body[12 + len - 1] != '\0') {
    return fmt::format(
        "header.frame_id of {} bytes at byte 16: expected a NUL-terminated string "
        "within the message's {} bytes",
        len, data.size());
  }
  size_t at = 12 + len;
  at = (at + 7) / 8 * 8;  // float64 alignment.
  if (at + kDoubles * 8 > body.size()) {
    return fmt::format(
        "{} bytes: expected {} for sensor_msgs/msg/Imu with a {}-byte frame_id "
        "(is the message another type?)",
        data.size(), 4 + at + kDoubles * 8, len - 1);
  }
  ReadDoubles(body, at, be, m);
  return CheckStamp(sec, nsec, m);
}

std::string DecodeImuRos1(std::string_view data, ImuMessage* m) {
  LeCursor c(data);
  uint32_t seq = 0, sec = 0, nsec = 0;
  std::string_view frame;
  if (!c.U32(&seq) || !c.U32(&sec) || !c.U32(&nsec) || !c.Prefixed32(&frame)) {
    return fmt::format("{} bytes: expected a std_msgs/Header (seq, stamp, frame_id) first",
                       data.size());
  }
  if (c.left() < kDoubles * 8) {
    return fmt::format("{} bytes: expected {} for sensor_msgs/Imu with a {}-byte frame_id",
                       data.size(), c.pos() + kDoubles * 8, frame.size());
  }
  ReadDoubles(data, c.pos(), false, m);
  return CheckStamp(sec, nsec, m);
}

}  // namespace metro::internal
