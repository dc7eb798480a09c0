// The budget section shared by the budget page and the session page (budget.mustache), from the
// typed budget report, and the budget page of a parsed document. Private to src/report/.
#pragma once

#include <kainjow/mustache.hpp>
#include <nlohmann/json.hpp>

#include "metro/core/status.hpp"
#include "metro/uncertainty/budget_report.hpp"

namespace metro::report_internal {

// Data for budget.mustache: the measurand, the statement, the lines rounded per JCGM 100
// 7.2.6 sorted by their share of u_c^2 (largest first), the contribution bars and a one-line
// Monte Carlo summary.
Result<kainjow::mustache::data> BudgetViewData(const BudgetReport& budget);

}  // namespace metro::report_internal

namespace metro {

// True when `document` is a budget definition (docs/budget-format.md: "measurand" and
// "inputs", no "schema"), the input of `characterize budget` rather than a report of it.
bool IsBudgetDefinition(const nlohmann::ordered_json& document);

}  // namespace metro
