// LoadReceiverCapture runs these stages, in this order:
//
//   session  NewReceiverSession            the session's format, frame period and columns
//   lines    ReadCaptureLines, RejectLine  line by line: a torn first line skipped, each
//            AddDecodedLine                decoded, framed, counted and kept per tag
//   finish   FinishReceiverSession         the tags, or no valid line as an error
#include "metro/io/receiver.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <string>
#include <string_view>

#include "io/session_internal.hpp"
#include "metro/core/file.hpp"

namespace metro {
namespace {

int HexValue(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

float FloatFromLittleEndian(const uint8_t* b) {
  const uint32_t bits = static_cast<uint32_t>(b[0]) | (static_cast<uint32_t>(b[1]) << 8) |
                        (static_cast<uint32_t>(b[2]) << 16) | (static_cast<uint32_t>(b[3]) << 24);
  float f;
  std::memcpy(&f, &bits, sizeof f);
  return f;
}

void FloatToLittleEndian(float f, uint8_t* b) {
  uint32_t bits;
  std::memcpy(&bits, &f, sizeof bits);
  for (int i = 0; i < 4; ++i) b[i] = static_cast<uint8_t>(bits >> (8 * i));
}

// A unit quaternion from the DMP has |q| = 1 to float precision; anything this far off is
// not a quaternion (a garbled or misframed line).
constexpr double kQuaternionNormTolerance = 0.05;

}  // namespace

bool DecodeReceiverLine(std::string_view line, ReceiverLine* out, ReceiverLineProblem* problem) {
  auto fail = [&](int64_t column, std::string message) {
    if (problem != nullptr) *problem = ReceiverLineProblem{column, std::move(message)};
    return false;
  };
  if (line.size() != static_cast<size_t>(kReceiverLineHexChars)) {
    return fail(0, fmt::format("receiver line has {} characters: expected {} hex characters "
                               "(sensor, NewData flag, {} payload bytes)",
                               line.size(), kReceiverLineHexChars, kReceiverPayloadBytes));
  }
  uint8_t bytes[2 + kReceiverPayloadBytes];
  for (size_t i = 0; i < line.size(); i += 2) {
    const int hi = HexValue(line[i]);
    const int lo = HexValue(line[i + 1]);
    if (hi < 0 || lo < 0) {
      const size_t bad = hi < 0 ? i : i + 1;
      const unsigned char c = static_cast<unsigned char>(line[bad]);
      return fail(static_cast<int64_t>(bad) + 1,
                  fmt::format("non-hex character '{}' at column {}: expected 0-9 or a-f",
                              std::isprint(c) ? std::string(1, static_cast<char>(c))
                                              : fmt::format("\\x{:02x}", c),
                              bad + 1));
    }
    bytes[i / 2] = static_cast<uint8_t>(hi * 16 + lo);
  }
  const int sensor = bytes[0];
  const int flag = bytes[1];
  if (sensor == 0) return fail(1, "sensor number 00: expected a tag number 01..ff");
  if (flag != 0x00 && flag != 0x01 && flag != 0xFF) {
    return fail(
        3,
        fmt::format("NewData flag {:02x}: expected 01 (fresh), 00 (stale) or ff (never received)",
                    flag));
  }
  ReceiverLine r;
  r.sensor = sensor;
  r.flag = static_cast<NewDataFlag>(flag);
  if (flag == 0x01) {
    r.q.w = FloatFromLittleEndian(bytes + 2);
    r.q.x = FloatFromLittleEndian(bytes + 6);
    r.q.y = FloatFromLittleEndian(bytes + 10);
    r.q.z = FloatFromLittleEndian(bytes + 14);
    const double norm = std::sqrt(r.q.w * r.q.w + r.q.x * r.q.x + r.q.y * r.q.y + r.q.z * r.q.z);
    if (!std::isfinite(norm) || std::abs(norm - 1.0) > kQuaternionNormTolerance) {
      return fail(
          5, fmt::format("fresh row with quaternion norm {}: expected a unit quaternion (w, x, y, "
                         "z as float32 little-endian in payload bytes 1..16)",
                         norm));
    }
  }
  if (out != nullptr) *out = r;
  return true;
}

void EncodeQuaternion(const Quaternion& q, ReceiverPayload* payload) {
  FloatToLittleEndian(static_cast<float>(q.w), payload->data() + 0);
  FloatToLittleEndian(static_cast<float>(q.x), payload->data() + 4);
  FloatToLittleEndian(static_cast<float>(q.y), payload->data() + 8);
  FloatToLittleEndian(static_cast<float>(q.z), payload->data() + 12);
}

std::string FormatReceiverLine(int sensor, NewDataFlag flag, const ReceiverPayload& payload) {
  std::string line = fmt::format("{:02x}{:02x}", sensor, static_cast<int>(flag));
  for (uint8_t b : payload) line += fmt::format("{:02x}", b);
  return line;
}

namespace {

// ---- LoadReceiverCapture's stages ---------------------------------------------------------

// One tag's observations and the rest of each of its lines (payload_hex).
struct ReceiverTagBuilder {
  Tag tag;
  std::vector<std::string> payload_hex;
};

// The state of the pass over the capture's lines.
struct CaptureState {
  const std::string& path;
  const LoadOptions& options;
  Session session;
  std::map<int, ReceiverTagBuilder> tags;
  int64_t frame = -1;
  int previous_sensor = 256;
  int64_t line_number = 0;
};

Session NewReceiverSession(const std::string& path, const LoadOptions& options) {
  Session session;
  session.path = path;
  session.format = SessionFormat::kReceiver;
  session.frame_period_s = options.frame_period_s;
  session.columns = {"sensor", "new_data", "qw", "qx", "qy", "qz", "payload_hex"};
  return session;
}

// A bad line: an error (strict) or counted and kept aside (lenient).
Status RejectLine(int64_t column, const std::string& message, CaptureState* st) {
  if (!st->options.lenient) return MakeError(st->path, st->line_number, column, message);
  Session& session = st->session;
  ++session.rejected_rows;
  ++session.rows;
  if (session.rejected_lines.size() < st->options.max_rejected_kept) {
    session.rejected_lines.push_back(st->line_number);
    session.rejected_reasons.push_back(message);
  }
  return Status::Ok();
}

// A decoded line into its tag: a new frame when the sensor number does not increase; stale
// and never-sent counted; a fresh one's quaternion and payload kept.
Status AddDecodedLine(const ReceiverLine& decoded, std::string_view line, CaptureState* st) {
  Session& session = st->session;
  const int64_t line_number = st->line_number;
  const int sensor = decoded.sensor;
  const int flag = static_cast<int>(decoded.flag);
  const Quaternion& q = decoded.q;
  // A new frame starts when the sensor number does not increase.
  if (sensor <= st->previous_sensor) ++st->frame;
  st->previous_sensor = sensor;
  ++session.rows;

  ReceiverTagBuilder& b = st->tags[sensor];
  b.tag.sensor = sensor;
  ++b.tag.counts.frames;
  if (flag == 0x00) {
    ++b.tag.counts.stale;
    return Status::Ok();
  }
  if (flag == 0xFF) {
    ++b.tag.counts.never;
    return Status::Ok();
  }
  ++b.tag.counts.fresh;
  if (b.tag.quantities.empty()) {
    for (const char* name : {"qw", "qx", "qy", "qz"}) {
      b.tag.quantities.push_back(Quantity{name, "1", QuantityOrigin::kFile, {}});
    }
  }
  b.tag.t_s.push_back(static_cast<double>(st->frame) * st->options.frame_period_s);
  if (line_number > internal::kMaxLineNumber) {
    return internal::TooManyLinesError(st->path, line_number);
  }
  b.tag.line.push_back(static_cast<uint32_t>(line_number));
  b.tag.quantities[0].values.push_back(q.w);
  b.tag.quantities[1].values.push_back(q.x);
  b.tag.quantities[2].values.push_back(q.y);
  b.tag.quantities[3].values.push_back(q.z);
  std::string extra(line.substr(4 + 2 * 16));
  for (char& c : extra) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  b.payload_hex.push_back(std::move(extra));
  return Status::Ok();
}

// Every line of the capture, in order.
Status ReadCaptureLines(const std::string& text, CaptureState* st) {
  const LoadOptions& options = st->options;
  size_t pos = 0;
  bool seen_line = false;  // A line that is neither blank nor a comment.
  size_t reported = 0;     // Bytes told to options.on_bytes_parsed.
  constexpr size_t kReportBytes = size_t{1} << 20;
  while (pos < text.size()) {
    size_t nl = text.find('\n', pos);
    if (nl == std::string::npos) nl = text.size();
    std::string_view line(text.data() + pos, nl - pos);
    pos = nl + 1;
    if (options.on_bytes_parsed && pos - reported >= kReportBytes) {
      const size_t upto = std::min(pos, text.size());
      options.on_bytes_parsed(static_cast<int64_t>(upto - reported));
      reported = upto;
    }
    ++st->line_number;
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    if (line.empty() || line.front() == '#') continue;
    const bool first_line = !seen_line;
    seen_line = true;
    // A capture starts wherever the serial port was opened, usually mid-line: a first line
    // that is the tail of a receiver line is skipped (even in strict mode), with a note.
    if (first_line && line.size() < static_cast<size_t>(kReceiverLineHexChars) &&
        std::all_of(line.begin(), line.end(), [](char c) { return HexValue(c) >= 0; })) {
      st->session.input.notes.push_back(fmt::format(
          "line {}: {} hex characters, the tail of a receiver line (the port was opened "
          "mid-line): skipped",
          st->line_number, line.size()));
      continue;
    }

    ReceiverLine decoded;
    ReceiverLineProblem problem;
    if (!DecodeReceiverLine(line, &decoded, &problem)) {
      if (problem.column == 0 && first_line) {
        problem.message +=
            "; the first line of a capture may be a terminal program's banner: remove it, or "
            "pass --lenient to skip it";
      }
      if (Status s = RejectLine(problem.column, problem.message, st); !s.ok()) return s;
      continue;
    }
    if (Status s = AddDecodedLine(decoded, line, st); !s.ok()) return s;
  }
  if (options.on_bytes_parsed && reported < text.size()) {
    options.on_bytes_parsed(static_cast<int64_t>(text.size() - reported));
  }
  return Status::Ok();
}

// The tags into the session, or the error of a capture without a valid line.
Status FinishReceiverSession(CaptureState* st) {
  Session& session = st->session;
  const std::string& path = st->path;
  if (session.rows == session.rejected_rows) {
    if (session.rejected_rows > 0) {
      return MakeError(path, 0,
                       fmt::format("no valid receiver lines: all {} were rejected (first: line "
                                   "{}: {})",
                                   session.rejected_rows, session.rejected_lines.front(),
                                   session.rejected_reasons.front()));
    }
    return MakeError(path, 0, "no receiver lines: only blank or comment lines");
  }
  for (auto& [sensor, b] : st->tags) {
    if (!b.tag.t_s.empty()) {
      b.tag.text_columns.push_back(TextColumn{"payload_hex", std::move(b.payload_hex)});
    }
    session.tags.push_back(std::move(b.tag));
  }
  return Status::Ok();
}

}  // namespace

namespace internal {

Result<Session> LoadReceiverCapture(const std::string& path, const LoadOptions& options) {
  auto text_or = ReadFile(path, kMaxRecordingBytes);
  if (!text_or.ok()) return text_or.error();
  const std::string& text = text_or.value();
  if (text.empty()) return MakeError(path, 0, "empty file: expected receiver capture lines");
  CaptureState st{path, options, NewReceiverSession(path, options), {}};
  if (Status s = ReadCaptureLines(text, &st); !s.ok()) return s.error();
  if (Status s = FinishReceiverSession(&st); !s.ok()) return s.error();
  return std::move(st.session);
}

}  // namespace internal
}  // namespace metro
