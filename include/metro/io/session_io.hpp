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
  bool derive_euler = true;  // Add yaw/pitch/roll_deg from qw..qz when absent.
  // Header names mapped to canonical names (--column 'SRC=DST', --columns-file); they
  // take precedence over the named formats' own mappings.
  std::vector<ColumnMapping> column_map;
  // A file without a time column: observation k of each tag is at t_s = k / rate_hz
  // (--rate-hz). 0: a time column is required (the raw format's "Fs,R" line also sets it).
  double rate_hz = 0.0;
  // Raw counts: full-scale settings that add ax_g.. and gx_dps.. (origin derived) beside
  // the _lsb columns, at fs / 32768 per count. 0: counts only.
  double accel_fs_g = 0.0;
  double gyro_fs_dps = 0.0;
  // ULog input: the topics to read (--topic, repeatable), each instance (multi_id) one tag;
  // "NAME[K]" or "NAME:K" reads instance K only; empty: sensor_combined if the log has it,
  // else sensor_accel and sensor_gyro. Any other format refuses topics.
  // MCAP and ROS bags: topics by name ("/imu/data"), each one tag; empty: the log's one
  // sensor_msgs/Imu topic (several are an error that lists them).
  std::vector<std::string> topics;
  // ROS logs: the sample time, header.stamp (kHeader) or the time the recorder logged the
  // message (kReceive: MCAP log_time, the ROS 1 record time, rosbag2's timestamp).
  enum class RosTime { kHeader, kReceive };
  RosTime ros_time = RosTime::kHeader;
  // ROS logs, PX4 ULog: times out of order are sorted, repeats dropped after the first
  // (both counted in input.notes), or the first one refused with an error (kRefuse).
  enum class TimeOrder { kSort, kRefuse };
  TimeOrder time_order = TimeOrder::kSort;
  int threads = 0;                // Parser threads; 0 = all cores.
  size_t max_rejected_kept = 10;  // How many rejected line numbers to keep.
  // Progress of a load: called with the byte count of each stretch of the file once it is
  // parsed (each byte counted once, even when the CSV loader reads the file a second
  // time), from any parser thread, so it must be thread-safe. The counts add up to the
  // file size when the load succeeds. Unset: no calls. imu_tk files do not report.
  std::function<void(int64_t bytes)> on_bytes_parsed;

  bool IsValid(std::string* why) const;
};

// Detects the format of a file from its first lines: a PX4 ULog by its magic bytes, a
// receiver capture when most of the
// first meaningful lines are receiver lines (a cut first line or a terminal program's banner
// does not defeat it), a named format from its header, session.csv otherwise.
Result<SessionFormat> DetectSessionFormat(const std::string& path);

// "SRC=DST" (the last '=' splits; DST must be a canonical column name).
Result<ColumnMapping> ParseColumnMapping(std::string_view spec);
// A file of SRC=DST lines (blank lines and '#' comments ignored), errors with file:line.
Result<std::vector<ColumnMapping>> LoadColumnMappings(const std::string& path);

// Loads a session.csv or a receiver capture (options.format, or detected).
Result<Session> LoadSession(const std::string& path, const LoadOptions& options = {});

// Loads imu_tk's two files (whitespace-separated `t_s x y z` raw counts, identical
// timestamps) as one tag with ax_lsb..az_lsb and gx_lsb..gz_lsb.
Result<Session> LoadImuTk(const std::string& acc_path, const std::string& gyro_path,
                          const LoadOptions& options = {});

// Renders a session as canonical session.csv text: t_s (t_ns, exact, when every tag has
// integer times), sensor, then every quantity and
// text column in the order of the first tag's columns; rows ordered by time, then sensor.
// Derived columns are written only if `include_derived`.
std::string FormatSessionCsv(const Session& session, bool include_derived = true);

}  // namespace metro
