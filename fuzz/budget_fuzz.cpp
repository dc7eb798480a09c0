// libFuzzer target: budget files (`characterize budget`, `--budget`, `--reference-u
// BUDGET.json`), docs/budget-format.md. The text goes through ParseBudget (JSON, keys,
// distributions, correlations, the muparser model); a budget that parses is evaluated by
// the GUM framework (what --reference-u does) and then, with the Monte Carlo run cut to a
// few trials on one thread so an input stays fast, by EvaluateBudget and both renderings.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <string>

#include "metro/uncertainty/budget.hpp"
#include "metro/uncertainty/budget_report.hpp"
#include "metro/uncertainty/gum.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  metro::Result<metro::Budget> budget = metro::ParseBudget(text, "fuzz/budget.json");
  if (!budget.ok()) return 0;
  (void)metro::EvaluateGum(budget.value());

  metro::Budget small = budget.value();
  small.monte_carlo.adaptive = false;
  small.monte_carlo.trials = std::min<int64_t>(small.monte_carlo.trials, 200);
  small.monte_carlo.threads = 1;
  metro::Result<metro::BudgetEvaluation> evaluation = metro::EvaluateBudget(small);
  if (evaluation.ok()) {
    (void)metro::ToJson(metro::MakeBudgetReport(evaluation.value()));
    (void)metro::BudgetReportTable(evaluation.value());
  }
  return 0;
}
