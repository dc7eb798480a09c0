// `calibrate inspect`: decode and validate a blob file (.bin) or a programmer image (.hex)
// with the firmware's rules, and render the result for people (text) and programs (JSON).
//
// Inspect is the gate before a programmer (docs/calibration-blob.md section 8.1): beyond the
// firmware's validator it refuses a file larger than kMaxInspectFileBytes (checked before it is
// read), a .bin with bytes after total_len, a .hex that writes anything outside the two
// calibration slot pages or leaves a slot page unwritten (no tombstone), bytes after total_len
// or beside the tombstone in a slot page, and a blob whose flags disagree with its sensor
// sections, that holds no sensor section, or whose sensor section the firmware would not use
// (NaN/Inf, limits, model bits).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "metro/blob/blob.hpp"
#include "metro/blob/intel_hex.hpp"
#include "metro/core/status.hpp"

namespace metro::blob {

// The largest file inspect reads. Both slot pages as Intel HEX take about 6 KiB (2048 data
// bytes in 16-byte records of 45 characters, plus 04 and 01 records); a .bin is at most 1024.
inline constexpr uint64_t kMaxInspectFileBytes = 64 * 1024;

struct InspectOptions {
  // The tag's device id; without it each slot is checked against its own id.
  std::optional<uint64_t> device_id;
  // Slot addresses looked up in a .hex image.
  uint32_t slot_a_address = kSlotAAddress;
  uint32_t slot_b_address = kSlotBAddress;

  // Slots page-aligned (multiple of 1024) and distinct.
  bool IsValid(std::string* why) const;
};

struct SensorVerdict {
  std::string name;         // "accel" or "gyro"
  int status = 1;           // firmware enum metro_fw_sensor_status; 1 = ABSENT
  std::string status_name;  // "OK", "ABSENT", "LIMITS", ...
};

struct SlotReport {
  std::string label;      // "file", "A" or "B"
  uint32_t address = 0;   // 0 for a .bin file
  int code = -1;          // firmware validator code, 0 = valid
  std::string code_name;  // "METRO_FW_OK", "METRO_FW_E_CRC", ...
  std::string message;
  std::optional<BlobContents> contents;  // when valid
  std::vector<SensorVerdict> sensors;    // usability on a tag configured as the blob says
};

// Defaults read as failure: no slot and no active slot.
struct InspectReport {
  std::string file;
  std::string format;  // "bin" or "hex"
  std::vector<SlotReport> slots;
  int active = -1;  // index into slots of the slot the firmware would load, -1 = none
  // Why the file must not go to a programmer although the firmware might load it, one line
  // each, naming the address range or byte offsets and what was expected.
  std::vector<std::string> refusals;

  // A .bin is valid when its blob validates; a .hex when some slot is active. Either only
  // when the gate found nothing to refuse.
  bool ok() const { return active >= 0 && refusals.empty(); }
};

// Inspects an Intel HEX image already parsed into segments (ReadIntelHex).
InspectReport InspectHexSegments(const std::vector<HexSegment>& segments,
                                 const InspectOptions& options);

// Inspects the bytes of a .bin blob (a single slot).
InspectReport InspectBin(const std::vector<uint8_t>& bytes, const InspectOptions& options);

// Inspects the file: Intel HEX if its first non-blank character is ':', else a raw blob.
// Errors: unreadable file, a file larger than kMaxInspectFileBytes (refused from its size,
// before it is read), HEX syntax (with line and column), invalid options.
Result<InspectReport> InspectFile(const std::string& path, const InspectOptions& options);

// Human-readable summary, one block per slot.
std::string FormatInspect(const InspectReport& report);

// JSON text with unit-suffixed keys, e.g. {"active_slot", "file", "format", "slots": [...]}
// (2-space indent, keys sorted, no trailing newline): what `calibrate inspect --json` prints.
std::string ToJson(const InspectReport& report);

}  // namespace metro::blob
