// PX4 ULog reader (metro/io/ulog.hpp), from PX4's "ULog File Format" specification.
#include "metro/io/ulog.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <unordered_map>

#include "io/session_internal.hpp"
#include "metro/core/file.hpp"
#include "metro/core/terminal_text.hpp"

namespace metro {
namespace {

constexpr char kMagic[7] = {'U', 'L', 'o', 'g', '\x01', '\x12', '\x35'};
constexpr uint64_t kHeaderBytes = 16;
constexpr uint64_t kMessageHeaderBytes = 3;  // msg_size (uint16), msg_type (uint8).
constexpr uint64_t kFlagBitsBytes = 40;      // 'B': 8 + 8 flag bytes, 3 uint64 offsets.
constexpr int kMaxNesting = 32;
constexpr size_t kMaxMessageBytes = 65535;

// Explicit little-endian loads (the file's byte order, whatever the host's).
uint64_t LoadLe(const char* p, int bytes) {
  uint64_t v = 0;
  for (int i = bytes - 1; i >= 0; --i) v = (v << 8) | static_cast<unsigned char>(p[i]);
  return v;
}

struct BasicType {
  std::string_view name;
  size_t size;
  char kind;
};
// The specification's "Data types" table.
constexpr BasicType kBasicTypes[] = {
    {"int8_t", 1, 'i'},  {"uint8_t", 1, 'u'},  {"int16_t", 2, 'i'}, {"uint16_t", 2, 'u'},
    {"int32_t", 4, 'i'}, {"uint32_t", 4, 'u'}, {"int64_t", 8, 'i'}, {"uint64_t", 8, 'u'},
    {"float", 4, 'f'},   {"double", 8, 'f'},   {"bool", 1, 'u'},    {"char", 1, 'u'},
};

const BasicType* FindBasicType(std::string_view name) {
  for (const BasicType& t : kBasicTypes) {
    if (t.name == name) return &t;
  }
  return nullptr;
}

Error At(const std::string& path, uint64_t offset, const std::string& what) {
  return MakeError(path, 0, fmt::format("byte offset {}: {}", offset, what));
}

// A message as found in the file.
struct Message {
  uint64_t offset = 0;  // Of its 3-byte header.
  char type = 0;
  const char* body = nullptr;
  uint16_t size = 0;
};

std::string TypeName(char type) {
  if (type >= 0x20 && type < 0x7f) return fmt::format("'{}'", type);
  return fmt::format("0x{:02x}", static_cast<unsigned char>(type));
}

class Reader {
 public:
  Reader(ULog* log, const ULogReadOptions& options) : log_(*log), options_(options) {}

  Status ReadHeader();
  Status ReadFlagBits();
  Status ReadSection(uint64_t begin, uint64_t end, bool last);

 private:
  Status Handle(const Message& m);
  Status Short(const Message& m, size_t needed, const char* layout) const;
  // An error, or with `lenient` a problem kept (of the message with that 1-based index).
  Status Reject(uint64_t offset, const std::string& what, int64_t message_index);
  Status AddFormat(const Message& m);
  Status ResolveFormat(size_t index, int depth, const Message& m);
  Status AddInfo(const Message& m);
  Status Subscribe(const Message& m);
  Status AddData(const Message& m);
  bool Keep(const std::string& topic) const {
    return options_.keep_topics.empty() ||
           std::find(options_.keep_topics.begin(), options_.keep_topics.end(), topic) !=
               options_.keep_topics.end();
  }

  ULog& log_;
  const ULogReadOptions& options_;
  std::unordered_map<std::string, size_t> format_index_;
  std::unordered_map<uint16_t, size_t> active_;  // msg_id -> subscription.
};

Status Reader::ReadHeader() {
  const std::string& b = log_.bytes;
  if (b.size() < kHeaderBytes || std::memcmp(b.data(), kMagic, sizeof(kMagic)) != 0) {
    std::string found;
    for (size_t i = 0; i < std::min<size_t>(b.size(), 7); ++i) {
      found += fmt::format("{}{:02x}", i ? " " : "", static_cast<unsigned char>(b[i]));
    }
    if (b.size() < kHeaderBytes && b.size() >= 7 &&
        std::memcmp(b.data(), kMagic, sizeof(kMagic)) == 0) {
      return At(log_.path, 0,
                fmt::format("a {}-byte file: expected the 16-byte ULog header (magic, version, "
                            "start time)",
                            b.size()));
    }
    return At(log_.path, 0,
              fmt::format("expected the ULog magic 55 4c 6f 67 01 12 35 (\"ULog\" 01 12 35), "
                          "found {}",
                          found.empty() ? "an empty file" : found));
  }
  log_.version = static_cast<unsigned char>(b[7]);
  log_.start_time_us = LoadLe(b.data() + 8, 8);
  if (log_.version > 1) {
    return At(log_.path, 7,
              fmt::format("ULog version {}: expected 0 or 1 (the versions the specification "
                          "defines)",
                          log_.version));
  }
  return Status::Ok();
}

// The 'B' message, when it is the first message, sets where appended data starts.
Status Reader::ReadFlagBits() {
  const std::string& b = log_.bytes;
  if (b.size() < kHeaderBytes + kMessageHeaderBytes || b[kHeaderBytes + 2] != 'B') {
    return Status::Ok();
  }
  const uint16_t size = static_cast<uint16_t>(LoadLe(b.data() + kHeaderBytes, 2));
  if (size < kFlagBitsBytes || kHeaderBytes + kMessageHeaderBytes + size > b.size()) {
    return At(log_.path, kHeaderBytes,
              fmt::format("'B' (flag bits) message of {} bytes ({} in the file): expected at "
                          "least {} (compat_flags[8], incompat_flags[8], appended_offsets[3])",
                          size, b.size() - kHeaderBytes - kMessageHeaderBytes, kFlagBitsBytes));
  }
  const char* body = b.data() + kHeaderBytes + kMessageHeaderBytes;
  std::memcpy(log_.compat_flags, body, 8);
  std::memcpy(log_.incompat_flags, body + 8, 8);
  for (int i = 0; i < 8; ++i) {
    const unsigned unknown = log_.incompat_flags[i] & (i == 0 ? 0xfeu : 0xffu);
    if (unknown != 0) {
      return At(log_.path, kHeaderBytes + kMessageHeaderBytes + 8 + i,
                fmt::format("incompat_flags[{}] = 0x{:02x}: an incompatible flag this reader "
                            "does not know (only incompat_flags[0] bit 0, appended data, is "
                            "defined); the file cannot be read safely",
                            i, log_.incompat_flags[i]));
    }
  }
  if ((log_.incompat_flags[0] & 1u) == 0) return Status::Ok();
  const uint64_t first_data = kHeaderBytes + kMessageHeaderBytes + size;
  for (int i = 0; i < 3; ++i) {
    const uint64_t offset = LoadLe(body + 16 + 8 * i, 8);
    if (offset == 0) continue;
    if (offset < first_data || offset > b.size()) {
      return At(log_.path, kHeaderBytes + kMessageHeaderBytes + 16 + 8 * i,
                fmt::format("appended_offsets[{}] = {}: expected an offset within the data "
                            "({}..{})",
                            i, offset, first_data, b.size()));
    }
    log_.appended_offsets.push_back(offset);
  }
  std::sort(log_.appended_offsets.begin(), log_.appended_offsets.end());
  return Status::Ok();
}

Status Reader::Reject(uint64_t offset, const std::string& what, int64_t message_index) {
  Error e = At(log_.path, offset, what);
  if (!options_.lenient) return e;
  log_.problems.push_back(e.ToString());
  log_.problem_messages.push_back(message_index);
  return Status::Ok();
}

// Reads the messages in [begin, end). A message that runs past `end` is a truncated file
// when `last`, else a message cut by appended data (counted, not an error).
Status Reader::ReadSection(uint64_t begin, uint64_t end, bool last) {
  const char* data = log_.bytes.data();
  uint64_t pos = begin;
  while (pos < end) {
    const uint64_t left = end - pos;
    Message m;
    m.offset = pos;
    if (left >= kMessageHeaderBytes) {
      m.size = static_cast<uint16_t>(LoadLe(data + pos, 2));
      m.type = data[pos + 2];
    }
    if (left < kMessageHeaderBytes || kMessageHeaderBytes + m.size > left) {
      if (!last) {
        log_.cut_bytes += static_cast<int64_t>(left);
        return Status::Ok();
      }
      const std::string what =
          left < kMessageHeaderBytes
              ? fmt::format(
                    "truncated file: {} byte(s) left, expected a 3-byte message header "
                    "(msg_size, msg_type)",
                    left)
              : fmt::format("truncated file: {} message of {} bytes, {} left after its header",
                            TypeName(m.type), m.size, left - kMessageHeaderBytes);
      if (Status s = Reject(pos, what, log_.message_count + 1); !s.ok()) return s;
      log_.truncated_bytes += static_cast<int64_t>(left);
      return Status::Ok();
    }
    m.body = data + pos + kMessageHeaderBytes;
    ++log_.message_count;
    if (log_.message_count > internal::kMaxLineNumber) {
      return At(log_.path, pos, "more than 4,294,967,295 messages: beyond what metro indexes");
    }
    if (Status s = Handle(m); !s.ok()) return s;
    pos += kMessageHeaderBytes + m.size;
  }
  return Status::Ok();
}

Status Reader::Short(const Message& m, size_t needed, const char* layout) const {
  if (m.size >= needed) return Status::Ok();
  return At(log_.path, m.offset,
            fmt::format("{} message of {} bytes: expected at least {} ({})", TypeName(m.type),
                        m.size, needed, layout));
}

Status Reader::Handle(const Message& m) {
  switch (m.type) {
    case 'B':
      if (m.offset != kHeaderBytes) {
        return At(log_.path, m.offset,
                  "'B' (flag bits) message: expected only as the first message, right after "
                  "the 16-byte header");
      }
      return Status::Ok();  // Read by ReadFlagBits.
    case 'F':
      return AddFormat(m);
    case 'I':
      return AddInfo(m);
    case 'M':
      ++log_.info_multiple_count;
      return Short(m, 2, "is_continued, key_len, key, value");
    case 'P':
      ++log_.parameter_count;
      return Short(m, 1, "key_len, key, value");
    case 'Q':
      ++log_.default_parameter_count;
      return Short(m, 2, "default_types, key_len, key, value");
    case 'A':
      return Subscribe(m);
    case 'R':
      ++log_.remove_count;
      if (Status s = Short(m, 2, "msg_id"); !s.ok()) return s;
      active_.erase(static_cast<uint16_t>(LoadLe(m.body, 2)));
      return Status::Ok();
    case 'D':
      return AddData(m);
    case 'L':
      ++log_.log_message_count;
      return Short(m, 9, "log_level, timestamp, message");
    case 'C':
      ++log_.tagged_log_message_count;
      return Short(m, 11, "log_level, tag, timestamp, message");
    case 'S':
      ++log_.sync_count;
      return Status::Ok();
    case 'O': {
      if (Status s = Short(m, 2, "duration in ms"); !s.ok()) return s;
      const int64_t ms = static_cast<int64_t>(LoadLe(m.body, 2));
      ++log_.dropout_count;
      log_.dropout_total_ms += ms;
      log_.dropout_max_ms = std::max(log_.dropout_max_ms, ms);
      return Status::Ok();
    }
    default:
      // The specification lets a reader skip message types it does not know.
      ++log_.unknown_message_count;
      return Status::Ok();
  }
}

// "float[3] gyro_rad" -> type float, array 3, name gyro_rad. `allow_empty`: "char[0] key"
// (an 'I' message with an empty string value) is accepted, as a scalar.
bool ParseField(std::string_view text, ULogField* f, bool allow_empty = false) {
  const size_t space = text.find(' ');
  if (space == std::string_view::npos || space == 0 || space + 1 >= text.size()) return false;
  std::string_view type = text.substr(0, space);
  f->name = std::string(text.substr(space + 1));
  if (f->name.find(' ') != std::string::npos) return false;
  const size_t bracket = type.find('[');
  if (bracket != std::string_view::npos) {
    if (type.back() != ']' || bracket == 0 || bracket + 2 >= type.size()) return false;
    int n = 0;
    for (char c : type.substr(bracket + 1, type.size() - bracket - 2)) {
      if (c < '0' || c > '9' || n > 100000) return false;
      n = n * 10 + (c - '0');
    }
    if (n == 0 && !allow_empty) return false;
    f->array_size = n;
    type = type.substr(0, bracket);
  }
  f->type = std::string(type);
  return true;
}

Status Reader::AddFormat(const Message& m) {
  const std::string_view text(m.body, m.size);
  const size_t colon = text.find(':');
  if (colon == std::string_view::npos || colon == 0) {
    return At(log_.path, m.offset,
              fmt::format("'F' message \"{}\": expected \"name:type field;type field;...\"",
                          EscapeControlChars(text.substr(0, 80))));
  }
  ULogFormat format;
  format.name = std::string(text.substr(0, colon));
  size_t pos = colon + 1;
  while (pos < text.size()) {
    size_t semi = text.find(';', pos);
    if (semi == std::string_view::npos) semi = text.size();
    const std::string_view field_text = text.substr(pos, semi - pos);
    pos = semi + 1;
    if (field_text.empty()) continue;
    ULogField f;
    if (!ParseField(field_text, &f)) {
      return At(log_.path, m.offset,
                fmt::format("'F' message of '{}': field \"{}\": expected \"type name\" or "
                            "\"type[N] name\", e.g. \"float[3] gyro_rad\"",
                            format.name, EscapeControlChars(field_text.substr(0, 80))));
    }
    format.fields.push_back(std::move(f));
  }
  auto [it, added] = format_index_.emplace(format.name, log_.formats.size());
  if (added) {
    log_.formats.push_back(std::move(format));
  } else {
    log_.formats[it->second] = std::move(format);  // A later definition replaces it.
  }
  return Status::Ok();
}

// Sizes and offsets of a format's fields, nested formats resolved first.
Status Reader::ResolveFormat(size_t index, int depth, const Message& m) {
  if (log_.formats[index].resolved) return Status::Ok();
  if (depth > kMaxNesting) {
    return At(log_.path, m.offset,
              fmt::format("format '{}' nests formats more than {} deep (a format that contains "
                          "itself?)",
                          log_.formats[index].name, kMaxNesting));
  }
  size_t offset = 0;
  for (size_t k = 0; k < log_.formats[index].fields.size(); ++k) {
    ULogField& f = log_.formats[index].fields[k];
    if (const BasicType* t = FindBasicType(f.type)) {
      f.element_size_bytes = t->size;
      f.kind = t->kind;
    } else {
      auto it = format_index_.find(f.type);
      if (it == format_index_.end()) {
        return At(log_.path, m.offset,
                  fmt::format("format '{}', field '{} {}': unknown type '{}'; expected int8_t, "
                              "uint8_t, int16_t, uint16_t, int32_t, uint32_t, int64_t, "
                              "uint64_t, float, double, bool, char or a format an 'F' message "
                              "defines",
                              log_.formats[index].name, f.type, f.name, f.type));
      }
      if (Status s = ResolveFormat(it->second, depth + 1, m); !s.ok()) return s;
      f.element_size_bytes = log_.formats[it->second].size_bytes;
    }
    f.offset_bytes = offset;
    f.size_bytes = f.element_size_bytes * static_cast<size_t>(std::max(1, f.array_size));
    offset += f.size_bytes;
    // Every size is bounded by what a message can hold, so nothing below can overflow.
    if (offset > kMaxMessageBytes) {
      return At(log_.path, m.offset,
                fmt::format("format '{}' is more than {} bytes at field '{}': more than a "
                            "message can hold (msg_size is a uint16)",
                            log_.formats[index].name, kMaxMessageBytes, f.name));
    }
  }
  ULogFormat& format = log_.formats[index];
  format.size_bytes = offset;
  format.logged_size_bytes = offset;
  if (!format.fields.empty() && format.fields.back().name.rfind("_padding", 0) == 0) {
    format.logged_size_bytes -= format.fields.back().size_bytes;
  }
  format.resolved = true;
  return Status::Ok();
}

std::string DecodeScalar(const char* p, size_t n, const BasicType& t) {
  if (t.size > n) return "";
  const uint64_t bits = LoadLe(p, static_cast<int>(t.size));
  if (t.kind == 'u') return std::to_string(bits);
  if (t.kind == 'i') {
    const int shift = 64 - 8 * static_cast<int>(t.size);
    return std::to_string(static_cast<int64_t>(bits << shift) >> shift);
  }
  if (t.size == 4) {
    float f;
    const uint32_t b32 = static_cast<uint32_t>(bits);
    std::memcpy(&f, &b32, 4);
    return fmt::format("{}", f);
  }
  double d;
  std::memcpy(&d, &bits, 8);
  return fmt::format("{}", d);
}

Status Reader::AddInfo(const Message& m) {
  if (Status s = Short(m, 1, "key_len, key, value"); !s.ok()) return s;
  const size_t key_len = static_cast<unsigned char>(m.body[0]);
  if (1 + key_len > m.size) {
    return At(
        log_.path, m.offset,
        fmt::format("'I' message of {} bytes: key_len {} runs past its end", m.size, key_len));
  }
  ULogInfo info;
  ULogField f;
  const std::string_view key(m.body + 1, key_len);
  if (!ParseField(key, &f, /*allow_empty=*/true)) {
    return At(log_.path, m.offset,
              fmt::format("'I' message key \"{}\": expected \"type name\", e.g. "
                          "\"char[5] sys_name\"",
                          EscapeControlChars(key)));
  }
  info.type = key.substr(0, key.find(' '));
  info.key = f.name;
  const char* value = m.body + 1 + key_len;
  const size_t value_size = m.size - 1 - key_len;
  const BasicType* t = FindBasicType(f.type);
  if (f.type == "char") {
    info.value.assign(value, value_size);
  } else if (t != nullptr && f.array_size == 0) {
    info.value = DecodeScalar(value, value_size, *t);
  } else {
    info.value = fmt::format("({} bytes)", value_size);
  }
  log_.info.push_back(std::move(info));
  return Status::Ok();
}

Status Reader::Subscribe(const Message& m) {
  if (Status s = Short(m, 4, "multi_id, msg_id, message_name"); !s.ok()) return s;
  ULogSubscription sub;
  sub.multi_id = static_cast<uint8_t>(m.body[0]);
  sub.msg_id = static_cast<uint16_t>(LoadLe(m.body + 1, 2));
  sub.topic.assign(m.body + 3, m.size - 3);
  auto it = format_index_.find(sub.topic);
  if (it == format_index_.end()) {
    return At(log_.path, m.offset,
              fmt::format("'A' message subscribes '{}' (msg_id {}), which no 'F' message "
                          "defines before it",
                          EscapeControlChars(sub.topic), sub.msg_id));
  }
  if (Status s = ResolveFormat(it->second, 0, m); !s.ok()) return s;
  sub.format_index = it->second;
  if (active_.count(sub.msg_id) != 0) {
    return At(log_.path, m.offset,
              fmt::format("'A' message for '{}' reuses msg_id {} of '{}' without an 'R' "
                          "message removing it",
                          sub.topic, sub.msg_id, log_.subscriptions[active_[sub.msg_id]].topic));
  }
  active_[sub.msg_id] = log_.subscriptions.size();
  log_.subscriptions.push_back(std::move(sub));
  return Status::Ok();
}

Status Reader::AddData(const Message& m) {
  if (Status s = Short(m, 2, "msg_id, data"); !s.ok()) return s;
  const uint16_t msg_id = static_cast<uint16_t>(LoadLe(m.body, 2));
  auto it = active_.find(msg_id);
  if (it == active_.end()) {
    ++log_.unsubscribed_data_count;
    return Reject(m.offset,
                  fmt::format("'D' message of msg_id {}, which no 'A' message added (or an 'R' "
                              "message removed): expected the msg_id of a subscribed topic",
                              msg_id),
                  log_.message_count);
  }
  ULogSubscription& sub = log_.subscriptions[it->second];
  const ULogFormat& format = log_.formats[sub.format_index];
  const size_t size = m.size - 2u;
  // A trailing padding field is not logged (the specification), so the data may be shorter.
  const size_t least = format.logged_size_bytes;
  if (size > format.size_bytes || size < least) {
    return Reject(m.offset,
                  fmt::format("'D' message of '{}' (msg_id {}): {} bytes of fields, expected {} "
                              "(its 'F' format{})",
                              sub.topic, msg_id, size, format.size_bytes,
                              least < format.size_bytes
                                  ? fmt::format(", or {} without the trailing padding", least)
                                  : ""),
                  log_.message_count);
  }
  ++sub.message_count;
  const uint64_t data_offset = m.offset + kMessageHeaderBytes + 2;
  if (const ULogField* t = format.Find("timestamp"); t != nullptr) {
    uint64_t us = 0;
    if (ReadULogU64(log_, data_offset, static_cast<uint16_t>(size), *t, &us)) {
      if (sub.message_count == 1) sub.first_timestamp_us = us;
      sub.last_timestamp_us = us;
    }
  }
  if (Keep(sub.topic)) {
    sub.data_offsets.push_back(data_offset);
    sub.data_sizes.push_back(static_cast<uint16_t>(size));
    sub.message_index.push_back(static_cast<uint32_t>(log_.message_count));
  }
  return Status::Ok();
}

}  // namespace

const ULogField* ULogFormat::Find(std::string_view field_name) const {
  for (const ULogField& f : fields) {
    if (f.name == field_name) return &f;
  }
  return nullptr;
}

std::vector<const ULogSubscription*> ULog::Find(std::string_view topic) const {
  std::vector<const ULogSubscription*> out;
  for (const ULogSubscription& s : subscriptions) {
    if (s.topic == topic) out.push_back(&s);
  }
  std::stable_sort(out.begin(), out.end(),
                   [](const ULogSubscription* a, const ULogSubscription* b) {
                     return a->multi_id < b->multi_id;
                   });
  return out;
}

bool IsULogMagic(std::string_view head) {
  return head.size() >= sizeof(kMagic) && std::memcmp(head.data(), kMagic, sizeof(kMagic)) == 0;
}

Result<ULog> ReadULog(const std::string& path, const ULogReadOptions& options) {
  ULog log;
  log.path = path;
  auto bytes = ReadFile(path, internal::kMaxRecordingBytes);
  if (!bytes.ok()) return bytes.error();
  log.bytes = std::move(bytes).value();
  Reader reader(&log, options);
  if (Status s = reader.ReadHeader(); !s.ok()) return s.error();
  if (Status s = reader.ReadFlagBits(); !s.ok()) return s.error();
  // The main data section, then each appended section.
  std::vector<uint64_t> starts = {kHeaderBytes};
  starts.insert(starts.end(), log.appended_offsets.begin(), log.appended_offsets.end());
  for (size_t i = 0; i < starts.size(); ++i) {
    const bool last = i + 1 == starts.size();
    const uint64_t end = last ? log.bytes.size() : starts[i + 1];
    if (Status s = reader.ReadSection(starts[i], end, last); !s.ok()) return s.error();
  }
  return log;
}

bool ReadULogValue(const ULog& log, uint64_t data_offset, uint16_t size, const ULogField& field,
                   int element, double* value) {
  const size_t n = field.element_size_bytes;
  const size_t at = field.offset_bytes + n * static_cast<size_t>(element);
  if (field.kind == 0 || element < 0 || element >= std::max(1, field.array_size) || at + n > size) {
    return false;
  }
  const uint64_t bits = LoadLe(log.bytes.data() + data_offset + at, static_cast<int>(n));
  if (field.kind == 'u') {
    *value = static_cast<double>(bits);
  } else if (field.kind == 'i') {
    const int shift = 64 - 8 * static_cast<int>(n);
    *value = static_cast<double>(static_cast<int64_t>(bits << shift) >> shift);
  } else if (n == 4) {
    float f;
    const uint32_t b32 = static_cast<uint32_t>(bits);
    std::memcpy(&f, &b32, 4);
    *value = f;
  } else {
    std::memcpy(value, &bits, 8);
  }
  return true;
}

bool ReadULogU64(const ULog& log, uint64_t data_offset, uint16_t size, const ULogField& field,
                 uint64_t* value) {
  if (field.kind != 'u' || field.element_size_bytes != 8 || field.array_size != 0 ||
      field.offset_bytes + 8 > size) {
    return false;
  }
  *value = LoadLe(log.bytes.data() + data_offset + field.offset_bytes, 8);
  return true;
}

std::vector<ULogTopicSummary> SummarizeULogTopics(const ULog& log) {
  std::vector<ULogTopicSummary> out;
  for (const ULogSubscription& s : log.subscriptions) {
    ULogTopicSummary t;
    t.topic = s.topic;
    t.multi_id = s.multi_id;
    t.message_count = s.message_count;
    t.message_size_bytes = log.FormatOf(s).logged_size_bytes;
    if (s.message_count >= 2 && s.last_timestamp_us > s.first_timestamp_us) {
      t.rate_hz = static_cast<double>(s.message_count - 1) /
                  (static_cast<double>(s.last_timestamp_us - s.first_timestamp_us) * 1e-6);
    }
    out.push_back(std::move(t));
  }
  std::stable_sort(out.begin(), out.end(),
                   [](const ULogTopicSummary& a, const ULogTopicSummary& b) {
                     return a.topic != b.topic ? a.topic < b.topic : a.multi_id < b.multi_id;
                   });
  return out;
}

std::string FormatULogTopics(const ULog& log) {
  std::string out = fmt::format("{:<40} {:>8} {:>10} {:>10} {:>10}\n", "topic", "multi_id",
                                "messages", "size_bytes", "rate_hz");
  for (const ULogTopicSummary& t : SummarizeULogTopics(log)) {
    const std::string rate = t.rate_hz > 0 ? fmt::format("{:.2f}", t.rate_hz) : "-";
    out += fmt::format("{:<40} {:>8} {:>10} {:>10} {:>10}\n", t.topic, t.multi_id, t.message_count,
                       t.message_size_bytes, rate);
  }
  out += fmt::format(
      "ULog version {}, {} messages; dropouts: {} ({} ms in all, longest {} ms); "
      "logged text: {} ('L') + {} ('C'); appended data sections: {}\n",
      log.version, log.message_count, log.dropout_count, log.dropout_total_ms, log.dropout_max_ms,
      log.log_message_count, log.tagged_log_message_count, log.appended_offsets.size());
  if (log.truncated_bytes > 0) {
    out += fmt::format("truncated: the last {} bytes are an incomplete message (--lenient)\n",
                       log.truncated_bytes);
  }
  return out;
}

}  // namespace metro
