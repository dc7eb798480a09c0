// calibrate report calibration.json [--html CERTIFICATE.html] [--tags FILE]
#include <fmt/format.h>

#include <memory>

#include "commands.hpp"
#include "metro/calibration/calibration_io.hpp"
#include "metro/core/file.hpp"
#include "metro/report/html_report.hpp"
#include "tags_cli.hpp"
#include "tags_names.hpp"
#include "unix_cli.hpp"

namespace metro::calibrate_app {
namespace {

struct ReportOptions {
  std::string calibration;
  std::string html;                    // Calibration certificate (docs/reports.md).
  std::string tags;                    // --tags FILE: the tags' names, device IDs and profiles.
  bool accept_rejected_model = false;  // --accept-rejected-model: certify them anyway.
};

int RunReport(const ReportOptions& r) {
  if (Status s = apps::RefuseStdout(r.html, "--html",
                                    "the summary goes to stdout: name a file for the certificate");
      !s.ok()) {
    return apps::PrintErrorExit(s.error());
  }
  if (Status s = apps::CheckOutputs({{"--html", r.html}},
                                    {{"CALIBRATION", r.calibration}, {"--tags", r.tags}});
      !s.ok()) {
    return apps::PrintErrorExit(s.error());
  }
  Result<Calibration> cal = LoadCalibration(r.calibration);
  if (!cal.ok()) {
    return apps::PrintErrorExit(cal.error());
  }
  Result<std::optional<TagRegistry>> tags = LoadTagsOption(r.tags);
  if (!tags.ok()) return apps::PrintErrorExit(tags.error());
  Calibration named = cal.value();
  if (tags.value()) {
    if (Status s = apps::ApplyTagsToCalibration(*tags.value(), r.tags, &named); !s.ok()) {
      return apps::PrintErrorExit(s.error());
    }
  }
  apps::PrintText(stdout, FormatCalibrationReport(named));
  if (tags.value()) {
    apps::PrintText(stdout,
                    fmt::format("tags ({}):\n{}", r.tags, apps::CalibrationTagLines(named)));
  }
  if (!r.html.empty()) {
    // Constants marked model_rejected are not certified without --accept-rejected-model.
    const std::vector<std::string> rejected = ModelRejectedConstants(named);
    if (!rejected.empty() && !r.accept_rejected_model) {
      std::string list;
      for (const std::string& x : rejected) list += (list.empty() ? " " : "; ") + x;
      apps::PrintErrorText(fmt::format(
          "{}: the certificate refuses constants marked model_rejected (not written):{}. Refit "
          "as the reason says, or give --accept-rejected-model to certify them with that notice; "
          "to view the file as a page (not a certificate): characterize report {} --html "
          "PAGE.html",
          r.calibration, list, r.calibration));
      return kExitUsage;
    }
    // The certificate's id is the hash of the file's own bytes; with --tags it names the tags
    // from the file.
    Result<std::string> html =
        apps::RenderCertificateFor(named, r.calibration, r.accept_rejected_model);
    // The certificate of a calibration.json that loaded: a render failure is the run's.
    Status s = html.ok() ? WriteFileAtomically(r.html, html.value())
                         : Status(html.error().WithKind(ErrorKind::kFailed));
    if (!s.ok()) {
      return apps::PrintErrorExit(s.error());
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
  sub->add_flag("--accept-rejected-model", o->accept_rejected_model,
                "certify constants marked model_rejected (a model the data reject or an exact "
                "fit), with that notice on the certificate");
  AddTagsOption(sub, &o->tags);
  sub->callback([o, exit_code] { *exit_code = RunReport(*o); });
}

}  // namespace metro::calibrate_app
