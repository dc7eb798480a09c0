// The value-level halves of the "metro.budget-report/1" codec (budget_report.hpp), for
// documents that embed a budget report (the session report's "budget"). Private to the library.
#pragma once

#include <nlohmann/json.hpp>

#include "core/json_reader.hpp"
#include "metro/uncertainty/budget_report.hpp"

namespace metro {

nlohmann::ordered_json ToJsonValue(const BudgetReport& report);

// Reads the report at `cursor`; errors are recorded in the cursor's reading (check ok()).
BudgetReport BudgetReportFromJsonValue(const JsonCursor& cursor);

// ToJsonValue(MakeBudgetReport(evaluation)).
nlohmann::ordered_json BudgetReportJson(const BudgetEvaluation& evaluation);

}  // namespace metro
