// ROS 1 bag 2.0 reader (metro/io/ros_log.hpp), written from the format's description
// (wiki.ros.org/Bags/Format/2.0): records read in file order from the version line on;
// chunks decompressed one at a time and their records read the same way. The index
// (index data, chunk info and the connection records after index_pos) is not needed.
#include <fmt/format.h>

#include <unordered_map>

#include "io/chunk_codecs.hpp"
#include "io/le_cursor.hpp"
#include "io/mapped_file.hpp"
#include "io/ros_log_internal.hpp"
#include "metro/io/ros_log.hpp"

namespace metro {
namespace {

using internal::LeCursor;

constexpr std::string_view kMagic = "#ROSBAG V2.0\n";

enum Op : uint8_t {
  kMessageData = 0x02,
  kBagHeader = 0x03,
  kIndexData = 0x04,
  kChunk = 0x05,
  kChunkInfo = 0x06,
  kConnection = 0x07,
};

// The "name=value" fields of a record header (or of a connection header).
struct Fields {
  std::vector<std::pair<std::string_view, std::string_view>> items;
  const std::string_view* Find(std::string_view name) const {
    for (const auto& [n, v] : items) {
      if (n == name) return &v;
    }
    return nullptr;
  }
};

// "" or what is wrong.
std::string ParseFields(std::string_view bytes, Fields* out) {
  LeCursor c(bytes);
  while (c.left() > 0) {
    std::string_view field;
    if (!c.Prefixed32(&field)) {
      return fmt::format("a header field's length runs past the header's {} bytes", bytes.size());
    }
    const size_t eq = field.find('=');
    if (eq == std::string_view::npos) {
      return fmt::format("header field \"{}\" without '='; expected name=value",
                         field.substr(0, 32));
    }
    out->items.emplace_back(field.substr(0, eq), field.substr(eq + 1));
  }
  return "";
}

// A fixed-size little-endian field of the header; false when absent or of another size.
bool FieldU(const Fields& f, std::string_view name, int bytes, uint64_t* v) {
  const std::string_view* s = f.Find(name);
  if (s == nullptr || s->size() != static_cast<size_t>(bytes)) return false;
  LeCursor c(*s);
  if (bytes == 1) {
    uint8_t x = 0;
    c.U8(&x);
    *v = x;
  } else if (bytes == 4) {
    uint32_t x = 0;
    c.U32(&x);
    *v = x;
  } else {
    c.U64(v);
  }
  return true;
}

class BagReader {
 public:
  BagReader(RosLog* log, std::string_view bytes, const RosLogReadOptions& options,
            const RosMessageVisitor& visit)
      : log_(log), bytes_(bytes), options_(options), visit_(visit) {}

  Status Read();

 private:
  Error Fail(uint64_t at, std::string_view what) const {
    return MakeError(log_->path, 0, fmt::format("byte offset {}: {}", at, what));
  }
  // In a chunk, `at` is the offset in its records and `chunk` the chunk record's offset.
  Error FailIn(uint64_t chunk, uint64_t at, std::string_view what) const {
    return Fail(chunk, fmt::format("(the chunk record's; {} bytes into its records) {}", at, what));
  }
  Status ReadRecords(std::string_view region, bool in_chunk, uint64_t chunk_offset);
  Status OnRecord(uint8_t op, const Fields& header, std::string_view data, uint64_t at,
                  bool in_chunk, uint64_t chunk_offset);
  Status OnConnection(const Fields& header, std::string_view data, std::string* why);
  Status OnMessage(const Fields& header, std::string_view data, uint64_t offset, std::string* why);
  Status OnChunk(const Fields& header, std::string_view data, uint64_t at);

  RosLog* log_;
  std::string_view bytes_;
  const RosLogReadOptions& options_;
  const RosMessageVisitor& visit_;
  std::unordered_map<uint32_t, size_t> connections_;  // conn id -> RosLog::connections index.
  std::string chunk_;
};

Status BagReader::Read() {
  if (bytes_.substr(0, kMagic.size()) != kMagic) {
    const std::string_view line = bytes_.substr(0, std::min(bytes_.find('\n'), size_t{16}));
    return Fail(
        0, fmt::format("expected the ROS bag version line \"#ROSBAG V2.0\", found \"{}\"{}", line,
                       line.substr(0, 9) == "#ROSBAG V" ? " (metro reads format 2.0)" : ""));
  }
  return ReadRecords(bytes_.substr(kMagic.size()), false, 0);
}

Status BagReader::ReadRecords(std::string_view region, bool in_chunk, uint64_t chunk_offset) {
  const uint64_t base = in_chunk ? 0 : kMagic.size();
  LeCursor c(region);
  while (c.left() > 0) {
    const uint64_t at = base + c.pos();
    std::string_view header_bytes, data;
    if (!c.Prefixed32(&header_bytes) || !c.Prefixed32(&data)) {
      const std::string what = fmt::format(
          "a record runs past the {}'s end ({} bytes left); expected header_len, header, "
          "data_len, data{}",
          in_chunk ? "chunk" : "file", region.size() - (at - base),
          in_chunk ? ""
                   : " (a bag cut short: --lenient reads the complete records before the cut)");
      if (in_chunk) return FailIn(chunk_offset, at, what);
      if (!options_.lenient) return Fail(at, what);
      log_->truncated_bytes = static_cast<int64_t>(region.size() - (at - base));
      log_->problems.push_back(fmt::format("{}: byte offset {}: {}", log_->path, at, what));
      return Status::Ok();
    }
    Fields header;
    uint64_t op = 0;
    std::string why = ParseFields(header_bytes, &header);
    if (why.empty() && !FieldU(header, "op", 1, &op)) why = "a record header without op";
    if (!why.empty()) return in_chunk ? FailIn(chunk_offset, at, why) : Fail(at, why);
    Status s = OnRecord(static_cast<uint8_t>(op), header, data, at, in_chunk, chunk_offset);
    if (!s.ok()) return s;
  }
  return Status::Ok();
}

Status BagReader::OnRecord(uint8_t op, const Fields& header, std::string_view data, uint64_t at,
                           bool in_chunk, uint64_t chunk_offset) {
  std::string why;
  Status s = Status::Ok();
  switch (op) {
    case kBagHeader: {
      uint64_t index_pos = 0;
      if (!FieldU(header, "index_pos", 8, &index_pos)) why = "a bag header without index_pos";
      log_->has_summary = index_pos != 0;
      break;
    }
    case kChunk:
      if (in_chunk) {
        why = "a chunk inside a chunk";
        break;
      }
      return OnChunk(header, data, at);
    case kConnection:
      s = OnConnection(header, data, &why);
      break;
    case kMessageData:
      s = OnMessage(header, data, in_chunk ? chunk_offset : at, &why);
      break;
    case kIndexData:
    case kChunkInfo:
      break;
    default:
      why = fmt::format(
          "record op 0x{:02x}: expected 0x02 (message data), 0x03 (bag header), "
          "0x04 (index data), 0x05 (chunk), 0x06 (chunk info) or 0x07 "
          "(connection)",
          op);
  }
  if (!s.ok()) return s;
  if (why.empty()) return Status::Ok();
  return in_chunk ? FailIn(chunk_offset, at, why) : Fail(at, why);
}

Status BagReader::OnConnection(const Fields& header, std::string_view data, std::string* why) {
  uint64_t id = 0;
  const std::string_view* topic = header.Find("topic");
  if (!FieldU(header, "conn", 4, &id) || topic == nullptr) {
    *why = "a connection record without conn (uint32) or topic";
    return Status::Ok();
  }
  if (connections_.count(static_cast<uint32_t>(id)) != 0) return Status::Ok();  // The index's.
  Fields fields;
  if (std::string w = ParseFields(data, &fields); !w.empty()) {
    *why = "connection header: " + w;
    return Status::Ok();
  }
  RosConnection conn;
  conn.topic = std::string(*topic);
  conn.encoding = "ros1";
  if (const std::string_view* type = fields.Find("type")) conn.type = std::string(*type);
  if (const std::string_view* md5 = fields.Find("md5sum")) conn.md5sum = std::string(*md5);
  connections_.emplace(static_cast<uint32_t>(id), log_->connections.size());
  log_->connections.push_back(std::move(conn));
  return Status::Ok();
}

Status BagReader::OnMessage(const Fields& header, std::string_view data, uint64_t offset,
                            std::string* why) {
  uint64_t id = 0, time = 0;
  if (!FieldU(header, "conn", 4, &id) || !FieldU(header, "time", 8, &time)) {
    *why = "a message data record without conn (uint32) or time (uint64)";
    return Status::Ok();
  }
  auto it = connections_.find(static_cast<uint32_t>(id));
  if (it == connections_.end()) {
    *why = fmt::format(
        "a message of connection {}, which no connection record before it "
        "defines; expected the connection first",
        id);
    return Status::Ok();
  }
  // time: uint32 sec, then uint32 nsec.
  const uint64_t sec = time & 0xffffffffu, nsec = time >> 32;
  if (nsec >= 1000000000u) {
    *why = fmt::format("message time nanoseconds {}: expected below 1000000000", nsec);
    return Status::Ok();
  }
  const int64_t t_ns = static_cast<int64_t>(sec) * 1000000000 + static_cast<int64_t>(nsec);
  internal::CountRosMessage(log_, it->second, t_ns);
  if (!visit_) return Status::Ok();
  RosMessageView m;
  m.connection = it->second;
  m.log_time_ns = t_ns;
  m.data = data;
  m.record_offset = offset;
  m.index = log_->message_count;
  return visit_(*log_, m);
}

Status BagReader::OnChunk(const Fields& header, std::string_view data, uint64_t at) {
  const std::string_view* compression = header.Find("compression");
  uint64_t size = 0;
  if (compression == nullptr || !FieldU(header, "size", 4, &size)) {
    return Fail(at, "a chunk record without compression or size (uint32)");
  }
  std::string why;
  std::string_view plain = data;
  if (*compression == "bz2") {
    why = internal::DecompressBz2(data, size, &chunk_);
    plain = chunk_;
  } else if (*compression == "lz4") {
    why = internal::DecompressLz4Frame(data, size, &chunk_);
    plain = chunk_;
  } else if (*compression != "none") {
    why = fmt::format("compression \"{}\": expected \"none\", \"bz2\" or \"lz4\"", *compression);
  } else if (size != data.size()) {
    why = fmt::format("uncompressed chunk of {} bytes whose header says {}", data.size(), size);
  }
  if (!why.empty()) return Fail(at, "chunk: " + why);
  internal::CountRosChunk(log_, *compression);
  return ReadRecords(plain, true, at);
}

}  // namespace

bool IsRosbag1Magic(std::string_view head) { return head.substr(0, kMagic.size()) == kMagic; }

Result<RosLog> ReadRosbag1Bytes(const std::string& path, std::string_view bytes,
                                const RosLogReadOptions& options, const RosMessageVisitor& visit) {
  RosLog log;
  log.path = path;
  log.format = "ROS 1 bag";
  BagReader reader(&log, bytes, options, visit);
  if (Status s = reader.Read(); !s.ok()) return s.error();
  return log;
}

Result<RosLog> ReadRosbag1(const std::string& path, const RosLogReadOptions& options,
                           const RosMessageVisitor& visit) {
  internal::MappedFile file;
  if (Status s = file.Open(path); !s.ok()) return s.error();
  auto log = ReadRosbag1Bytes(path, std::string_view(file.data(), file.size()), options, visit);
  if (std::string changed = file.ChangedSinceOpen(); !changed.empty()) {
    return MakeError(path, 0, changed);
  }
  return log;
}

}  // namespace metro
