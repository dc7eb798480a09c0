// Reading an estimator's noise file back (any format of noise_export.hpp) and judging each
// value against the measurement (issue #40 step 3, `characterize noise-compare`).
//
// The reader takes the shapes the exporter writes and their hand-edited forms:
//   flat YAML `key: value` lines, `# comments`, `%YAML:1.0` and `---` (OpenCV FileStorage),
//   one level of nesting by indentation (OpenVINS's `imu0:`), flow lists `[a, b, c]` (each
//   element read as key[i]); PX4 `param set NAME VALUE` lines; JSON (basalt, members
//   flattened as value0.accel_noise_std[0]; "metro_convention" skipped).
// Anything else is an error at file:line:column saying what was expected. The format is told
// by its keys (the first key that belongs to one format) unless given.
//
// The comparison, per value x of the file against the measurement X with standard
// uncertainty u(X):
//   ratio = x / X
//   E_n = (x - X) / sqrt(U_x^2 + U_X^2)     (ISO 13528:2015 9.7, JCGM 100:2008 6.2)
// with U_X = 2 u(X) (k = 2) and U_x = 0: a configuration file states no uncertainty. |E_n| <= 1
// means the file's value agrees with the measurement; a file inflated x200 shows ratio 200.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "metro/core/status.hpp"
#include "metro/noise/noise_export.hpp"

namespace metro {

// One value of the file: its flattened key, number (or text), and the 1-based positions of
// the key and of the value.
struct NoiseConfigEntry {
  std::string key;
  std::optional<double> number;  // nullopt: not a number (text kept in `text`).
  std::string text;
  int64_t key_line = 0, key_column = 0;
  int64_t line = 0, column = 0;
};

struct NoiseConfigFile {
  std::string file;
  std::vector<NoiseConfigEntry> entries;  // In file order.
};

// Parses `text` (named `file` in errors). Syntax errors at file:line:column.
Result<NoiseConfigFile> ReadNoiseConfig(std::string_view text, const std::string& file);

// The format whose keys the file holds (the first noise or meta key of a format decides).
Result<NoiseExportFormat> DetectNoiseConfigFormat(const NoiseConfigFile& config);

struct NoiseComparisonRow {
  std::string key;
  std::string unit;
  double file_value = std::nan("");
  double measured = std::nan("");
  double u_measured = std::nan("");  // k = 1.
  double ratio = std::nan("");
  double e_n = std::nan("");  // With U = 2 u of the measurement (see above).
};

struct NoiseComparison {
  NoiseExportFormat format = NoiseExportFormat::kKalibr;
  double k = 2.0;  // Coverage factor of U_X in E_n.
  std::vector<NoiseComparisonRow> rows;
};

// Checks `config` against the keys of `options.format` and compares each noise value with the
// measurement (ExportedNoiseValues(input, options)). Errors (input) at the offending entry's
// file:line:column: an unknown key (with the nearest known one), a duplicate, a value that is
// not a number, a negative value, an update rate that is not positive, an off-diagonal that is
// not 0; a missing key at the file's first line (or its parent's). The measurement's own
// refusals (an unresolved term) pass through.
Result<NoiseComparison> CompareNoiseConfig(const NoiseConfigFile& config,
                                           const NoiseExportInput& input,
                                           const NoiseExportOptions& options);

// A plain-text table: key, file value, measured value, u, ratio, E_n.
std::string NoiseComparisonTable(const NoiseComparison& comparison);

}  // namespace metro
