// The central receiver's serial line (thesis Appendix A, main.c lines 556-572).
//
// Every frame (DELTAT = 3281 ticks of the 32768 Hz RTC = 0.10013 s) the nRF52840 central
// prints one line per tag:
//   printf("%02x%02x", n + 1, NewData);  for m in 1..25: printf("%02x", CursorLine[m]);
// i.e. 54 lower-case hex characters: sensor number (1..15), NewData flag (01 fresh,
// 00 stale repeat, ff never received), then 25 payload bytes. Payload bytes 1..16 are
// the quaternion as four IEEE-754 binary32 values, little-endian, order w, x, y, z; bytes
// 17..25 are further packet fields, kept raw as `payload_hex`. A new frame starts when
// the sensor number does not increase.
#pragma once

#include <array>
#include <cstdint>
#include <string>

#include "metro/core/angles.hpp"

namespace metro {

inline constexpr int kReceiverPayloadBytes = 25;
inline constexpr int kReceiverLineHexChars = 4 + 2 * kReceiverPayloadBytes;  // 54
inline constexpr double kReceiverFramePeriodS = 3281.0 / 32768.0;            // 0.10013 s

enum class NewDataFlag : uint8_t { kStale = 0x00, kFresh = 0x01, kNever = 0xFF };

using ReceiverPayload = std::array<uint8_t, kReceiverPayloadBytes>;

// Puts the quaternion (rounded to binary32) into payload bytes 1..16.
void EncodeQuaternion(const Quaternion& q, ReceiverPayload* payload);

// One receiver line without the line terminator.
std::string FormatReceiverLine(int sensor, NewDataFlag flag, const ReceiverPayload& payload);

}  // namespace metro
