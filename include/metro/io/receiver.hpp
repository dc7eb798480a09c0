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
#include <string_view>

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

// One decoded receiver line.
struct ReceiverLine {
  int sensor = 0;  // 1..255
  NewDataFlag flag = NewDataFlag::kNever;
  Quaternion q;  // w, x, y, z from payload bytes 1..16; fresh rows only (else identity).
};

// Why a line is not a receiver line: the 1-based column of the offending character (0 when
// the line as a whole is wrong) and what was expected.
struct ReceiverLineProblem {
  int64_t column = 0;
  std::string message;
};

// Decodes `line` (without its terminator; a trailing CR must already be removed) with the
// receiver loader's rules (docs/formats.md, "Receiver capture"): 54 hex characters, sensor
// 01..ff, NewData 00/01/ff, a fresh row's quaternion norm within 0.05 of 1. Returns false and
// fills `problem` (when not null) for anything else. The capture loader and `characterize
// capture` share it, so a line the capture keeps is a line the loader reads.
bool DecodeReceiverLine(std::string_view line, ReceiverLine* out, ReceiverLineProblem* problem);

}  // namespace metro
