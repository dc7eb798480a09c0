// The accuracy report: the typed model of a "metro.accuracy-report/1" document (every key and
// its unit in docs/accuracy.md), made from an evaluation (MakeAccuracyReport), written and read
// as JSON (ToJson, AccuracyReportFromJson) and shown as a readable table for people
// (AccuracyReportTable). The HTML page renders the same model (metro/report/accuracy_page.hpp).
//
// The model keeps the document's sections; a section whose content is a library struct holds
// that struct (PlateauNoise, SystematicError, Linearity, Hysteresis, Repeatability, CrossAxis,
// HarmonicFit, ReadingBudget, Alignment, AccuracyOptions). Fields of those structs that the
// document does not hold keep their defaults when a report is read (Alignment::reference_deg,
// AccuracyOptions::type_a and ::alignment, BudgetLine::value). A number the JSON writes as null
// reads back as NaN; a degrees of freedom written as null (infinite) reads back as infinity.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "metro/accuracy/accuracy.hpp"
#include "metro/core/status.hpp"
#include "metro/io/session.hpp"
#include "metro/io/tag_registry.hpp"

namespace metro {

inline constexpr const char* kAccuracyReportSchema = "metro.accuracy-report/1";

// "input.tag": the evaluated tag as the tags file names it (docs/formats.md "Tags file").
struct AccuracyReportTag {
  std::string name;
  std::optional<std::string> device_id;  // null when the tags file gives none.
};

// "input.reference" of a separate reference log (t_s, table_angle_deg).
struct AccuracyReferenceLog {
  std::string file;
  std::string sha256;
  Alignment alignment;  // reference_deg is not in the report.
};

// "input".
struct AccuracyReportInput {
  std::string session;
  std::string sha256;
  std::string format;  // SessionFormatName
  int64_t sensor = 0;
  TableAxis table_axis = TableAxis::kYaw;
  std::string quantity;  // e.g. "yaw_deg"
  // Absent in reports written before input.tag existed (before 2026-11-27).
  std::optional<AccuracyReportTag> tag;
  // nullopt: the session's own table_angle_deg column ({"file": null, "column": ...}).
  std::optional<AccuracyReferenceLog> reference_log;
};

// "window": the part of the tag's record evaluated.
struct AccuracyReportWindow {
  int64_t skip_samples = 0;
  double skip_seconds = 0.0;
  std::optional<double> from_s;
  std::optional<double> to_s;
  int64_t n_total = 0;
  int64_t n = 0;
  double t_first_s = 0.0;
  double t_last_s = 0.0;
};

// "segmentation.excluded" element.
struct AccuracyExcludedSpan {
  double t_start_s = 0.0;
  double t_end_s = 0.0;
  int64_t samples = 0;
  std::string reason;
};

// "segmentation".
struct AccuracyReportSegmentation {
  int64_t plateaus = 0;
  int64_t excluded_samples = 0;
  double excluded_s = 0.0;
  int64_t settle_samples = 0;
  std::vector<AccuracyExcludedSpan> excluded;
  double lag_tau_s = 0.0;
  std::string lag_method;
  int64_t lag_settled_plateaus = 0;
  double max_settle_s = 0.0;
  bool reference_unwrapped = false;
  int64_t departure_trimmed_plateaus = 0;
  int64_t departure_trimmed_samples = 0;
  double max_end_trimmed_s = 0.0;
  int64_t departure_kept_plateaus = 0;
};

// "fit": the error curve (error_fit.hpp) with its description.
struct AccuracyReportFit {
  ErrorModel model = ErrorModel::kLinear;
  std::string equation;
  bool hysteresis_term = false;
  std::string order_rule;
  std::string weights;
  HarmonicFit fit;  // "params" (name, value, u, unit), "covariance", ... "residuals_deg".
  double max_prediction_u_deg = 0.0;
};

// "result".
struct AccuracyReportResult {
  double U_random_deg = 0.0;
  double U_uncorrected_max_abs_deg = 0.0;
  double U_uncorrected_gum_deg = 0.0;
  std::string which_u;
  std::string statement_corrected;
  std::string statement_uncorrected;
  // U_corrected_deg, k_corrected, U_uncorrected_deg, k_uncorrected and coverage are the
  // budgets' (AccuracyReport::corrected, ::uncorrected); "ok" is always true.
};

struct AccuracyReport {
  AccuracyReportInput input;
  AccuracyReportWindow window;
  // "options". Its axis and sensor are input.table_axis and input.sensor, its window's skip and
  // range the "window" section's.
  AccuracyOptions options;
  AccuracyReportSegmentation segmentation;
  // "points" (index = position). With !cross_axis_available their other-axis values are NaN
  // (null in JSON).
  std::vector<AccuracyPoint> points;
  PlateauNoise noise;
  std::string noise_method;
  SystematicError systematic;
  AccuracyReportFit fit;
  Linearity linearity;
  Hysteresis hysteresis;
  Repeatability repeatability;
  bool cross_axis_available = true;
  std::string cross_axis_note;  // With !cross_axis_available.
  CrossAxis cross_axis[2];      // "cross_axis", keyed by their quantity.
  ReadingBudget corrected;      // "budget.corrected" (gum: u, dof_eff, k, U, coverage, lines).
  ReadingBudget uncorrected;    // "budget.uncorrected"
  AccuracyReportResult result;
  std::vector<std::string> warnings;
};

// `session` and `reference` (may be null) name the inputs in the report's `input` section;
// `tags` names the evaluated tag there (`input.tag`: its name for the session's format, see
// TagRegistry::Name, and its device ID when the tags file gives one; docs/formats.md "Tags
// file").
AccuracyReport MakeAccuracyReport(const AccuracyResult& result, const Session& session,
                                  const Session* reference,
                                  const TagRegistry& tags = TagRegistry::Default());

// The report as JSON text, indent 2, without a trailing newline (what `characterize accuracy`
// writes before its "\n").
std::string ToJson(const AccuracyReport& report);

// A "metro.accuracy-report/1" document read back; errors at the offending value's
// file:line:column with its path ("r.json:40:17: points[3].type_a.u_deg: expected a number,
// found a string"). input.tag is optional (older reports).
Result<AccuracyReport> AccuracyReportFromJson(std::string_view text, const std::string& file);

std::string AccuracyReportTable(const AccuracyReport& report);

}  // namespace metro
