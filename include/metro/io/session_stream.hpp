// Reading a session in groups of rows instead of whole (the streaming mode of long records,
// issue #38 step 2): the file is read once, group by group, and each group's rows are handed
// to the caller and dropped, so the memory held is about one group's, whatever the length.
//
// Every text format the CSV loader reads (session.csv and the named CSV formats) streams; a
// receiver capture, a PX4 ULog and imu_tk's two files do not (an Error names the format).
// Rows are checked as LoadSession checks them (strict or lenient, time order per tag across
// groups); with integer times the session's origin is the first group's earliest time, and a
// tag whose rows start earlier than it is refused (rows not in time order across tags).
// Euler angles are derived per group as LoadSession derives them. `-` (stdin), a FIFO or a
// device is first copied once to a temporary file on disk (LoadSession's cap on stream size
// applies) and streamed from there; the session and its errors keep the name given.
#pragma once

#include <cstddef>
#include <functional>
#include <string>

#include "metro/core/status.hpp"
#include "metro/io/session.hpp"
#include "metro/io/session_io.hpp"

namespace metro {

inline constexpr size_t kDefaultStreamGroupBytes = size_t{8} << 20;

// Calls on_group for each group of rows in file order (its tags hold only that group's rows;
// an Error it returns stops the read and is returned). Returns the session without rows:
// path, sha256 of the whole file, format, dialect, columns, rows and rejected rows.
Result<Session> StreamSession(const std::string& path, const LoadOptions& options,
                              const std::function<Status(Session& group)>& on_group,
                              size_t group_bytes = kDefaultStreamGroupBytes);

}  // namespace metro
