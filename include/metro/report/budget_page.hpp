// The budget page (issue #25): a budget report (metro/uncertainty/budget_report.hpp,
// "metro.budget-report/1") as one self-contained HTML page, from
// reports/templates/budget_page.mustache in the page chrome of page.mustache. docs/reports.md
// ("Budget page") shows what it holds, in this order:
//   the statement of JCGM 100:2008 7.2.4 (y = (value +- U) unit with k, nu_eff and the
//     coverage probability; value and U rounded per 7.2.6 with RoundForStatement) and the
//     concise notation of u_c (7.2.2);
//   the GUF and Monte Carlo results with both coverage intervals, each end rounded to the
//     place of two significant digits of the interval's width (RoundInterval), so the ends
//     tell apart;
//   the verdict of the GUF validation (JCGM 101:2008 8.2);
//   the Monte Carlo histogram (monte_carlo.histogram) with the GUF density overlaid (JCGM 101
//     5.6: the normal or, with finite nu_eff, the scaled and shifted t distribution);
//   the contributions (c_i u_i)^2 / u_c^2 as sorted bars and the budget table.
#pragma once

#include <string>
#include <string_view>

#include "metro/core/status.hpp"
#include "metro/uncertainty/budget_report.hpp"

namespace metro {

Result<std::string> RenderBudgetReportHtml(const BudgetReport& report);

// The page of a "metro.budget-report/1" document read with BudgetReportFromJson: errors at
// file:line:column with the value's path (`characterize report B.json`).
Result<std::string> RenderBudgetReportHtml(std::string_view json_text, const std::string& file);

}  // namespace metro
