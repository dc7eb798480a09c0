// Self-contained HTML reports (issue #7): one file with inline CSS and inline SVG plots
// (PLplot), no network reference, rendered from the mustache templates in
// reports/templates/ (compiled into the library). docs/reports.md shows what each view
// holds.
//
// The view is chosen by the JSON "schema" key:
//   "metro.report/1"       session view: the result first (per tag and quantity value, U,
//                          k, p rounded per JCGM 100 7.2.6), the Type A details, the noise
//                          table (one-sided density, Allan minimum, Allan-predicted
//                          u(mean)), the input and the options as a table; per tag the x/y/z
//                          Allan curves of each sensor in one plot; per quantity the time
//                          series with the excluded (skip/settle) part shaded, the histogram with
//                          the normal density of the Type A result, the autocorrelation with the
//                          white-noise band, the Allan deviation with confidence bars and the
//                          fitted IEEE 952 terms, and the budget as sorted bars;
//   "metro.calibration/1"  the calibration certificate (certificate.hpp);
//   "metro.accuracy-report/1" the accuracy view: error vs reference angle with U bars, the
//                          fitted error curve and its band, hysteresis, cross-axis errors,
//                          the budgets as sorted bars (docs/reports.md);
//   anything else          a generic view: the JSON as tables (a "budget" key gets bars).
// Numbers in tables are rounded per JCGM 100:2008 7.2.6; the JSON keeps full precision.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "metro/core/status.hpp"
#include "metro/io/session.hpp"
#include "metro/report/session_analysis.hpp"
#include "metro/report/session_report.hpp"

namespace metro {

struct HtmlReportOptions {
  // Quantities that get a section with their plots; empty: every evaluated quantity except
  // the quaternion components qw qx qy qz (their Euler angles are plotted instead). The
  // plots themselves are the report's plot data, computed when the session was analysed
  // (SessionAnalysisOptions::plot, plot_data.hpp).
  std::vector<std::string> plot_quantities;
  int max_plotted_quantities = 48;  // Over all tags; the rest are listed in the tables only.

  bool IsValid(std::string* why) const;
};

// The session view of a "metro.report/1" report, drawn from the report alone: the time
// series, histograms and autocorrelations from each quantity's plot data (a report from
// before metro kept plot data says so and lists them as unavailable), the Allan curves from
// its Allan sections.
// Errors: invalid options, a budget section that cannot be shown.
Result<std::string> RenderSessionReportHtml(const SessionReport& report,
                                            const HtmlReportOptions& options = {});

// The session view of a finished AnalyzeSession (everything in memory).
Result<std::string> RenderSessionAnalysisHtml(const SessionAnalysis& analysis,
                                              const HtmlReportOptions& options = {});

// Reads a saved JSON document and renders the page its "schema" key calls for (see above).
// Each typed document (session report, calibration, accuracy and budget reports) is read with
// its FromJson from the file's text, so a wrong or missing value is named at its line and
// column in the file with its path. No view reloads an input. Errors name the file.
Result<std::string> RenderJsonFileHtml(const std::string& json_path,
                                       const HtmlReportOptions& options = {});

// The "schema" of a JSON document's text; "" when it is not a JSON object with a string
// "schema".
std::string JsonSchemaOf(std::string_view text);

}  // namespace metro
