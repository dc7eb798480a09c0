// The HTML view of an accuracy report ("metro.accuracy-report/1", docs/accuracy.md), private
// to src/report/: RenderJsonHtml dispatches here on the schema key, and
// RenderAccuracyReportHtml (metro/report/accuracy_page.hpp) renders the typed model through
// the same code, from the JSON the model writes (ToJsonValue).
//
// Everything is drawn from the report alone: the plateau errors against the reference angle
// with their expanded-uncertainty bars U_i = t_{(1+p)/2}(nu_i) u_i (JCGM 100:2008 6.2.1,
// G.3.2; up and down sweeps as separate series), the fitted error curve with its band
// e(theta) +- t_{(1+p)/2}(m - p) u_fit(theta), u_fit = sqrt(g^T C g) from the reported
// covariance (JCGM 100:2008 5.2.2, H.3.4), the hysteresis h with its bars, the cross-axis
// means with their fitted first harmonic, and both single-reading budgets as sorted bars.
// Numbers in tables are rounded per JCGM 100:2008 7.2.6.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "metro/accuracy/accuracy_report.hpp"
#include "metro/core/status.hpp"

namespace metro::report_internal {

using ::metro::kAccuracyReportSchema;

// The page of a report. `json_path` names the report in the title when it names no session (may
// be empty). Errors: a report without points, or a point without a finite reference_deg,
// error_deg or type_a.u_deg.
Result<std::string> RenderAccuracyHtml(const AccuracyReport& report, const std::string& json_path);

}  // namespace metro::report_internal
