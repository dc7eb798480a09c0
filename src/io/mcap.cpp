// MCAP reader (metro/io/ros_log.hpp), written from the MCAP specification (mcap.dev/spec):
// the data section is read record by record from the magic on; chunks are decompressed one at
// a time and their records read the same way. The summary section is skipped.
#include <fmt/format.h>

#include <map>
#include <unordered_map>

#include "io/chunk_codecs.hpp"
#include "io/le_cursor.hpp"
#include "io/mapped_file.hpp"
#include "io/ros_log_internal.hpp"
#include "metro/io/ros_log.hpp"

namespace metro {
namespace {

using internal::LeCursor;

constexpr std::string_view kMagic("\x89MCAP0\r\n", 8);
constexpr uint64_t kRecordHeaderBytes = 9;  // opcode (uint8), length (uint64).

enum Opcode : uint8_t {
  kHeader = 0x01,
  kFooter = 0x02,
  kSchema = 0x03,
  kChannel = 0x04,
  kMessage = 0x05,
  kChunk = 0x06,
  kDataEnd = 0x0F,
};

const char* OpName(uint8_t op) {
  static const char* const kNames[] = {
      "invalid",          "Header",     "Footer",        "Schema",         "Channel",
      "Message",          "Chunk",      "Message Index", "Chunk Index",    "Attachment",
      "Attachment Index", "Statistics", "Metadata",      "Metadata Index", "Summary Offset",
      "Data End"};
  return op < 16 ? kNames[op] : "unknown";
}

// Where a record is: at a file offset, or inside the chunk at `chunk` (a file offset) at
// `inner` bytes into its uncompressed records.
struct Place {
  uint64_t at = 0;
  bool in_chunk = false;
  uint64_t chunk = 0;
  std::string Text() const {
    return in_chunk ? fmt::format("{} (the Chunk record's; {} bytes into its records)", chunk, at)
                    : fmt::to_string(at);
  }
  uint64_t FileOffset() const { return in_chunk ? chunk : at; }
};

class McapReader {
 public:
  McapReader(RosLog* log, std::string_view bytes, const RosLogReadOptions& options,
             const RosMessageVisitor& visit)
      : log_(log), bytes_(bytes), options_(options), visit_(visit) {}

  Status Read();

 private:
  Error Fail(const Place& p, std::string_view what) const {
    return MakeError(log_->path, 0, fmt::format("byte offset {}: {}", p.Text(), what));
  }
  Status ReadRecords(std::string_view region, bool in_chunk, uint64_t chunk_offset);
  Status OnRecord(uint8_t op, std::string_view body, const Place& place);
  Status OnSchema(std::string_view body, const Place& place);
  Status OnChannel(std::string_view body, const Place& place);
  Status OnMessage(std::string_view body, const Place& place);
  Status OnChunk(std::string_view body, const Place& place);
  Status Truncated(uint64_t at, uint8_t op, uint64_t length);

  RosLog* log_;
  std::string_view bytes_;
  const RosLogReadOptions& options_;
  const RosMessageVisitor& visit_;
  std::unordered_map<uint16_t, std::string> schemas_;  // id -> name.
  std::unordered_map<uint16_t, size_t> channels_;      // id -> RosLog::connections index.
  std::string chunk_;                                  // The current chunk, uncompressed.
  bool footer_ = false;
  bool data_end_ = false;
};

Status McapReader::Read() {
  if (bytes_.substr(0, kMagic.size()) != kMagic) {
    std::string found;
    for (size_t i = 0; i < std::min<size_t>(8, bytes_.size()); ++i) {
      found += fmt::format("{}{:02x}", i ? " " : "", static_cast<unsigned char>(bytes_[i]));
    }
    return Fail(Place{}, fmt::format("expected the MCAP magic 89 4d 43 41 50 30 0d 0a "
                                     "(0x89 \"MCAP0\" CR LF), found {}",
                                     found.empty() ? "an empty file" : found));
  }
  if (Status s = ReadRecords(bytes_.substr(kMagic.size()), false, 0); !s.ok()) return s;
  if (footer_ || log_->truncated_bytes > 0) return Status::Ok();
  const std::string what = fmt::format(
      "the file ends after {} messages in complete records{} without MCAP's Footer "
      "record and closing magic; expected a complete file (a recording cut short: --lenient "
      "reads its complete records)",
      log_->message_count, data_end_ ? " and its Data End" : "");
  if (!options_.lenient) return Fail(Place{bytes_.size()}, what);
  log_->problems.push_back(fmt::format("{}: byte offset {}: {}", log_->path, bytes_.size(), what));
  return Status::Ok();
}

Status McapReader::Truncated(uint64_t at, uint8_t op, uint64_t length) {
  const uint64_t left = bytes_.size() - at;
  const std::string what = fmt::format(
      "a {} record (opcode 0x{:02x}) of {} bytes runs past the file's end ({} bytes left); "
      "expected a complete record (a file cut short: --lenient reads the complete records "
      "before the cut)",
      OpName(op), op, length, left - std::min<uint64_t>(left, kRecordHeaderBytes));
  if (!options_.lenient) return Fail(Place{at}, what);
  log_->truncated_bytes = static_cast<int64_t>(left);
  log_->problems.push_back(fmt::format("{}: byte offset {}: {}", log_->path, at, what));
  return Status::Ok();
}

// The records of `region` (the data section after the magic, or a chunk's records).
Status McapReader::ReadRecords(std::string_view region, bool in_chunk, uint64_t chunk_offset) {
  const uint64_t base = in_chunk ? 0 : kMagic.size();
  LeCursor c(region);
  while (c.left() > 0 && !footer_) {
    const Place place{base + c.pos(), in_chunk, chunk_offset};
    uint8_t op = 0;
    uint64_t length = 0;
    if (!c.U8(&op) || !c.U64(&length) || length > c.left()) {
      if (!in_chunk) return Truncated(place.at, op, length);
      return Fail(place, fmt::format("a {} record of {} bytes runs past the chunk's records ({} "
                                     "bytes); expected records that fill the chunk exactly",
                                     OpName(op), length, region.size()));
    }
    std::string_view body;
    c.Bytes(length, &body);
    if (in_chunk && op != kSchema && op != kChannel && op != kMessage) {
      return Fail(place, fmt::format("a {} record (opcode 0x{:02x}) inside a chunk; expected "
                                     "Schema, Channel or Message records",
                                     OpName(op), op));
    }
    if (Status s = OnRecord(op, body, place); !s.ok()) return s;
  }
  return Status::Ok();
}

Status McapReader::OnRecord(uint8_t op, std::string_view body, const Place& place) {
  switch (op) {
    case kHeader: {
      LeCursor c(body);
      std::string_view profile;
      if (!c.Prefixed32(&profile)) return Fail(place, "a Header record without its profile");
      log_->profile = std::string(profile);
      return Status::Ok();
    }
    case kFooter: {
      footer_ = true;
      uint64_t summary_start = 0;
      LeCursor c(body);
      log_->has_summary = c.U64(&summary_start) && summary_start != 0;
      return Status::Ok();
    }
    case kSchema:
      return OnSchema(body, place);
    case kChannel:
      return OnChannel(body, place);
    case kMessage:
      return OnMessage(body, place);
    case kChunk:
      return OnChunk(body, place);
    case kDataEnd:
      data_end_ = true;
      return Status::Ok();
    default:  // Indexes, attachments, metadata, statistics, user opcodes: skipped.
      return Status::Ok();
  }
}

Status McapReader::OnSchema(std::string_view body, const Place& place) {
  LeCursor c(body);
  uint16_t id = 0;
  std::string_view name, encoding, data;
  if (!c.U16(&id) || !c.Prefixed32(&name) || !c.Prefixed32(&encoding) || !c.Prefixed32(&data)) {
    return Fail(place,
                "a Schema record cut short; expected id (uint16), name, encoding and "
                "data (uint32 length-prefixed)");
  }
  if (id == 0)
    return Fail(place,
                "a Schema record with id 0; expected an id from 1 (0 means "
                "\"no schema\")");
  schemas_.emplace(id, std::string(name));
  return Status::Ok();
}

Status McapReader::OnChannel(std::string_view body, const Place& place) {
  LeCursor c(body);
  uint16_t id = 0, schema_id = 0;
  std::string_view topic, encoding;
  if (!c.U16(&id) || !c.U16(&schema_id) || !c.Prefixed32(&topic) || !c.Prefixed32(&encoding)) {
    return Fail(place,
                "a Channel record cut short; expected id, schema_id (uint16), topic "
                "and message_encoding (uint32 length-prefixed)");
  }
  if (channels_.count(id) != 0) return Status::Ok();  // Repeated in the summary.
  auto schema = schemas_.find(schema_id);
  if (schema_id != 0 && schema == schemas_.end()) {
    return Fail(place, fmt::format("Channel {} ({}) names schema {}, which no Schema record "
                                   "before it defines; expected the schema first",
                                   id, topic, schema_id));
  }
  RosConnection conn;
  conn.topic = std::string(topic);
  conn.type = schema_id == 0 ? "" : schema->second;
  conn.encoding = std::string(encoding);
  channels_.emplace(id, log_->connections.size());
  log_->connections.push_back(std::move(conn));
  return Status::Ok();
}

Status McapReader::OnMessage(std::string_view body, const Place& place) {
  LeCursor c(body);
  uint16_t channel = 0;
  uint32_t sequence = 0;
  uint64_t log_time = 0, publish_time = 0;
  if (!c.U16(&channel) || !c.U32(&sequence) || !c.U64(&log_time) || !c.U64(&publish_time)) {
    return Fail(place,
                "a Message record cut short; expected channel_id (uint16), sequence "
                "(uint32), log_time and publish_time (uint64), data");
  }
  auto it = channels_.find(channel);
  if (it == channels_.end()) {
    return Fail(place, fmt::format("a Message of channel {}, which no Channel record before it "
                                   "defines; expected the channel first",
                                   channel));
  }
  if (log_time > static_cast<uint64_t>(INT64_MAX)) {
    return Fail(place, fmt::format("log_time {} ns: expected at most 2^63 - 1", log_time));
  }
  internal::CountRosMessage(log_, it->second, static_cast<int64_t>(log_time));
  if (!visit_) return Status::Ok();
  RosMessageView m;
  m.connection = it->second;
  m.log_time_ns = static_cast<int64_t>(log_time);
  m.data = body.substr(c.pos());
  m.record_offset = place.FileOffset();
  m.index = log_->message_count;
  return visit_(*log_, m);
}

Status McapReader::OnChunk(std::string_view body, const Place& place) {
  LeCursor c(body);
  uint64_t start = 0, end = 0, size = 0, records_length = 0;
  uint32_t crc = 0;
  std::string_view compression, records;
  if (!c.U64(&start) || !c.U64(&end) || !c.U64(&size) || !c.U32(&crc) ||
      !c.Prefixed32(&compression) || !c.U64(&records_length) ||
      !c.Bytes(records_length, &records)) {
    return Fail(place,
                "a Chunk record cut short; expected message start and end times, "
                "uncompressed size (uint64), CRC (uint32), compression, records");
  }
  std::string why;
  std::string_view plain = records;
  if (compression == "zstd") {
    why = internal::DecompressZstd(records, size, &chunk_);
    plain = chunk_;
  } else if (compression == "lz4") {
    why = internal::DecompressLz4Frame(records, size, &chunk_);
    plain = chunk_;
  } else if (!compression.empty()) {
    why = fmt::format("compression \"{}\": expected \"\" (none), \"zstd\" or \"lz4\"", compression);
  } else if (size != records.size()) {
    why = fmt::format("uncompressed chunk of {} bytes whose header says {}", records.size(), size);
  }
  if (why.empty() && crc != 0 && internal::Crc32(plain) != crc) {
    why = fmt::format(
        "the chunk's records have CRC-32 {:08x}; its header says {:08x} (a corrupt "
        "chunk)",
        internal::Crc32(plain), crc);
  }
  if (!why.empty()) return Fail(place, "Chunk: " + why);
  internal::CountRosChunk(log_, compression);
  return ReadRecords(plain, true, place.at);
}

}  // namespace

bool IsMcapMagic(std::string_view head) { return head.substr(0, kMagic.size()) == kMagic; }

Result<RosLog> ReadMcapBytes(const std::string& path, std::string_view bytes,
                             const RosLogReadOptions& options, const RosMessageVisitor& visit) {
  RosLog log;
  log.path = path;
  log.format = "MCAP";
  McapReader reader(&log, bytes, options, visit);
  if (Status s = reader.Read(); !s.ok()) return s.error();
  return log;
}

Result<RosLog> ReadMcap(const std::string& path, const RosLogReadOptions& options,
                        const RosMessageVisitor& visit) {
  internal::MappedFile file;
  if (Status s = file.Open(path); !s.ok()) return s.error();
  auto log = ReadMcapBytes(path, std::string_view(file.data(), file.size()), options, visit);
  if (std::string changed = file.ChangedSinceOpen(); !changed.empty()) {
    return MakeError(path, 0, changed);
  }
  return log;
}

}  // namespace metro
