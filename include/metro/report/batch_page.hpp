// The batch page (issue #25): a "metro.batch-summary/1" summary (batch.hpp) as one
// self-contained HTML page (reports/templates/batch_page.mustache in page.mustache's chrome):
//   one row per session and tag (frames, fresh, stale, never; a tag with frames but no fresh
//     packet is marked dead), failed sessions with their error, links to each session's page
//     and JSON report;
//   per tag and quantity the summary across sessions (mean of means, std of means, rounded
//     per JCGM 100:2008 7.2.6) and a spread plot: each session's mean with +-u_mean bars and
//     the mean of means as a line.
// docs/reports.md ("Batch page") shows it.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "metro/core/status.hpp"

namespace metro {

struct BatchPageOptions {
  // Prefix of the links to the session pages and reports (their names in summary.json are
  // relative to the batch's output directory): the path from the page's folder to that
  // directory, "" when the page is written into it.
  std::string link_prefix;
  int max_plotted_quantities = 48;  // The rest are in the table only (the page says so).
};

// Errors: not a "metro.batch-summary/1" object.
Result<std::string> RenderBatchSummaryHtml(const nlohmann::ordered_json& summary,
                                           const BatchPageOptions& options = {});

}  // namespace metro
