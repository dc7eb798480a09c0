// Private: how a CSV-like file is read (its dialect) and what its columns are (the plan),
// decided once from the file's first lines, before any data row is parsed.
//
// Stages, in order (docs/formats.md, "session.csv dialect"):
//   1. DetectDialect: byte-order mark, line ends (LF, CRLF, CR), delimiter (',' ';' tab)
//      and decimal comma, from the first 64 kB;
//   2. FindHeader: the header line, after comments and blank lines, after a raw logger's
//      metadata lines, or inside the '#' comment right before the first data row (EuRoC);
//   3. PlanColumns: every header name to a canonical column name (the user's --column
//      mapping, then the named format's own names, then the name itself case-insensitively),
//      the time column and its unit; an unknown non-canonical name is an error that proposes
//      the mapping;
//   4. FindDataEnd: a spreadsheet's footer (empty rows ",,,," and a text line at the end) is
//      left out, with a note.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "io/mapped_file.hpp"
#include "metro/core/status.hpp"
#include "metro/io/columns.hpp"
#include "metro/io/session.hpp"
#include "metro/io/session_io.hpp"

namespace metro::internal {

// Columns a session file may have (docs/formats.md, "Limits"): far more than any IMU log,
// and few enough that a report's per-quantity work stays fast.
inline constexpr size_t kMaxSessionColumns = 10000;

struct HeaderLine {
  size_t line_begin = 0;
  size_t data_begin = 0;  // Offset just after the header line.
  int64_t line_number = 0;
  std::string text;            // Without the line end (and the leading '#' of a comment header).
  int64_t metadata_lines = 0;  // Raw format: "key,value" lines before the header.
};

struct ColumnPlan {
  InputDialect dialect;
  SessionFormat format = SessionFormat::kCsv;  // kCsv or the named format applied.
  std::vector<std::string> source_names;       // As in the header (unquoted, trimmed).
  std::vector<std::string> names;              // Canonical names ("" for an ignored column).
  std::vector<ColumnInfo> info;
  int time_field = -1;  // -1: times from rate_hz.
  int sensor_field = -1;
  // Integer time: nanoseconds per unit of the time column (1e6 for t_ms); 0 for t_s.
  int64_t time_ns_per_unit = 0;
  double rate_hz = 0.0;  // Times i / rate_hz when time_field < 0.
  size_t data_end = 0;   // Offset where the data rows end (a spreadsheet footer is left out).
  // Raw format with full-scale settings: for each numeric slot, the factor to its derived
  // physical column (0: none), and that column's name.
  std::vector<double> raw_scale;
  std::vector<std::string> raw_scaled_name;
  // For each field: index into the numeric row (quantity), or into the text row, or -1.
  std::vector<int> numeric_slot;
  std::vector<int> text_slot;
  std::vector<int> numeric_fields;  // Field index of each numeric slot.
  std::vector<int> text_fields;     // Field index of each text slot.

  // The clean fast path reads only canonical comma-separated files with '.' decimals,
  // LF or CRLF line ends, time in t_s, and every field a number it keeps.
  bool CleanPathCan() const;
};

// Stages 1-4 above. `path` names the file in errors.
Result<ColumnPlan> PlanCsv(const std::string& path, const MappedFile& file,
                           const LoadOptions& options, SessionFormat format, HeaderLine* header);

// The format a CSV-like file's header says it is in (kCsv when none).
SessionFormat DetectNamedFormat(const std::string& path, std::string_view head);

// A canonical name for a header name that is not one ("gyro_x (deg/s)" -> "gx_dps",
// "w_RS_S_x [rad s^-1]" -> "gx_rads", "timestamp [ns]" -> "t_ns"); "" when none is evident.
std::string InferCanonicalName(std::string_view source);

// Splits a line into fields on `delimiter`, honouring double quotes ("a,b" is one field,
// "" inside quotes is a quote); fields are trimmed of spaces and tabs.
std::vector<std::string> SplitFields(std::string_view line, char delimiter);

// Parses a time field of integer unit (ns_per_unit nanoseconds) exactly into nanoseconds:
// digits with an optional fraction and exponent ("1.40363657975856E+018"), as long as the
// value is a whole number of nanoseconds within int64. `resolution_ns` is set to the power
// of ten (in ns) of the last written digit when the number has an exponent and that digit
// is coarser than 1 ns (E-notation: "1.40363657975856E+018" -> 10000), else 0; callers
// decide which resolution is a loss. Returns false with a reason otherwise.
bool ParseExactTimeNs(const char* b, const char* e, int64_t ns_per_unit, int64_t* ns,
                      int64_t* resolution_ns, const char** why);

}  // namespace metro::internal
