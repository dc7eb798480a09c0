// `calibrate inspect`: decode and validate a blob file (.bin) or a programmer image (.hex)
// with the firmware's rules, and render the result for people (text) and programs (JSON).
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "metro/blob/blob.hpp"
#include "metro/core/status.hpp"

namespace metro::blob {

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

  // A .bin is valid when its blob validates; a .hex when some slot is active.
  bool ok() const { return active >= 0; }
};

// Inspects the bytes of a .bin blob (a single slot).
InspectReport InspectBin(const std::vector<uint8_t>& bytes, const InspectOptions& options);

// Inspects the file: Intel HEX if its first non-blank character is ':', else a raw blob.
// Errors: unreadable file, HEX syntax (with line and column), invalid options.
Result<InspectReport> InspectFile(const std::string& path, const InspectOptions& options);

// Human-readable summary, one block per slot.
std::string FormatInspect(const InspectReport& report);

// JSON with unit-suffixed keys, e.g. {"file", "format", "active_slot", "slots": [...]}.
nlohmann::json InspectToJson(const InspectReport& report);

}  // namespace metro::blob
