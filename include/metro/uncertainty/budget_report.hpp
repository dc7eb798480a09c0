// Budget evaluation and its report: the GUM framework, the Monte Carlo method and the GUF
// validation of JCGM 101 clause 8 in one call, rendered as "metro.budget-report/1" JSON
// (full precision) or as a readable table (statement rounded per JCGM 100 7.2.6 with
// metro/core/rounding.hpp: two significant digits of U, the value to the same place).
//
// JSON layout (docs/budget-format.md): schema, budget_file, measurand {name, unit, model},
// result {value, u, dof_eff, k, U, coverage, interval, ...}, budget [{name, value, u,
// distribution, sensitivity, contribution, dof, percent, note}], correlations, monte_carlo
// {trials, seed, generator, value, u, interval_symmetric, interval_shortest, delta, d_low,
// d_high, guf_validated, histogram {edges, counts, below, above}, ...} (null when disabled). Every
// number is in the measurand's or the input's own unit; an infinite dof is written as null.
#pragma once

#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "metro/core/progress.hpp"
#include "metro/core/status.hpp"
#include "metro/uncertainty/budget.hpp"
#include "metro/uncertainty/gum.hpp"
#include "metro/uncertainty/monte_carlo.hpp"

namespace metro {

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
// the options stored in the budget.
// `progress` (optional, not owned) hears of the Monte Carlo trials as a phase.
Result<BudgetEvaluation> EvaluateBudget(const Budget& budget, ProgressSink* progress = nullptr);

nlohmann::ordered_json BudgetReportJson(const BudgetEvaluation& evaluation);
std::string BudgetReportTable(const BudgetEvaluation& evaluation);

}  // namespace metro
