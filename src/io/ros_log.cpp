#include "metro/io/ros_log.hpp"

#include <fmt/format.h>

#include "io/ros_log_internal.hpp"

namespace metro {

std::vector<const RosConnection*> RosLog::Find(std::string_view topic) const {
  std::vector<const RosConnection*> out;
  for (const RosConnection& c : connections) {
    if (c.topic == topic) out.push_back(&c);
  }
  return out;
}

std::string FormatRosTopics(const RosLog& log) {
  std::string out =
      fmt::format("{:<32} {:<34} {:>10} {:>10}\n", "topic", "type", "messages", "rate_hz");
  for (const RosConnection& c : log.connections) {
    const double span_s = static_cast<double>(c.last_log_time_ns - c.first_log_time_ns) * 1e-9;
    const std::string rate =
        c.message_count >= 2 && span_s > 0
            ? fmt::format("{:.2f}", static_cast<double>(c.message_count - 1) / span_s)
            : "-";
    out += fmt::format("{:<32} {:<34} {:>10} {:>10}\n", c.topic, c.type, c.message_count, rate);
  }
  std::string chunks;
  for (const auto& [name, n] : log.chunk_compressions) {
    chunks += fmt::format("{}{} {}", chunks.empty() ? "" : ", ", n, name);
  }
  out += fmt::format("{}{}, {} messages; chunks: {}; {}\n", log.format,
                     log.profile.empty() ? "" : " (profile " + log.profile + ")", log.message_count,
                     chunks.empty() ? "none" : chunks,
                     log.format.find("sqlite3") != std::string::npos ? "sqlite3 storage (no chunks)"
                     : log.has_summary                               ? "indexed"
                                       : "no index or summary (read sequentially)");
  if (log.truncated_bytes > 0) {
    out += fmt::format("truncated: the last {} bytes are an incomplete record (--lenient)\n",
                       log.truncated_bytes);
  }
  return out;
}

namespace internal {

void CountRosMessage(RosLog* log, size_t c, int64_t log_time_ns) {
  RosConnection& conn = log->connections[c];
  if (conn.message_count == 0) conn.first_log_time_ns = log_time_ns;
  conn.last_log_time_ns = log_time_ns;
  ++conn.message_count;
  ++log->message_count;
}

void CountRosChunk(RosLog* log, std::string_view compression) {
  const std::string name = compression.empty() ? "none" : std::string(compression);
  ++log->chunk_count;
  for (auto& [n, count] : log->chunk_compressions) {
    if (n == name) {
      ++count;
      return;
    }
  }
  log->chunk_compressions.emplace_back(name, 1);
}

Error RosError(const std::string& path, uint64_t offset, std::string_view what) {
  return MakeError(path, 0, fmt::format("byte offset {}: {}", offset, what));
}

}  // namespace internal
}  // namespace metro
