// Loading and writing sessions: the canonical session.csv, the central receiver's raw hex
// capture, and imu_tk's two-file text format. Formats are specified in docs/formats.md.
//
// Strict by default: the first malformed row stops the load with an Error naming the file,
// the 1-based line (and field) and what was expected. With `lenient`, malformed rows are
// skipped and counted in Session::rejected_rows (the first few line numbers and messages are
// kept). Structural problems (empty file, header-only, binary data, no t_s column, an
// incomplete axis family) are errors in both modes.
#pragma once

#include <cstdint>
#include <functional>
#include <string>

#include "metro/core/status.hpp"
#include "metro/io/receiver.hpp"
#include "metro/io/session.hpp"

namespace metro {

struct LoadOptions {
  SessionFormat format = SessionFormat::kAuto;  // kAuto: detected from the content.
  bool lenient = false;
  // Receiver frame period: the central's DELTAT = 3281 ticks of its 32768 Hz RTC, i.e.
  // 0.10013 s (exactly 0.100128173828125 s).
  double frame_period_s = kReceiverFramePeriodS;
  bool derive_euler = true;       // Add yaw/pitch/roll_deg from qw..qz when absent.
  int threads = 0;                // Parser threads; 0 = all cores.
  size_t max_rejected_kept = 10;  // How many rejected line numbers to keep.
  // Progress of a load: called with the byte count of each stretch of the file once it is
  // parsed (each byte counted once, even when the CSV loader reads the file a second
  // time), from any parser thread, so it must be thread-safe. The counts add up to the
  // file size when the load succeeds. Unset: no calls. imu_tk files do not report.
  std::function<void(int64_t bytes)> on_bytes_parsed;

  bool IsValid(std::string* why) const;
};

// Detects the format of a file from its first meaningful line.
Result<SessionFormat> DetectSessionFormat(const std::string& path);

// Loads a session.csv or a receiver capture (options.format, or detected).
Result<Session> LoadSession(const std::string& path, const LoadOptions& options = {});

// Loads imu_tk's two files (whitespace-separated `t_s x y z` raw counts, identical
// timestamps) as one tag with ax_lsb..az_lsb and gx_lsb..gz_lsb.
Result<Session> LoadImuTk(const std::string& acc_path, const std::string& gyro_path,
                          const LoadOptions& options = {});

// Frees every tag of `session` (leaving `tags` empty), returning the pages of its columns to
// the system on up to `threads` threads (0 = all cores). For the end of a run on a large
// session: destroyed the usual way, hundreds of MB of columns keep one core busy for tens of
// milliseconds (docs/benchmarks.md, session 9) while the others wait.
void ReleaseSessionSamples(Session* session, int threads = 0);

// Renders a session as canonical session.csv text: t_s, sensor, then every quantity and
// text column in the order of the first tag's columns; rows ordered by time, then sensor.
// Derived columns are written only if `include_derived`.
std::string FormatSessionCsv(const Session& session, bool include_derived = true);

}  // namespace metro
