#include "metro/io/dataflash.hpp"

#include <fmt/format.h>

#include <cmath>
#include <cstring>

#include "io/session_internal.hpp"
#include "metro/core/file.hpp"
#include "metro/core/terminal_text.hpp"

namespace metro {
namespace {

constexpr unsigned char kHead0 = 0xA3, kHead1 = 0x95;
constexpr int kFmtType = 128;
constexpr size_t kFmtLength = 89;
constexpr size_t kHeaderBytes = 3;

// Logged size of a format character; 0 if unknown.
size_t SizeOf(char c) {
  switch (c) {
    case 'b':
    case 'B':
    case 'M':
      return 1;
    case 'h':
    case 'H':
    case 'c':
    case 'C':
    case 'g':
      return 2;
    case 'i':
    case 'I':
    case 'f':
    case 'e':
    case 'E':
    case 'L':
    case 'n':
      return 4;
    case 'q':
    case 'Q':
    case 'd':
      return 8;
    case 'N':
      return 16;
    case 'Z':
    case 'a':
      return 64;
    default:
      return 0;
  }
}

uint64_t Le(const char* p, size_t n) {
  uint64_t x = 0;
  for (size_t i = n; i-- > 0;) x = (x << 8) | static_cast<unsigned char>(p[i]);
  return x;
}

// A NUL-padded text field.
std::string Text(const char* p, size_t n) {
  size_t len = 0;
  while (len < n && p[len] != '\0') ++len;
  return std::string(p, len);
}

// IEEE 754 binary16 -> double.
double Half(uint16_t h) {
  const int exponent = (h >> 10) & 0x1f;
  const double mantissa = h & 0x3ff;
  const double sign = (h & 0x8000) ? -1.0 : 1.0;
  if (exponent == 0) return sign * std::ldexp(mantissa, -24);
  if (exponent == 31) return mantissa == 0 ? sign * INFINITY : NAN;
  return sign * std::ldexp(mantissa + 1024.0, exponent - 25);
}

class Reader {
 public:
  Reader(DataFlash* log, const DataFlashReadOptions& options) : log_(log), options_(options) {}
  Status Read();

 private:
  Status Fail(uint64_t at, const std::string& what) const {
    return MakeError(log_->path, 0, fmt::format("byte offset {}: {}", at, what));
  }
  Status ReadFmt(uint64_t at);
  Status Resync(uint64_t* at, const std::string& what);

  DataFlash* log_;
  const DataFlashReadOptions& options_;
};

// The FMT message at `at` defines a type: its fields laid out from the format string.
Status Reader::ReadFmt(uint64_t at) {
  const char* p = log_->bytes.data() + at + kHeaderBytes;
  const int type = static_cast<unsigned char>(p[0]);
  DataFlashFormat f;
  f.defined = true;
  f.fmt_offset = at;
  f.length_bytes = static_cast<unsigned char>(p[1]);
  f.name = Text(p + 2, 4);
  f.format = Text(p + 6, 16);
  const std::string columns = Text(p + 22, 64);
  std::vector<std::string> names;
  for (size_t start = 0; start <= columns.size();) {
    const size_t comma = std::min(columns.find(',', start), columns.size());
    names.push_back(columns.substr(start, comma - start));
    start = comma + 1;
  }
  const std::string what = fmt::format("FMT of type {} '{}' (format \"{}\", columns \"{}\")", type,
                                       EscapeControlChars(f.name), EscapeControlChars(f.format),
                                       EscapeControlChars(columns));
  if (names.size() != f.format.size()) {
    return Fail(at, fmt::format("{}: {} format characters but {} column names; expected one "
                                "name per character",
                                what, f.format.size(), names.size()));
  }
  size_t offset = kHeaderBytes;
  for (size_t k = 0; k < f.format.size(); ++k) {
    const size_t size = SizeOf(f.format[k]);
    if (size == 0) {
      return Fail(at, fmt::format("{}: unknown format character '{}'; expected one of b B h H i "
                                  "I q Q f d n N Z a c C e E L M g",
                                  what, EscapeControlChars(std::string(1, f.format[k]))));
    }
    f.fields.push_back(DataFlashField{names[k], f.format[k], offset, size});
    offset += size;
  }
  if (offset != f.length_bytes) {
    return Fail(at, fmt::format("{}: Length {} bytes, but its fields and the 3-byte header "
                                "add up to {}; expected equal",
                                what, f.length_bytes, offset));
  }
  if (type == kFmtType && offset != kFmtLength) {
    return Fail(at, fmt::format("{}: expected FMT's own 89-byte layout", what));
  }
  DataFlashFormat& slot = log_->formats[static_cast<size_t>(type)];
  f.message_count = slot.message_count;  // A type defined again keeps its count.
  f.offsets = std::move(slot.offsets);
  f.indexes = std::move(slot.indexes);
  f.first_offset = slot.first_offset;
  f.last_offset = slot.last_offset;
  slot = std::move(f);
  return Status::Ok();
}

// Strict: the error. Lenient: skips to the next message header and counts the bytes.
Status Reader::Resync(uint64_t* at, const std::string& what) {
  if (!options_.lenient) return Fail(*at, what + " (--lenient skips to the next message)");
  const std::string_view b = log_->bytes;
  size_t next = *at + 1;
  while (next + 1 < b.size() && !(static_cast<unsigned char>(b[next]) == kHead0 &&
                                  static_cast<unsigned char>(b[next + 1]) == kHead1)) {
    ++next;
  }
  if (next + 1 >= b.size()) next = b.size();
  log_->skipped_bytes += static_cast<int64_t>(next - *at);
  log_->problems.push_back(
      fmt::format("{}: byte offset {}: {}; {} bytes skipped", log_->path, *at, what, next - *at));
  *at = next;
  return Status::Ok();
}

Status Reader::Read() {
  log_->formats.assign(256, DataFlashFormat{});
  DataFlashFormat& fmt_format = log_->formats[kFmtType];
  fmt_format.defined = true;
  fmt_format.name = "FMT";
  fmt_format.length_bytes = kFmtLength;
  const std::string_view b = log_->bytes;
  uint64_t at = 0;
  while (at < b.size()) {
    const uint64_t left = b.size() - at;
    if (left < kHeaderBytes || static_cast<unsigned char>(b[at]) != kHead0 ||
        static_cast<unsigned char>(b[at + 1]) != kHead1) {
      if (left < kHeaderBytes && options_.lenient) {
        log_->truncated_bytes = static_cast<int64_t>(left);
        break;
      }
      const std::string found =
          left < 2 ? "the file's end"
                   : fmt::format("{:02x} {:02x}", static_cast<unsigned char>(b[at]),
                                 static_cast<unsigned char>(b[at + 1]));
      if (Status s = Resync(&at, "expected a message header a3 95, found " + found); !s.ok()) {
        return s;
      }
      continue;
    }
    const int type = static_cast<unsigned char>(b[at + 2]);
    DataFlashFormat& f = log_->formats[static_cast<size_t>(type)];
    if (!f.defined) {
      if (Status s = Resync(&at, fmt::format("a message of type {}, which no FMT message before "
                                             "it defines; expected a defined type",
                                             type));
          !s.ok()) {
        return s;
      }
      continue;
    }
    if (f.length_bytes > left) {
      if (options_.lenient) {
        log_->truncated_bytes = static_cast<int64_t>(left);
        break;
      }
      return Fail(at, fmt::format("truncated file: a message of type {} ({}) of {} bytes, {} left; "
                                  "expected a complete message (--lenient reads the messages "
                                  "before it)",
                                  type, EscapeControlChars(f.name), f.length_bytes, left));
    }
    const size_t length = f.length_bytes;
    if (f.message_count == 0) f.first_offset = at;
    f.last_offset = at;
    ++f.message_count;
    ++log_->message_count;
    for (const std::string& keep : options_.keep_names) {
      if (keep != f.name) continue;
      f.offsets.push_back(at);
      f.indexes.push_back(log_->message_count);
    }
    if (type == kFmtType) {
      if (Status s = ReadFmt(at); !s.ok()) return s;
    }
    at += length;
  }
  return Status::Ok();
}

}  // namespace

const DataFlashField* DataFlashFormat::Find(std::string_view column) const {
  for (const DataFlashField& f : fields) {
    if (f.name == column) return &f;
  }
  return nullptr;
}

const DataFlashFormat* DataFlash::Find(std::string_view name) const {
  for (const DataFlashFormat& f : formats) {
    if (f.defined && f.name == name) return &f;
  }
  return nullptr;
}

bool IsDataFlashMagic(std::string_view head) {
  static constexpr char kMagic[] =
      "\xA3\x95\x80\x80\x59"
      "FMT";
  return head.size() >= 8 && std::memcmp(head.data(), kMagic, 8) == 0;
}

Result<DataFlash> ReadDataFlash(const std::string& path, const DataFlashReadOptions& options) {
  DataFlash log;
  log.path = path;
  auto bytes = ReadFile(path, internal::kMaxRecordingBytes);
  if (!bytes.ok()) return bytes.error();
  log.bytes = std::move(bytes).value();
  if (!IsDataFlashMagic(log.bytes)) {
    std::string found;
    for (size_t i = 0; i < std::min<size_t>(8, log.bytes.size()); ++i) {
      found += fmt::format("{}{:02x}", i == 0 ? "" : " ", static_cast<unsigned char>(log.bytes[i]));
    }
    return MakeError(path, 0,
                     fmt::format("byte offset 0: expected an ArduPilot DataFlash log's first "
                                 "message, the FMT that defines FMT: a3 95 80 80 59 46 4d 54 "
                                 "(header, type 128, length 89, \"FMT\"), found {}",
                                 found.empty() ? "an empty file" : found));
  }
  Reader reader(&log, options);
  if (Status s = reader.Read(); !s.ok()) return s.error();
  return log;
}

bool ReadDataFlashU64(const DataFlash& log, uint64_t offset, const DataFlashField& field,
                      uint64_t* value) {
  if (std::string_view("bBhHiIqQM").find(field.type) == std::string_view::npos ||
      offset + field.offset + field.size_bytes > log.bytes.size()) {
    return false;
  }
  *value = Le(log.bytes.data() + offset + field.offset, field.size_bytes);
  return true;
}

bool ReadDataFlashValue(const DataFlash& log, uint64_t offset, const DataFlashField& field,
                        double* value) {
  if (offset + field.offset + field.size_bytes > log.bytes.size()) return false;
  const char* p = log.bytes.data() + offset + field.offset;
  const uint64_t x = Le(p, field.size_bytes);
  const int n = static_cast<int>(field.size_bytes) * 8;
  // Two's complement of an n-bit field.
  const auto s = [&] {
    return n == 64 ? static_cast<int64_t>(x) : static_cast<int64_t>(x << (64 - n)) >> (64 - n);
  };
  switch (field.type) {
    case 'b':
    case 'h':
    case 'i':
    case 'q':
      *value = static_cast<double>(s());
      return true;
    case 'B':
    case 'H':
    case 'I':
    case 'Q':
    case 'M':
      *value = static_cast<double>(x);
      return true;
    case 'c':
    case 'e':
      *value = static_cast<double>(s()) * 0.01;
      return true;
    case 'C':
    case 'E':
      *value = static_cast<double>(x) * 0.01;
      return true;
    case 'L':
      *value = static_cast<double>(s()) * 1e-7;
      return true;
    case 'g':
      *value = Half(static_cast<uint16_t>(x));
      return true;
    case 'f': {
      float f;
      const uint32_t bits = static_cast<uint32_t>(x);
      std::memcpy(&f, &bits, 4);
      *value = f;
      return true;
    }
    case 'd':
      std::memcpy(value, &x, 8);
      return true;
    default:
      return false;
  }
}

std::string FormatDataFlashTopics(const DataFlash& log) {
  std::string out = fmt::format("{:<6} {:<5} {:>10} {:>12} {:>10}\n", "type", "name", "messages",
                                "length_bytes", "rate_hz");
  for (size_t type = 0; type < log.formats.size(); ++type) {
    const DataFlashFormat& f = log.formats[type];
    if (!f.defined || f.message_count == 0) continue;
    std::string rate = "-";
    const DataFlashField* t = f.Find("TimeUS");
    uint64_t first = 0, last = 0;
    if (t != nullptr && f.message_count > 1 && ReadDataFlashU64(log, f.first_offset, *t, &first) &&
        ReadDataFlashU64(log, f.last_offset, *t, &last) && last > first) {
      rate = fmt::format("{:.2f}", static_cast<double>(f.message_count - 1) /
                                       (static_cast<double>(last - first) * 1e-6));
    }
    out += fmt::format("{:<6} {:<5} {:>10} {:>12} {:>10}\n", type, EscapeControlChars(f.name),
                       f.message_count, f.length_bytes, rate);
  }
  out += fmt::format("ArduPilot DataFlash, {} messages", log.message_count);
  if (log.truncated_bytes > 0) {
    out += fmt::format("; truncated: the last {} bytes are an incomplete message",
                       log.truncated_bytes);
  }
  if (log.skipped_bytes > 0) out += fmt::format("; {} bytes skipped", log.skipped_bytes);
  return out + "\n";
}
}  // namespace metro
