// Budget evaluation and its report: the GUM framework, the Monte Carlo method and the GUF
// validation of JCGM 101 clause 8 in one call (EvaluateBudget), the typed report model of
// "metro.budget-report/1" (BudgetReport, MakeBudgetReport), its JSON (ToJson at full
// precision, BudgetReportFromJson) and a readable table (BudgetReportTable: the statement
// rounded per JCGM 100 7.2.6 with metro/core/rounding.hpp, two significant digits of U, the
// value to the same place).
//
// JSON layout (docs/budget-format.md): schema, budget_file, measurand {name, unit, model,
// unit_check}, result {value, u, dof_eff, k, U, coverage, interval, ...}, budget [{name, value,
// u, distribution, sensitivity, contribution, dof, percent, unit, note, unit_conversion,
// session}], correlations, monte_carlo {trials, seed, generator, value, u, interval_symmetric,
// interval_shortest, delta, d_low, d_high, guf_validated, histogram {edges, counts, below,
// above}, ...} (null when disabled). Every number is in the measurand's or the input's own
// unit; a number that is not finite is written as null (an infinite dof too).
#pragma once

#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "metro/core/progress.hpp"
#include "metro/core/status.hpp"
#include "metro/uncertainty/budget.hpp"
#include "metro/uncertainty/gum.hpp"
#include "metro/uncertainty/monte_carlo.hpp"

namespace metro {

inline constexpr const char* kBudgetReportSchema = "metro.budget-report/1";

// The Monte Carlo model values binned once at evaluation time, for a plot of the
// distribution for y (JCGM 101 7.5); the samples themselves are not kept. `edges` (bins + 1,
// ascending, in the measurand's unit) span the central 99.9 % of the values, widened by 5 %
// of that span each side and to include both coverage intervals (GUF and MC); `below` and
// `above` count the values outside. Bins: sqrt(M) clamped to 10..60.
struct McHistogram {
  std::vector<double> edges;
  std::vector<int64_t> counts;
  int64_t below = 0;
  int64_t above = 0;
};

struct BudgetEvaluation {
  Budget budget;
  GumResult gum;
  std::optional<McResult> monte_carlo;      // Absent when budget.monte_carlo.enabled is false.
  std::optional<GufValidation> validation;  // With monte_carlo.
  std::optional<McHistogram> histogram;     // With monte_carlo, when it has a finite spread.
  // True when every requested part succeeded (an adaptive run that did not settle: false).
  bool ok = false;
};

// GUM evaluation, then (if enabled) the Monte Carlo run and the GUF validation, each with
// the options stored in the budget. A model without exact derivatives (gum.hpp
// derivatives_exact false: central differences) needs the Monte Carlo method, whose result
// is then the stated one: with monte_carlo disabled such a budget is refused (an input
// error naming the reason).
// `progress` (optional, not owned) hears of the Monte Carlo trials as a phase.
Result<BudgetEvaluation> EvaluateBudget(const Budget& budget, ProgressSink* progress = nullptr);

// ---- The report model: what a "metro.budget-report/1" document holds, key for key. ----
// A number the JSON writes as null reads back as NaN, except the degrees of freedom, whose
// null means infinite (JCGM 100 G.4.1: nu = inf for an exactly known input).

// "measurand".
struct BudgetReportMeasurand {
  std::string name;
  std::string unit;   // "" when the budget states none.
  std::string model;  // "" (null in JSON): y = sum c_i x_i.
  // The unit check (docs/budget-format.md, "Units"); absent in reports of budgets whose
  // check failed (they are refused before evaluation, so metro writes it for every report).
  // model_unit is "" (null in JSON) when not checked.
  std::optional<BudgetUnits> unit_check;
};

// "result": the GUM framework (JCGM 100:2008).
struct BudgetReportResult {
  double value = std::numeric_limits<double>::quiet_NaN();   // y
  double u = std::numeric_limits<double>::quiet_NaN();       // u_c(y)
  double dof_eff = std::numeric_limits<double>::infinity();  // nu_eff (null: infinite)
  double k = std::numeric_limits<double>::quiet_NaN();
  double expanded = std::numeric_limits<double>::quiet_NaN();  // "U" = k u_c
  double coverage = std::numeric_limits<double>::quiet_NaN();  // p
  CoverageInterval interval;                                   // y -+ U
  double u_first_order = std::numeric_limits<double>::quiet_NaN();
  bool second_order = false;
  CorrelatedDofPolicy dof_policy = CorrelatedDofPolicy::kGroup;  // "dof_policy": its name
  bool correlated = false;
  std::string dof_note;
  std::string derivatives;  // exact (symbolic), stated, or differences
  // "y = (v +- U) unit, k = 2.00, p = 95 %", rounded per JCGM 100 7.2.6.
  std::string statement;
};

// "unit_conversion" of a budget line: a session quantity converted to the input's unit,
// value = factor * value_from + offset, u = |factor| u_from.
struct BudgetLineConversion {
  std::string from;
  std::string to;
  double factor = 1.0;
  double offset = 0.0;
  double value_from = 0.0;  // In `from`.
  double u_from = 0.0;      // In `from`.
};

// "session" of a budget line: the session quantity a Type A input was summarised from.
struct BudgetLineSession {
  std::string file;
  int64_t sensor = 1;
  std::string quantity;
  int64_t n = 0;  // Observations.
};

// One element of "budget" (GumResult::budget order: largest contribution first).
struct BudgetReportLine {
  std::string name;
  double value = 0.0;                                    // x_i
  double u = 0.0;                                        // u(x_i)
  std::string distribution;                              // DistributionName()
  double sensitivity = 0.0;                              // c_i
  double contribution = 0.0;                             // u_i(y) = |c_i| u(x_i)
  double dof = std::numeric_limits<double>::infinity();  // nu_i (null: infinite)
  double percent = 0.0;                                  // 100 u_i(y)^2 / u_c^2
  std::string unit;                                      // "" (key absent) when not stated.
  std::string note;                                      // "" (key absent) when none.
  std::optional<BudgetLineConversion> unit_conversion;
  std::optional<BudgetLineSession> session;
};

// "monte_carlo" (JCGM 101:2008).
struct BudgetReportMonteCarlo {
  int64_t trials = 0;  // M
  uint64_t seed = 0;
  std::string generator;
  int64_t threads = 0;
  bool adaptive = false;
  bool converged = false;
  int64_t blocks = 0;
  int64_t ndig = 2;
  double coverage = std::numeric_limits<double>::quiet_NaN();
  double value = std::numeric_limits<double>::quiet_NaN();  // NaN when !mean_defined
  double u = std::numeric_limits<double>::quiet_NaN();      // NaN when !u_defined
  bool u_defined = true;
  bool mean_defined = true;
  std::vector<std::string> inputs_without_variance;  // "name (nu = 2)" (6.4.9.4)
  CoverageInterval symmetric;                        // "interval_symmetric"
  CoverageInterval shortest;                         // "interval_shortest" (fitted)
  CoverageInterval shortest_discrete;                // "interval_shortest_discrete" (7.7)
  double numerical_tolerance = std::numeric_limits<double>::quiet_NaN();  // delta of 7.9.2
  std::optional<McStability> stability;  // "stability_half_width", adaptive runs only.
  // "delta", "d_low", "d_high", "guf_validated" (clause 8), when validated at all.
  std::optional<GufValidation> validation;
  std::optional<McHistogram> histogram;
  std::string message;  // "" (key absent) when none.
};

// "stated": the result the budget states, the headline of the table and the page. The GUF
// result when the Monte Carlo method validated it (JCGM 101:2008 8.2); the Monte Carlo one
// (its mean, u and shortest coverage interval, 7.7) when the validation failed or the GUF
// sensitivities were taken by central differences; the GUF result, said to be unvalidated,
// when the budget ran no Monte Carlo method. Reports written before 2026-12-02 have no
// "stated": it is decided again from their other keys when they are read.
inline constexpr const char* kStatedGuf = "guf";
inline constexpr const char* kStatedMonteCarlo = "monte_carlo";
struct BudgetReportStated {
  std::string method;                                       // kStatedGuf or kStatedMonteCarlo.
  std::string reason;                                       // Why this one, in words.
  double value = std::numeric_limits<double>::quiet_NaN();  // NaN: undefined (JCGM 101 6.4.9.4)
  double u = std::numeric_limits<double>::quiet_NaN();
  CoverageInterval interval;  // GUF: y -+ U; Monte Carlo: the shortest interval.
  double coverage = std::numeric_limits<double>::quiet_NaN();
  // GUF: as result.statement; Monte Carlo: "y = v unit, u(y) = u unit, shortest 95 %
  // coverage interval [low, high] unit (JCGM 101 7.7)", rounded per JCGM 100 7.2.6.
  std::string statement;
};

struct BudgetReport {
  std::string budget_file;
  BudgetReportMeasurand measurand;
  BudgetReportResult result;
  BudgetReportStated stated;
  std::vector<BudgetReportLine> budget;
  std::vector<Correlation> correlations;
  std::optional<BudgetReportMonteCarlo> monte_carlo;  // null when the budget disabled it.
};

BudgetReport MakeBudgetReport(const BudgetEvaluation& evaluation);

// The report as JSON text, indent 2, without a trailing newline: exactly what `characterize
// budget` writes (before its "\n").
std::string ToJson(const BudgetReport& report);

// A "metro.budget-report/1" document read back. Errors name the file, the line and column
// of the offending value and its path ("r.json:12:14: result.u: expected a number or null,
// found a string"). Keys metro writes only in some reports (unit_check, a line's unit, note,
// unit_conversion and session, the Monte Carlo validation, histogram, stability and message)
// are optional.
Result<BudgetReport> BudgetReportFromJson(std::string_view text, const std::string& file);

// The readable table of `characterize budget`.
std::string BudgetReportTable(const BudgetReport& report);
std::string BudgetReportTable(const BudgetEvaluation& evaluation);

}  // namespace metro
