// ArduPilot DataFlash binary logs (.bin), read by metro's own reader written from ArduPilot's
// log format (ArduPilot's libraries/AP_Logger/LogStructure.h and the "Downloading and
// Analyzing Data Logs" wiki; docs/formats.md "ArduPilot DataFlash"):
//   - a log is a sequence of messages, each a 3-byte header (0xA3, 0x95, message type) and
//     its fields, little endian, unaligned, no padding; a message's length is fixed by its
//     type and includes the header;
//   - FMT (type 128, 89 bytes: Type B, Length B, Name char[4], Format char[16], Columns
//     char[64]) defines a type: a format character per field and comma-separated column
//     names. A message of a type no FMT defined before it cannot be sized: an error.
//   - format characters: b B h H i I q Q (int8 .. uint64), f (float), d (double), n N Z
//     (char[4], [16], [64]), a (int16[32]), c C (int16, uint16 * 0.01), e E (int32, uint32 *
//     0.01), L (int32 latitude/longitude * 1e-7), M (uint8 flight mode), g (IEEE half float).
// Errors name the file, the byte offset of the message (0-based) and what was expected. With
// `lenient`, a file cut inside a message keeps the complete messages before it, and bytes
// that are not a message header (a log written over an older one) are skipped to the next
// header; both are counted.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "metro/core/status.hpp"

namespace metro {

// A field of a DataFlash message type.
struct DataFlashField {
  std::string name;       // Its column name, e.g. "GyrX".
  char type = 0;          // Its format character.
  size_t offset = 0;      // Byte offset within the message, header included.
  size_t size_bytes = 0;  // Logged size.
};

// A message type as its FMT message defines it.
struct DataFlashFormat {
  bool defined = false;
  std::string name;         // "IMU".
  std::string format;       // "QffffffIIfBBHH".
  size_t length_bytes = 0;  // Message length, header included.
  std::vector<DataFlashField> fields;
  uint64_t fmt_offset = 0;        // Byte offset of the FMT message.
  int64_t message_count = 0;      // Messages of the type read.
  std::vector<uint64_t> offsets;  // Byte offsets of its messages, when kept,
  std::vector<int64_t> indexes;   // and their 1-based indexes among the file's messages.
  uint64_t first_offset = 0, last_offset = 0;  // Of its first and last message.

  // The field of that column name; null if none.
  const DataFlashField* Find(std::string_view column) const;
};

struct DataFlashReadOptions {
  bool lenient = false;                 // See the file comment.
  std::vector<std::string> keep_names;  // Types whose message offsets are kept.
};

struct DataFlash {
  std::string path;
  std::string bytes;                     // The whole file.
  std::vector<DataFlashFormat> formats;  // Indexed by message type (256).
  int64_t message_count = 0;
  int64_t truncated_bytes = 0;        // Lenient: the bytes of a message cut by the file's end.
  int64_t skipped_bytes = 0;          // Lenient: bytes skipped to the next message header.
  std::vector<std::string> problems;  // Lenient: what was skipped (file: byte offset: what).

  // The type named `name`; null if none.
  const DataFlashFormat* Find(std::string_view name) const;
};

// True when `head` starts with the FMT message that defines FMT itself (A3 95 80 80 59
// "FMT"), as every ArduPilot log does.
bool IsDataFlashMagic(std::string_view head);

Result<DataFlash> ReadDataFlash(const std::string& path, const DataFlashReadOptions& options = {});

// The value of `field` in the message at byte `offset`, scaled as its format character says
// (c C e E: * 0.01, L: * 1e-7); false for a text or array field.
bool ReadDataFlashValue(const DataFlash& log, uint64_t offset, const DataFlashField& field,
                        double* value);
// An integer field's exact value (TimeUS is a uint64); false for other types.
bool ReadDataFlashU64(const DataFlash& log, uint64_t offset, const DataFlashField& field,
                      uint64_t* value);

// The table printed by `characterize topics`: one line per message type with messages (type,
// name, messages, length, rate_hz from its first and last TimeUS, "-" without TimeUS or below
// two messages), then the totals and what was skipped.
std::string FormatDataFlashTopics(const DataFlash& log);

}  // namespace metro
