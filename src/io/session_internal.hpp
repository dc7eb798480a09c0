// Private declarations shared by the session loaders.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "metro/core/status.hpp"
#include "metro/io/session.hpp"
#include "metro/io/session_io.hpp"

namespace metro::internal {

// What a recording read whole into memory (a receiver capture, an imu_tk text file) may
// hold: 4 GiB, the bound of a stream (stdin_input.hpp), above a day of 15 tags' captures.
inline constexpr int64_t kMaxRecordingBytes = int64_t{4} << 30;

// `allow_clean_path` = false forces the general (sequential-distribution) loader; the
// result is the same either way (tests compare the two). `hash`: also sets the session's
// sha256 (hashed on a second thread from the parser's own mapping of the file). `format`:
// kCsv, a named CSV-like format (kEuroc, kRaw, kPhyphox, kSensorLogger), or kAuto to detect
// a named format from the header.
Result<Session> LoadSessionCsv(const std::string& path, const LoadOptions& options,
                               bool allow_clean_path = true, bool hash = false,
                               SessionFormat format = SessionFormat::kAuto);
// How many loads the clean-file path has completed in this process (for tests).
int64_t CleanPathLoads();
Result<Session> LoadReceiverCapture(const std::string& path, const LoadOptions& options);
// A PX4 ULog's IMU topics (options.topics), one tag per topic instance (ulog_session.cpp);
// sets the session's sha256.
Result<Session> LoadULogSession(const std::string& path, const LoadOptions& options);
// An ArduPilot DataFlash log's IMU messages (dataflash_session.cpp).
Result<Session> LoadDataFlashSession(const std::string& path, const LoadOptions& options);
// An MCAP file's or a ROS bag's sensor_msgs/Imu topics (options.topics), one tag per topic
// (ros_session.cpp); sets the session's sha256.
Result<Session> LoadRosSession(const std::string& path, SessionFormat format,
                               const LoadOptions& options);

// Adds a text column to the tag, or, for an unknown column whose every value is a finite
// number, a numeric Quantity with origin kUnknown.
void AddTextOrUnknownColumn(const std::string& name, bool unknown, const std::string& unit,
                            std::vector<std::string> values, Tag* tag);

// Tag::line keeps source lines as uint32_t: the error for a line beyond that, from every
// loader (a file of more than 4,294,967,295 lines, some 40 GB at least).
constexpr int64_t kMaxLineNumber = UINT32_MAX;
// A session read from the copy of a stream (stdin, a FIFO) at copy_path, named display_name:
// the session's path, and an error's file when it is the copy's.
Result<Session> NamedAsStream(Result<Session> session, const std::string& copy_path,
                              const std::string& display_name);

Error TooManyLinesError(const std::string& path, int64_t line);

// The error a loader returns when a session's columns do not fit in memory (it catches
// std::bad_alloc, from any of its threads).
Error OutOfMemoryError(const std::string& path);

// Returns the whole pages inside every column of 1 MB or more to the system, on up to
// `threads` threads (MADV_DONTNEED, Linux; elsewhere nothing). The columns keep their sizes,
// but the values on those pages then read as zeros: for columns about to be destroyed
// (Session::~Session).
void ReturnColumnPages(Session* session, int threads);

}  // namespace metro::internal
