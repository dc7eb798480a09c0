// The `raw` line format of the calibration station (docs/station.md): one sample per line as
// the Arduino MPU6050 sketches print it,
//
//   ax,ay,az,gx,gy,gz[,t_ms]
//
// six signed integer counts (int16: -32768 .. 32767; accelerometer then gyroscope, the sensor's
// own axes) and an optional seventh field, the tag's clock in milliseconds (Arduino millis(),
// integer or decimal). Fields are separated by commas (spaces or tabs around them allowed); a
// line may end in CR LF. Empty lines and lines starting with '#' are skipped by the reader,
// never by the parser. The counts are what `--format raw` names a[xyz]_lsb and g[xyz]_lsb in a
// session file (docs/formats.md).
//
// A count at either end of the int16 range (-32768 or 32767) is a saturated reading: the
// sensor's output clipped, not a measurement (RawSample::saturated).
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "metro/core/status.hpp"

namespace metro::station {

struct RawSample {
  std::array<int32_t, 3> accel_lsb{};  // ax ay az [LSB]
  std::array<int32_t, 3> gyro_lsb{};   // gx gy gz [LSB]
  std::optional<double> t_ms;          // The tag's clock, when the line has a seventh field.
  bool saturated = false;              // Any count at -32768 or 32767.
  std::string saturated_axis;          // The first saturated field, e.g. "az" (empty if none).
};

// The expected shape, for messages: "ax,ay,az,gx,gy,gz[,t_ms] (six integer counts, e.g.
// -412,83,16390,-12,40,7)".
const char* RawLineShape();

// Parses one line (without its newline; a trailing CR is allowed). Errors name `source`,
// `line_number` and the 1-based column of the offending character, what was found and the
// expected shape: "port:12:9: field 3 (az) "16x90" is not an integer count; expected ...".
Result<RawSample> ParseRawLine(std::string_view line, const std::string& source,
                               int64_t line_number);

// True for a line the reader skips: empty (or only spaces, CR) or a '#' comment.
bool IsSkippedRawLine(std::string_view line);

// The line of a sample as the parser reads it (no t_ms field when t_ms is unset; t_ms with
// up to 3 decimals).
std::string FormatRawLine(const RawSample& sample);

}  // namespace metro::station
