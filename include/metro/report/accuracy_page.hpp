// The accuracy page: an accuracy report (metro/accuracy/accuracy_report.hpp,
// "metro.accuracy-report/1") as one self-contained HTML page (docs/reports.md, docs/accuracy.md):
// the result statements first, the inputs and options as tables, the plateau errors with their
// expanded uncertainties and the fitted error curve with its band, linearity, hysteresis,
// repeatability, the cross-axis means and both single-reading budgets.
#pragma once

#include <string>
#include <string_view>

#include "metro/accuracy/accuracy_report.hpp"
#include "metro/core/status.hpp"

namespace metro {

// `json_path` names the report in the title when the report names no session (may be empty).
Result<std::string> RenderAccuracyReportHtml(const AccuracyReport& report,
                                             const std::string& json_path);

// The page of a saved report, read with AccuracyReportFromJson: errors at file:line:column
// with the value's path (`characterize report A.json`).
Result<std::string> RenderAccuracyReportHtml(std::string_view json_text, const std::string& file);

}  // namespace metro
