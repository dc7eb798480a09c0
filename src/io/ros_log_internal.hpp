// Private: bookkeeping shared by the ROS log readers (mcap.cpp, ros1_bag.cpp, rosbag2.cpp).
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

#include "metro/io/ros_log.hpp"

namespace metro::internal {

// Counts one message of connection `c` at `log_time_ns` (count, first and last log time,
// RosLog::message_count).
void CountRosMessage(RosLog* log, size_t c, int64_t log_time_ns);
// Counts one chunk under its compression name ("" is counted as "none").
void CountRosChunk(RosLog* log, std::string_view compression);
// "file: byte offset N: what" as an Error.
Error RosError(const std::string& path, uint64_t offset, std::string_view what);

}  // namespace metro::internal

namespace metro::internal {

// The SHA-256 of a ROS 2 bag: of its metadata.yaml and each storage file, joined by '+'
// (a .db3 named alone: its own).
Result<std::string> Rosbag2Digest(const std::string& path);

}  // namespace metro::internal
