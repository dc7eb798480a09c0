#include "metro/station/raw_line.hpp"

#include <fast_float/fast_float.h>
#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <vector>

namespace metro::station {

namespace {

constexpr const char* kFieldNames[7] = {"ax", "ay", "az", "gx", "gy", "gz", "t_ms"};

bool IsBlank(char c) { return c == ' ' || c == '\t' || c == '\r'; }

// One comma-separated field: its text without surrounding blanks and its 1-based column.
struct Field {
  std::string_view text;
  int64_t column = 0;
};

}  // namespace

const char* RawLineShape() {
  return "ax,ay,az,gx,gy,gz[,t_ms] (six integer counts, e.g. -412,83,16390,-12,40,7)";
}

bool IsSkippedRawLine(std::string_view line) {
  size_t i = 0;
  while (i < line.size() && IsBlank(line[i])) ++i;
  return i == line.size() || line[i] == '#';
}

Result<RawSample> ParseRawLine(std::string_view line, const std::string& source,
                               int64_t line_number) {
  auto fail = [&](int64_t column, const std::string& what) -> Error {
    return MakeError(source, line_number, column,
                     fmt::format("{}; expected {}", what, RawLineShape()));
  };
  std::vector<Field> fields;
  size_t start = 0;
  for (size_t i = 0; i <= line.size(); ++i) {
    if (i < line.size() && line[i] != ',') continue;
    size_t b = start, e = i;
    while (b < e && IsBlank(line[b])) ++b;
    while (e > b && IsBlank(line[e - 1])) --e;
    fields.push_back({line.substr(b, e - b), static_cast<int64_t>(b) + 1});
    start = i + 1;
    if (fields.size() > 7) {
      return fail(fields.back().column, fmt::format("more than 7 fields (the line has {})",
                                                    std::count(line.begin(), line.end(), ',') + 1));
    }
  }
  if (fields.size() < 6) {
    return fail(static_cast<int64_t>(line.size()) + 1,
                fmt::format("{} field{} where 6 or 7 are expected", fields.size(),
                            fields.size() == 1 ? "" : "s"));
  }
  RawSample s;
  for (size_t f = 0; f < 6; ++f) {
    const Field& fd = fields[f];
    int64_t v = 0;
    const char* first = fd.text.data();
    const char* last = first + fd.text.size();
    if (first != last && *first == '+') ++first;
    const auto [ptr, ec] = std::from_chars(first, last, v);
    if (fd.text.empty() || ec != std::errc() || ptr != last) {
      const int64_t bad =
          fd.text.empty() ? fd.column : fd.column + static_cast<int64_t>(ptr - fd.text.data());
      return fail(bad, fmt::format("field {} ({}) \"{}\" is not an integer count", f + 1,
                                   kFieldNames[f], fd.text));
    }
    if (v < -32768 || v > 32767) {
      return fail(fd.column, fmt::format("field {} ({}) {} is outside the int16 range "
                                         "-32768 .. 32767 of a count",
                                         f + 1, kFieldNames[f], v));
    }
    (f < 3 ? s.accel_lsb[f] : s.gyro_lsb[f - 3]) = static_cast<int32_t>(v);
    if ((v == -32768 || v == 32767) && !s.saturated) {
      s.saturated = true;
      s.saturated_axis = kFieldNames[f];
    }
  }
  if (fields.size() == 7) {
    const Field& fd = fields[6];
    double t = 0;
    const char* first = fd.text.data();
    const char* last = first + fd.text.size();
    const auto r = fast_float::from_chars(first, last, t);
    if (fd.text.empty() || r.ec != std::errc() || r.ptr != last || !std::isfinite(t)) {
      return fail(fd.column,
                  fmt::format("field 7 (t_ms) \"{}\" is not a time in milliseconds", fd.text));
    }
    s.t_ms = t;
  }
  return s;
}

std::string FormatRawLine(const RawSample& s) {
  std::string out = fmt::format("{},{},{},{},{},{}", s.accel_lsb[0], s.accel_lsb[1], s.accel_lsb[2],
                                s.gyro_lsb[0], s.gyro_lsb[1], s.gyro_lsb[2]);
  if (s.t_ms) out += fmt::format(",{:.3f}", *s.t_ms);
  return out;
}

}  // namespace metro::station
