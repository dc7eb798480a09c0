// characterize report REPORT.json --html FILE [--session SESSION]
#include <fmt/format.h>

#include <memory>

#include "commands.hpp"
#include "metro/core/file.hpp"
#include "metro/report/html_report.hpp"
#include "output.hpp"

namespace metro::apps {
namespace {

struct ReportCommandOptions {
  std::string json;
  std::string html;
  std::string session;
};

int RunReportCommand(const ReportCommandOptions& o) {
  if (Status s = CheckOutputs({{"--html", o.html}}, {{"REPORT", o.json}, {"--session", o.session}});
      !s.ok()) {
    PrintError(s.error());
    return kExitUsage;
  }
  Result<std::string> html = RenderJsonFileHtml(o.json, o.session);
  if (!html.ok()) {
    PrintError(html.error());
    return kExitUsage;
  }
  if (Status s = WriteOutput(o.html, html.value()); !s.ok()) {
    PrintError(s.error());
    return kExitFailed;
  }
  Note(fmt::format("wrote {}\n", IsStdio(o.html) ? "stdout" : o.html));
  return kExitOk;
}

}  // namespace

void AddReportCommand(CLI::App& app, int* exit_code) {
  auto o = std::make_shared<ReportCommandOptions>();
  CLI::App* sub = app.add_subcommand(
      "report",
      "render a saved JSON (metro.report/1, metro.calibration/1, metro.accuracy-report/1, any "
      "other schema as tables) "
      "as a self-contained HTML page");
  sub->add_option("json", o->json, "REPORT.json")->required()->check(CLI::ExistingFile);
  sub->add_option("--html", o->html, "HTML file to write (- for stdout)")->required();
  sub->add_option("--session", o->session,
                  "the session the report was made from, if it moved (its SHA-256 must match)")
      ->check(CLI::ExistingFile);
  sub->callback([o, exit_code] { *exit_code = RunReportCommand(*o); });
}

}  // namespace metro::apps
