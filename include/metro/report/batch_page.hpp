// The batch page (issue #25): a batch summary (BatchSummaryReport, batch_summary.hpp) as one
// self-contained HTML page (reports/templates/batch_page.mustache in page.mustache's chrome):
//   one row per session and tag (frames, fresh, stale, never; a tag with frames but no fresh
//     packet is marked dead), failed sessions with their error, links to each session's page
//     and JSON report;
//   per tag and quantity the summary across sessions (mean of means, std of means, rounded
//     per JCGM 100:2008 7.2.6) and a spread plot: each session's mean with +-u_mean bars and
//     the mean of means as a line.
// docs/reports.md ("Batch page") shows it.
#pragma once

#include <string>
#include <string_view>

#include "metro/core/status.hpp"
#include "metro/report/batch_summary.hpp"

namespace metro {

struct BatchPageOptions {
  // Prefix of the links to the session pages and reports (their names in summary.json are
  // relative to the batch's output directory): the path from the page's folder to that
  // directory, "" when the page is written into it.
  std::string link_prefix;
  int max_plotted_quantities = 48;  // The rest are in the table only (the page says so).
};

// Errors: a plot or the template failing to render.
Result<std::string> RenderBatchSummaryHtml(const BatchSummaryReport& summary,
                                           const BatchPageOptions& options = {});

// The page of a saved summary.json, read with BatchSummaryFromJson: errors at
// file:line:column with the value's path (`characterize report OUTDIR/summary.json`).
Result<std::string> RenderBatchSummaryHtml(std::string_view json_text, const std::string& file,
                                           const BatchPageOptions& options = {});

}  // namespace metro
