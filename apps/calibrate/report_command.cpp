// calibrate report calibration.json
#include <fmt/format.h>

#include <memory>

#include "commands.hpp"
#include "metro/calibration/calibration_io.hpp"
#include "metro/core/file.hpp"
#include "metro/report/html_report.hpp"
#include "unix_cli.hpp"

namespace metro::calibrate_app {
namespace {

struct ReportOptions {
  std::string calibration;
  std::string html;  // Calibration certificate (docs/reports.md).
};

int RunReport(const ReportOptions& r) {
  if (Status s = apps::RefuseStdout(r.html, "--html",
                                    "the summary goes to stdout: name a file for the certificate");
      !s.ok()) {
    apps::PrintError(s.error());
    return kExitUsage;
  }
  if (Status s = apps::CheckOutputs({{"--html", r.html}}, {{"CALIBRATION", r.calibration}});
      !s.ok()) {
    apps::PrintError(s.error());
    return kExitUsage;
  }
  Result<Calibration> cal = LoadCalibration(r.calibration);
  if (!cal.ok()) {
    apps::PrintError(cal.error());
    return kExitUsage;
  }
  apps::PrintText(stdout, FormatCalibrationReport(cal.value()));
  if (!r.html.empty()) {
    // The certificate reloads the recorded inputs when their SHA-256 still matches.
    Result<std::string> html = RenderJsonFileHtml(r.calibration);
    Status s = html.ok() ? WriteFileAtomically(r.html, html.value()) : Status(html.error());
    if (!s.ok()) {
      apps::PrintError(s.error());
      return kExitFailed;
    }
    apps::Note(fmt::format("wrote {}\n", r.html));
  }
  return kExitOk;
}

}  // namespace

void AddReportCommand(CLI::App& app, int* exit_code) {
  auto o = std::make_shared<ReportOptions>();
  CLI::App* sub = app.add_subcommand("report", "print a readable summary of calibration.json");
  sub->add_option("calibration", o->calibration, "calibration.json")
      ->required()
      ->check(CLI::ExistingFile);
  sub->add_option("--html", o->html, "also write the calibration certificate (HTML) here");
  sub->callback([o, exit_code] { *exit_code = RunReport(*o); });
}

}  // namespace metro::calibrate_app
