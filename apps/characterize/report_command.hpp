// characterize report REPORT.json --html FILE [--session SESSION] [--tags FILE]: the HTML page
// of a saved report (docs/reports.md).
#pragma once

#include <string>

namespace metro::apps {

struct ReportCommandOptions {
  std::string json;
  std::string html;
  std::string session;
  std::string tags;  // --tags FILE: the tags' names on the page.
};

int RunReportCommand(const ReportCommandOptions& o);

}  // namespace metro::apps
