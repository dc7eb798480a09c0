// Session: the in-memory form of a logged tag session, whatever file it came from.
//
// A session holds one Tag per sensor number. Each tag has its observation times t_s
// (seconds, strictly increasing), the 1-based source line of every observation, and one
// Quantity per numeric column (values[i] belongs to t_s[i]). Quantities keep the units of
// the file (a column `ax_g` stays in g); nothing is converted on load.
//
// Canonical column names (docs/formats.md) and their units:
//   t_s [s] (required), sensor (tag number, default 1),
//   qw qx qy qz [1] (quaternion, w first),
//   yaw_deg pitch_deg roll_deg [deg] (derived from the quaternion when absent),
//   ax_g ay_g az_g [g] | ax_mps2.. [m/s^2] | ax_lsb.. [LSB],
//   gx_dps gy_dps gz_dps [deg/s] | gx_rads.. [rad/s] | gx_lsb.. [LSB],
//   temp_c [degC], table_rate_dps [deg/s] (empty = unknown, 0 = stopped),
//   table_angle_deg [deg], payload_hex (text: the receiver's 9 undecoded payload bytes).
// Any other column is "unknown": carried through, numeric if every value parses.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace metro {

// kCsv is session.csv in any dialect (docs/formats.md); the named formats are other tools'
// files, read through the same CSV loader with their own column names and units.
enum class SessionFormat {
  kAuto,
  kCsv,
  kReceiver,
  kImuTk,
  kEuroc,         // ASL/EuRoC imu0/data.csv: ns timestamps, rad/s and m/s^2.
  kRaw,           // Arduino-style raw-count prints: ax,ay,az,gx,gy,gz (+ metadata lines).
  kPhyphox,       // phyphox CSV exports ("Time (s)", "Gyroscope x (rad/s)", ...).
  kSensorLogger,  // Sensor Logger per-sensor files: time (epoch ns), seconds_elapsed, z, y, x.
  kPhone,         // Another phone or logger app's CSV whose header spells each sensor axis with its
                  // unit ("Time (s)", "Accel_X (m/s^2)", "accX [g]", "gyroscope_x_rads").
  kULog,          // PX4 ULog flight logs (binary; metro/io/ulog.hpp): IMU topics, one tag each.
  kMcap,          // MCAP files (metro/io/ros_log.hpp): sensor_msgs/msg/Imu topics, one tag each.
  kRosbag1,       // ROS 1 bags 2.0 (metro/io/ros_log.hpp): sensor_msgs/Imu topics.
  kRosbag2,       // ROS 2 bag folders (metadata.yaml; sqlite3 or MCAP storage).
  kDataFlash,     // ArduPilot DataFlash .bin logs (metro/io/dataflash.hpp): IMU, IMU2, IMU3.
};

// The binary logs (ULog, MCAP, ROS bags, DataFlash): no delimiter, line ends or header to report.
bool IsBinaryLogFormat(SessionFormat format);

// "csv", "receiver", "imutk", "euroc", "raw", "phyphox", "sensorlogger", "phone", "ulog",
// "mcap", "rosbag1", "rosbag2", "dataflash" ("auto" for kAuto).
const char* SessionFormatName(SessionFormat format);
// The format with that name; false if none.
bool ParseSessionFormat(std::string_view name, SessionFormat* format);

// A header name mapped to a canonical column name (--column 'SRC=DST').
struct ColumnMapping {
  std::string source;     // As written in the file's header (matched case-insensitively).
  std::string canonical;  // A canonical column name, e.g. gx_dps.
};

// How a text file was read: what the loader detected or was told, so that the report can
// say it and a reload can repeat it. Nothing is guessed silently.
struct InputDialect {
  char delimiter = ',';            // ',', ';' or '\t'.
  char decimal_point = '.';        // ',' only when the delimiter is not a comma.
  std::string line_ends = "LF";    // "LF", "CRLF", "CR".
  bool bom = false;                // A UTF-8 byte-order mark was skipped.
  bool quoted = false;             // Some header field was quoted.
  bool header_in_comment = false;  // The header line started with '#' (EuRoC).
  // The header line (1-based; 0 for input without one: a receiver capture, imu_tk) and the
  // column name each of its fields was given, in field order ("" for a field left out), so
  // that a check made after loading can point at a header cell: file:line:field.
  int64_t header_line = 0;
  std::vector<std::string> header_names;
  // Every header name that is not already canonical, with the name it was given.
  std::vector<ColumnMapping> mapping;
  // Time: the source column and its unit ("s", "ms", "us", "ns"), or "rate" when the
  // times are i / rate_hz (a file without a time column, --rate-hz).
  std::string time_source;
  std::string time_unit = "s";
  double rate_hz = 0.0;
  // Integer time (ms, us, ns): t_s = (t_ns - time_origin_ns) * 1e-9, exact differences.
  bool time_integer = false;
  int64_t time_origin_ns = 0;
  // Resolution of the time column when it was written with fewer digits than its unit
  // (E-notation after a spreadsheet round trip), in seconds; 0 when the unit's own.
  double time_resolution_s = 0.0;
  // Raw counts converted beside themselves at full scale / 32768 per count (0: not).
  double accel_fs_g = 0.0;
  double gyro_fs_dps = 0.0;
  std::vector<std::string> notes;     // E.g. a cut first line skipped.
  std::vector<std::string> warnings;  // Doubtful input the numbers depend on.
};

enum class QuantityOrigin {
  kFile,     // A canonical column read from the file.
  kDerived,  // Computed by metro (Euler angles from the quaternion).
  kUnknown,  // A column metro does not know; carried through as read.
};

struct Quantity {
  std::string name;  // Column name, e.g. "pitch_deg".
  std::string unit;  // "deg", "g", "m/s^2", "LSB", "deg/s", "rad/s", "degC", "s", "1";
                     // for unknown columns the unit implied by the suffix, or "".
  QuantityOrigin origin = QuantityOrigin::kFile;
  std::vector<double> values;  // One per observation. NaN only where an empty field is
                               // allowed (table_rate_dps, table_angle_deg: "unknown").
};

struct TextColumn {
  std::string name;
  std::vector<std::string> values;  // One per observation.
};

// Receiver frame counts for one tag (all zero for session.csv input).
struct FrameCounts {
  int64_t frames = 0;  // Frames in which the tag's row appeared.
  int64_t fresh = 0;   // NewData 01: a new packet; these rows are the observations.
  int64_t stale = 0;   // NewData 00: a repeat of the previous packet; not an observation.
  int64_t never = 0;   // NewData ff: nothing ever received; not an observation.
  // Packet loss ratio (docs/formats.md, "Receiver capture"): frames without a fresh packet
  // (stale + never) / all frames; 1.0 for a tag that never sent one. 0 without frames
  // (session.csv input).
  double PacketLossRatio() const {
    return frames > 0 ? static_cast<double>(stale + never) / static_cast<double>(frames) : 0.0;
  }
};

struct Tag {
  int sensor = 1;
  // The name the input gives this tag's source: a ROS topic ("/imu/data"), a ULog topic
  // instance ("sensor_combined[0]"); empty for files whose tags are numbers. Reports name the
  // tag by it unless a tags file names the sensor (TagRegistry::Name).
  std::string source_name;
  std::vector<double> t_s;  // Observation times [s], strictly increasing.
  // Exact integer times [ns] when the file's time column was integer (t_ms, t_us, t_ns);
  // empty otherwise. Sample periods and gaps come from their differences, never from
  // doubles of epoch nanoseconds. t_s[i] = (t_ns[i] - InputDialect::time_origin_ns) * 1e-9.
  std::vector<int64_t> t_ns;
  std::vector<uint32_t> line;  // 1-based source line of each observation.
  std::vector<Quantity> quantities;
  std::vector<TextColumn> text_columns;
  FrameCounts counts;

  size_t size() const { return t_s.size(); }
  // The quantity with this column name, or nullptr.
  const Quantity* Find(std::string_view name) const;
  Quantity* Find(std::string_view name);
  // Keeps observations [begin, end) of every column (clamped to the size); `counts` are
  // the file's and stay as they are.
  void KeepRows(size_t begin, size_t end);
};

// Adds yaw_deg, pitch_deg, roll_deg (origin kDerived) from qw..qz when the tag has the
// quaternion and none of the three angles, as every loader does (LoadOptions::derive_euler).
// Returns a warning when a quaternion's norm is more than 1 % from 1 (the angles, which do
// not depend on the norm, are still derived), else "".
std::string DeriveEulerIfAbsent(Tag* tag);

struct Session {
  std::string path;    // As given by the user.
  std::string sha256;  // Of the file's bytes (of both files for imu_tk input, "a+b").
  SessionFormat format = SessionFormat::kCsv;
  int64_t rows = 0;                     // Data rows read (receiver: all lines with a tag row).
  int64_t rejected_rows = 0;            // Rows skipped in lenient mode.
  std::vector<int64_t> rejected_lines;  // First few rejected line numbers (lenient mode).
  std::vector<std::string> rejected_reasons;  // Their messages, same order.
  std::vector<std::string> columns;           // Header names in file order.
  std::vector<std::string> unknown_columns;   // Names in `columns` metro does not know.
  double frame_period_s = 0.0;                // Receiver input only.
  InputDialect input;                         // How a text file was read.
  std::vector<Tag> tags;                      // Sorted by sensor number.

  const Tag* FindTag(int sensor) const;

  Session() = default;
  Session(const Session&) = default;
  Session(Session&&) = default;
  Session& operator=(const Session&) = default;
  Session& operator=(Session&&) = default;
  // A session of hundreds of MB returns its column pages to the system on all cores
  // before they are freed: freed the usual way they keep one core busy for tens of
  // milliseconds while the others wait (docs/benchmarks-history.md, "Returning column pages").
  ~Session();
};

}  // namespace metro
