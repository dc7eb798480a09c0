// The session report ("metro.report/1", docs/report-schema.md) as plain data: what
// `characterize SESSION --type-a` writes, what the console table, the session page and the
// batch summary read, and what `characterize report` re-renders. One codec: ToJson writes
// the text metro has always written (keys, order, numbers byte for byte) and
// SessionReportFromJson reads it back, failing at the offending value's file:line:column
// with its path (e.g. `r.json:41:17: sensors[0].quantities.gx_dps.type_a.mean: expected a
// number, found a string`).
//
// Conventions: a JSON null of a number is NaN (metro writes NaN as null) unless the member
// is an integer, then std::optional; a member that may be absent is std::optional (absent
// when nullopt), or an empty vector for arrays written only when non-empty. Keys added by
// later metro versions (type_a.coverage, k, U_mean; options.settle_scope) are optional when
// reading, so older reports still load.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "metro/core/status.hpp"
#include "metro/noise/allan_report.hpp"
#include "metro/report/plot_data.hpp"
#include "metro/report/spec_decision.hpp"
#include "metro/uncertainty/budget_report.hpp"

namespace metro {

inline constexpr const char* kReportSchema = "metro.report/1";

// "tool": the program that wrote the report.
struct ReportTool {
  std::string name;
  std::string version;
};

// "input.rejected[i]": a row skipped with --lenient.
struct RejectedRow {
  int64_t line = 0;
  std::string reason;
};

// "input.dialect" (text input): what the loader applied (docs/formats.md, "Dialect").
struct ReportDialect {
  std::string delimiter;      // One character.
  std::string decimal_point;  // One character.
  std::string line_ends;      // "LF", "CRLF", "CR".
  bool bom = false;
  bool quoted = false;
  bool header_in_comment = false;
};

// "input.mapping[i]": a header name and the canonical column it became ("" = left out).
struct ReportColumnMapping {
  std::string source;
  std::string canonical;
};

// "input.time" (text input). integer time: t_s = (t_ns - origin_ns) / 1e9; unit "rate":
// t_s = k / rate_hz.
struct ReportTime {
  std::string source;
  std::string unit;  // "ns", "s", "ms", "us", "rate".
  bool integer = false;
  std::optional<int64_t> origin_ns;    // Present for integer time.
  std::optional<double> rate_hz;       // Present when a rate was used.
  std::optional<double> resolution_s;  // Present for E-notation time.
};

// "input.raw_full_scale": --accel-fs-g and --gyro-fs-dps (0: not given).
struct ReportRawFullScale {
  double accel_fs_g = 0.0;
  double gyro_fs_dps = 0.0;
};

// "input".
struct ReportInput {
  std::string path;    // As given.
  std::string sha256;  // Of the file's bytes.
  std::string format;  // "csv", "receiver", "euroc", "raw", "phyphox", "sensorlogger".
  int64_t rows = 0;
  int64_t rejected_rows = 0;
  std::vector<RejectedRow> rejected;
  std::vector<std::string> columns;
  std::vector<std::string> unknown_columns;
  std::optional<double> frame_period_s;  // Receiver input only.
  // Text input only (all three present together).
  std::optional<ReportDialect> dialect;
  std::optional<std::vector<ReportColumnMapping>> mapping;
  std::optional<ReportTime> time;
  std::optional<ReportRawFullScale> raw_full_scale;
  std::vector<std::string> notes;     // Written only when not empty.
  std::vector<std::string> warnings;  // Written only when not empty.
};

// "options.autocorrelation".
struct ReportAutocorrelation {
  std::string method;
  double band_confidence = 0.0;
  double max_lag_fraction = 0.0;
};

// "options": how the report was made.
struct SessionReportOptions {
  int64_t skip_samples = 0;
  double skip_seconds = 0.0;
  double from_s = std::nan("");  // null: not given.
  double to_s = std::nan("");    // null: not given.
  std::string settle;            // "auto" or "none".
  std::vector<int64_t> sensors;
  std::vector<std::string> quantities;
  ReportAutocorrelation autocorrelation;
  std::optional<std::string> settle_scope;  // "quantity" or "tag"; absent in older reports.
};

// "sensors[i].window.settle" (--settle auto).
struct ReportWindowSettle {
  std::string method;
  int64_t samples = 0;
  bool at_limit = false;
  // Added with the settle fit; absent in older reports. When `scope` is present "driver" is
  // written too (null: no cut).
  std::optional<std::string> scope;   // "quantity" or "tag".
  std::optional<std::string> driver;  // The quantity whose cut the tag window takes.
};

// "sensors[i].window": the observations evaluated, [first_index, end_index).
struct ReportWindow {
  int64_t n_total = 0;
  int64_t n = 0;
  int64_t first_index = 0;
  int64_t end_index = 0;
  // null (NaN, nullopt) when the window is empty.
  double t_first_s = std::nan("");
  double t_last_s = std::nan("");
  std::optional<int64_t> first_line;
  std::optional<int64_t> last_line;
  std::optional<ReportWindowSettle> settle;  // --settle auto.
};

// "type_a" of a quantity (JCGM 100:2008 4.2; docs/type-a.md). NaN is null: the four
// autocorrelation terms when not computed (autocorr_note says why), u_mean and u_mean_dof of a
// constant series.
struct TypeAReport {
  int64_t n = 0;
  double mean = 0.0;
  double variance = 0.0;
  double std = 0.0;
  double variance_of_mean = 0.0;
  double std_of_mean = 0.0;
  int64_t dof = 0;
  double n_eff = std::nan("");
  double std_of_mean_autocorr = std::nan("");
  std::optional<int64_t> autocorr_cutoff_lag;
  double rho1 = std::nan("");
  std::optional<std::string> autocorr_note;  // null when the terms above were computed.
  bool has_autocorr_note = true;             // false: a report written before the key existed.
  // false: a report written before u_mean existed (the four keys below absent).
  bool has_u_mean = true;
  double u_mean = std::nan("");
  double u_mean_dof = std::nan("");
  std::optional<std::string> u_mean_method;
  std::optional<int64_t> u_mean_ar_order;  // "ar_spectral" only.
  // The expanded uncertainty of the mean (JCGM 100:2008 6.2.1, G.3.2): U_mean = k u_mean,
  // k = t_{(1+p)/2}(u_mean_dof), p = coverage. nullopt coverage: a report written before
  // these keys existed (k and U_mean then absent too); NaN k and U_mean: no U (u_mean null or
  // u_mean_dof < 1).
  std::optional<double> coverage;
  double k = std::nan("");
  double U_mean = std::nan("");
};

// "settle" of a quantity (--settle auto, docs/type-a.md): the fitted start-up transient.
struct QuantitySettle {
  std::string method;
  int64_t samples = 0;
  bool at_limit = false;
  bool fitted = false;
  // When fitted:
  bool significant = false;
  double tau_samples = std::nan("");
  double tau_s = std::nan("");
  double amplitude = std::nan("");
  double amplitude_over_u = std::nan("");
  double u_mean_residual = std::nan("");
  double bias_over_u_uncut = std::nan("");
  double bias_over_u_kept = std::nan("");
  // When not fitted: why (n < 20, a constant series).
  std::string note;
};

// "sensors[i].quantities.<name>": key order as written: unit, origin, angle_handling,
// unwrap_jumps, type_a, error, settle_samples, warnings, window_first_index, t_first_s,
// settle, allan, allan_type_a_link.
struct QuantityReport {
  std::string name;  // The member name, e.g. "pitch_deg".
  std::string unit;
  std::string origin;                     // "file", "derived", "unknown_column".
  std::string angle_handling;             // "linear", "unwrapped".
  std::optional<int64_t> unwrap_jumps;    // Unwrapped angles only.
  std::optional<TypeAReport> type_a;      // nullopt (null): not evaluated, see `error`.
  std::string error;                      // Written when type_a is null.
  std::optional<int64_t> settle_samples;  // --settle auto: this quantity's own cut.
  std::vector<std::string> warnings;
  // --settle auto: the first observation evaluated and its time (NaN: null).
  std::optional<int64_t> window_first_index;
  double t_first_s = std::nan("");  // Written when window_first_index is.
  std::optional<QuantitySettle> settle;
  std::optional<AllanReport> allan;                 // --allan (docs/noise.md).
  std::optional<AllanTypeALink> allan_type_a_link;  // --allan, with a curve.
  // "plot" (the last key): what the session page draws, computed at analysis time
  // (plot_data.hpp). Absent: not plotted (PlotDataOptions), or a report from before metro
  // kept plot data.
  std::optional<QuantityPlotData> plot;
};

// "sensors[i]": one tag.
struct SensorReport {
  int64_t sensor = 0;
  std::string name;  // Tag registry.
  int64_t frames = 0;
  int64_t fresh = 0;
  int64_t stale = 0;
  int64_t never = 0;
  double packet_loss_ratio = std::nan("");  // (stale + never) / frames.
  ReportWindow window;
  std::vector<QuantityReport> quantities;  // In the report's order.
  std::vector<std::string> warnings;

  // The quantity named `name`, or nullptr.
  const QuantityReport* Find(const std::string& quantity) const;
  QuantityReport* Find(const std::string& quantity);
};

// A "metro.report/1" document.
struct SessionReport {
  std::string schema = kReportSchema;
  ReportTool tool;
  ReportInput input;
  SessionReportOptions options;
  std::vector<SensorReport> sensors;
  // `characterize batch`: why a session without rate quantities has no Allan section.
  std::optional<std::string> allan_skipped;
  // --budget: the "budget" object, a whole metro.budget-report/1 (docs/budget-format.md).
  std::optional<BudgetReport> budget;
  // --spec-part: the "spec" object, the noise terms judged against a datasheet
  // (spec_decision.hpp), and the page's "Against the datasheet" section when the page is
  // drawn in the same run. Written only: a saved report read back does not carry it, so a
  // page re-drawn from it (characterize report) has no such section.
  std::optional<SpecDecisions> spec;

  // The sensor numbered `sensor`, or nullptr.
  const SensorReport* FindSensor(int64_t number) const;
};

// The report as JSON text, indent 2, without a trailing newline: exactly what metro writes.
std::string ToJson(const SessionReport& report);

// Reads a report written by ToJson (or by an older metro). `file` names it in errors.
// Errors: a syntax error or a value of the wrong type or a missing member, at its
// file:line:column with its path; a "schema" other than "metro.report/1".
Result<SessionReport> SessionReportFromJson(std::string_view text, const std::string& file);

// The lines that must head a console table or a summary: one per tag of a receiver capture
// with no fresh packet (frames > 0, fresh == 0), from a session report's sensors: its
// counts and packet_loss_ratio 1.0. `prefix` goes before each line (e.g. the session).
std::vector<std::string> NoFreshPacketWarnings(const SessionReport& report,
                                               const std::string& prefix = "");

}  // namespace metro
