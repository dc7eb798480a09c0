// PX4 ULog flight logs: a reader of the documented file format (PX4 user guide, "ULog File
// Format"; docs/formats.md "PX4 ULog"), written from that specification.
//
// File layout (all integers little endian, no alignment or padding between fields):
//   header (16 bytes): magic "ULog" 0x01 0x12 0x35, version (uint8), start time (uint64, us)
//   then messages, each: msg_size (uint16, bytes after this 3-byte header), msg_type (uint8),
//   msg_size bytes of body. The definitions ('B' flag bits, 'F' formats, 'I' info, 'M' multi
//   info, 'P' parameters, 'Q' default parameters) come first; the data section follows:
//   'A' subscribe (multi_id uint8, msg_id uint16, topic name), 'R' unsubscribe (msg_id),
//   'D' data (msg_id uint16, then the topic's fields as its 'F' format lays them out, a
//   trailing padding field left out), 'L' log text (level uint8, timestamp uint64, text),
//   'C' tagged log text (level uint8, tag uint16, timestamp uint64, text), 'S' sync
//   (8 magic bytes), 'O' dropout (duration uint16, ms). 'F', 'I', 'M', 'P' may also appear in
//   the data section.
//   'B' (ULog version 1; absent in version 0 files): compat_flags[8], incompat_flags[8],
//   appended_offsets[3] (uint64). incompat_flags[0] bit 0 says that data was appended at the
//   non-zero appended_offsets; any other incompatible bit makes the file unreadable.
//
// Appended data: the messages of the main data section are read up to the first appended
// offset; each appended section is read from its offset to the next one (or the file's
// end). A message the main section's end cuts (a log stopped mid-write before data was
// appended) is counted in `ULog::cut_bytes`, not an error.
//
// Errors name the file and the byte offset of the message (0-based, from the start of the
// file) and what was expected. With `lenient`, a truncated last message and data messages of
// ids never subscribed or of a size their format does not allow are skipped and kept in
// `problems` instead.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "metro/core/status.hpp"

namespace metro {

// One field of an 'F' format: "float[3] gyro_rad" is type "float", array_size 3.
struct ULogField {
  std::string type;         // "float", "uint64_t", ..., or the name of another format (nested).
  std::string name;         // "gyro_rad"; padding fields are named "_padding<N>".
  int array_size = 0;       // 0: a scalar; N: type[N].
  size_t offset_bytes = 0;  // From the start of the message's fields (after the msg_id).
  size_t size_bytes = 0;    // Of the whole field (all elements).
  // Of one element: 1, 2, 4 or 8 for a basic type; the nested format's size otherwise.
  size_t element_size_bytes = 0;
  // 'i' signed integer, 'u' unsigned integer (bool and char too), 'f' float or double;
  // 0 for a nested format.
  char kind = 0;
};

// An 'F' message, with its layout resolved (nested formats expanded into sizes).
struct ULogFormat {
  std::string name;
  std::vector<ULogField> fields;
  size_t size_bytes = 0;  // Sum of the field sizes (trailing padding included).
  // What a 'D' message carries: size_bytes less a trailing padding field ("_padding<N>"),
  // which the logger leaves out.
  size_t logged_size_bytes = 0;
  bool resolved = false;  // Layout computed (done when a subscription first needs it).

  // The field with this name, or nullptr.
  const ULogField* Find(std::string_view field_name) const;
};

// An 'A' message: one instance (multi_id) of a topic, with the messages logged under it.
struct ULogSubscription {
  uint16_t msg_id = 0;
  uint8_t multi_id = 0;
  std::string topic;          // The format's name, e.g. "sensor_combined".
  size_t format_index = 0;    // Into ULog::formats.
  int64_t message_count = 0;  // 'D' messages read.
  // Byte offset of each 'D' message's fields (just after its msg_id) and their size
  // (a trailing padding field may be left out, so it can be below the format's size).
  std::vector<uint64_t> data_offsets;
  std::vector<uint16_t> data_sizes;
  // 1-based index of each 'D' message among all messages of the file (after the header).
  std::vector<uint32_t> message_index;
  // The `timestamp` field of the first and last message [us]; 0 when none.
  uint64_t first_timestamp_us = 0;
  uint64_t last_timestamp_us = 0;
};

struct ULogInfo {
  std::string type;   // As declared: "char[5]", "int32_t", ...
  std::string key;    // "sys_name".
  std::string value;  // Text for char arrays, the number in decimal otherwise.
};

struct ULogReadOptions {
  // Read the complete messages of a truncated file and count the loss, and skip (count)
  // data messages of ids never subscribed, instead of stopping with an error.
  bool lenient = false;
  // Keep the data message offsets of these topics only (empty: all; a list naming no topic
  // of the log: none). Counts are kept for all.
  std::vector<std::string> keep_topics;
};

struct ULog {
  std::string path;
  std::string bytes;  // The whole file; data_offsets index into it.
  int version = 0;    // 0 or 1.
  uint64_t start_time_us = 0;
  uint8_t compat_flags[8] = {};
  uint8_t incompat_flags[8] = {};
  std::vector<uint64_t> appended_offsets;  // The non-zero ones, ascending.
  std::vector<ULogFormat> formats;
  std::vector<ULogSubscription> subscriptions;  // In 'A' order.
  std::vector<ULogInfo> info;                   // 'I' messages.
  int64_t info_multiple_count = 0;              // 'M' messages.
  int64_t parameter_count = 0;                  // 'P' messages.
  int64_t default_parameter_count = 0;          // 'Q' messages.
  int64_t log_message_count = 0;                // 'L' messages.
  int64_t tagged_log_message_count = 0;         // 'C' messages.
  int64_t sync_count = 0;                       // 'S' messages.
  int64_t remove_count = 0;                     // 'R' messages.
  int64_t unknown_message_count = 0;            // Message types the specification lacks.
  int64_t dropout_count = 0;                    // 'O' messages.
  int64_t dropout_total_ms = 0;                 // Sum of their durations.
  int64_t dropout_max_ms = 0;
  int64_t message_count = 0;  // All messages read after the header.
  // Lenient mode: bytes of a truncated last message, and data messages of ids never
  // subscribed, skipped; with the first such problem's text (file: byte offset: what).
  int64_t truncated_bytes = 0;
  int64_t unsubscribed_data_count = 0;
  std::vector<std::string> problems;
  std::vector<int64_t> problem_messages;  // 1-based message index of each problem.
  // Bytes of a message cut by the start of appended data (see the file comment).
  int64_t cut_bytes = 0;

  // The subscriptions of `topic`, ascending multi_id.
  std::vector<const ULogSubscription*> Find(std::string_view topic) const;
  const ULogFormat& FormatOf(const ULogSubscription& s) const { return formats[s.format_index]; }
};

// True when `head` starts with the ULog magic (the first 7 bytes).
bool IsULogMagic(std::string_view head);

// Reads and indexes a ULog file. Errors: "file: byte offset N: what was found; expected".
Result<ULog> ReadULog(const std::string& path, const ULogReadOptions& options = {});

// One element of a field of a data message, as a double (integer types exactly up to 2^53).
// `element` < max(1, field.array_size). The field must be a basic type (not nested) and lie
// within `size`; returns false otherwise (a field in a left-out trailing padding).
// Precondition: `data_offset` and `size` are one of a subscription's data_offsets/sizes.
bool ReadULogValue(const ULog& log, uint64_t data_offset, uint16_t size, const ULogField& field,
                   int element, double* value);
// The same for a uint64 field (timestamps), exact.
bool ReadULogU64(const ULog& log, uint64_t data_offset, uint16_t size, const ULogField& field,
                 uint64_t* value);

// A line of `characterize topics`: one subscription.
struct ULogTopicSummary {
  std::string topic;
  int multi_id = 0;
  int64_t message_count = 0;
  size_t message_size_bytes = 0;  // The format's logged size (ULogFormat::logged_size_bytes).
  // (count - 1) / (last - first timestamp); 0 with fewer than 2 messages or no timestamp
  // span (some topics log a zero or constant timestamp): printed "-".
  double rate_hz = 0.0;
};
std::vector<ULogTopicSummary> SummarizeULogTopics(const ULog& log);
// The table printed by `characterize topics` (a header line, one line per subscription,
// then dropouts, logged text and appended-data lines).
std::string FormatULogTopics(const ULog& log);

}  // namespace metro
