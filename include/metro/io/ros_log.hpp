// Robotics logs without ROS: MCAP files (ROS 2's default bag storage) and ROS 1 bags, read
// sequentially by metro's own readers written from the published specifications
// (docs/formats.md "ROS bags and MCAP"):
//   - MCAP (mcap.dev/spec, format version 0): magic 89 "MCAP0" 0d 0a; records of
//     opcode (uint8), length (uint64), content; Schema 0x03, Channel 0x04, Message 0x05 and
//     Chunk 0x06 (compression "", "zstd" or "lz4" (LZ4 frame format), uncompressed_crc the
//     CRC-32 of the records it holds, 0 = not computed) are read; the summary section,
//     indexes, attachments and metadata are skipped, so a file without a summary (a
//     recorder killed before it wrote one) reads the same as an indexed one.
//   - ROS 1 bag format 2.0 (wiki.ros.org/Bags/Format/2.0): "#ROSBAG V2.0\n", then records of
//     header_len (uint32), header fields (uint32 len, "name=value"), data_len (uint32), data;
//     bag header op 0x03, chunk 0x05 (compression "none", "bz2" or "lz4" (roslz4: the LZ4
//     frame format)), connection 0x07, message data 0x02; index data 0x04 and chunk info
//     0x06 are skipped. Chunks are read in file order, so a bag without its index (the
//     recorder killed: index_pos 0) reads the same as a closed one.
// All integers little endian. Messages are handed to a visitor in file order, with the
// connection they belong to; their payloads are not decoded here (imu_message decodes
// sensor_msgs/Imu).
//
// Errors name the file, the byte offset of the record (0-based from the file's start; for
// a record inside a chunk, the chunk's offset and the record's offset in its uncompressed
// data) and what was expected. With `lenient`, a file cut inside a record (a recorder
// killed mid-write) keeps the messages of the complete records before the cut and counts
// the lost bytes in `RosLog::truncated_bytes`.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "metro/core/status.hpp"

namespace metro {

// A stream of messages of one type: an MCAP channel, a ROS 1 connection, a rosbag2 topic.
struct RosConnection {
  std::string topic;     // "/imu/data".
  std::string type;      // "sensor_msgs/msg/Imu" (ROS 2), "sensor_msgs/Imu" (ROS 1).
  std::string encoding;  // Of the payload: "cdr" (ROS 2) or "ros1".
  std::string md5sum;    // ROS 1 connections: the message definition's MD5 ("" elsewhere).
  int64_t message_count = 0;
  // Log (receive) times of the first and last message [ns since the Unix epoch]; 0 if none.
  int64_t first_log_time_ns = 0;
  int64_t last_log_time_ns = 0;
};

// One message as the reader hands it over; `data` is valid during the visitor call only.
struct RosMessageView {
  size_t connection = 0;       // Index into RosLog::connections.
  int64_t log_time_ns = 0;     // MCAP log_time, ROS 1 record time, rosbag2 timestamp.
  std::string_view data;       // The serialized message.
  uint64_t record_offset = 0;  // File byte offset of the message's record, or of its chunk.
  int64_t index = 0;           // 1-based index of the message among all messages read.
};

struct RosLogReadOptions {
  bool lenient = false;  // Keep the complete records of a file cut inside a record.
};

struct RosLog {
  std::string path;
  std::string format;   // "MCAP", "ROS 1 bag", "ROS 2 bag (sqlite3)", "ROS 2 bag (MCAP)".
  std::string profile;  // MCAP header profile ("ros2", ...); "" elsewhere.
  std::vector<RosConnection> connections;  // In the order they were first met.
  int64_t message_count = 0;
  int64_t chunk_count = 0;
  // Chunks per compression, e.g. {"zstd", 12}; "none" for uncompressed chunks.
  std::vector<std::pair<std::string, int64_t>> chunk_compressions;
  bool has_summary = false;  // MCAP: a summary section was present. ROS 1: an index.
  // What RosMessageView::record_offset counts in errors: "byte offset" (MCAP, ROS 1), or
  // "messages row id" (rosbag2's sqlite3 storage), with the file it is in.
  std::string offset_name = "byte offset";
  int64_t truncated_bytes = 0;        // Lenient: bytes of a record cut by the file's end.
  std::vector<std::string> problems;  // Lenient: what was skipped (file: byte offset: what).

  // The connections of `topic`.
  std::vector<const RosConnection*> Find(std::string_view topic) const;
};

// Called for each message in file order; a non-ok Status stops the read and is returned.
using RosMessageVisitor = std::function<Status(const RosLog& log, const RosMessageView& m)>;

// True when `head` starts with the MCAP magic (8 bytes) / the ROS 1 bag 2.0 line (13).
bool IsMcapMagic(std::string_view head);
bool IsRosbag1Magic(std::string_view head);

// Reads an MCAP file sequentially; `visit` (may be empty) sees every message.
Result<RosLog> ReadMcap(const std::string& path, const RosLogReadOptions& options,
                        const RosMessageVisitor& visit);
// The same on MCAP bytes held in memory (fuzzing, rosbag2's MCAP storage); `path` names it.
Result<RosLog> ReadMcapBytes(const std::string& path, std::string_view bytes,
                             const RosLogReadOptions& options, const RosMessageVisitor& visit);
// Reads a ROS 1 bag 2.0 sequentially.
Result<RosLog> ReadRosbag1(const std::string& path, const RosLogReadOptions& options,
                           const RosMessageVisitor& visit);
Result<RosLog> ReadRosbag1Bytes(const std::string& path, std::string_view bytes,
                                const RosLogReadOptions& options, const RosMessageVisitor& visit);

// Reads a ROS 2 bag: a bag folder (or its metadata.yaml) whose storage is sqlite3 (.db3
// files: the topics and messages tables of rosbag2_storage_default_plugins) or MCAP (.mcap
// files, read as above), its files in metadata.yaml's relative_file_paths order. A .db3 file
// named directly is read alone. Errors name metadata.yaml with its line, or the storage file.
Result<RosLog> ReadRosbag2(const std::string& path, const RosLogReadOptions& options,
                           const RosMessageVisitor& visit);
// True when `path` is a directory with a metadata.yaml, a file named metadata.yaml, or a file
// starting with SQLite's header "SQLite format 3\0" (a .db3 on its own).
bool IsRosbag2Path(const std::string& path);

// The table printed by `characterize topics`: one line per connection (topic, type,
// messages, rate_hz = (count - 1) / (last - first log time), "-" below 2 messages), then
// the format, chunk and truncation lines.
std::string FormatRosTopics(const RosLog& log);

}  // namespace metro
