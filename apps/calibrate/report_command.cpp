// calibrate report calibration.json [--html CERTIFICATE.html] [--tags FILE]
#include "report_command.hpp"

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

// --html: the certificate. Constants marked model_rejected are not certified without
// --accept-rejected-model (exit 2, not written). The certificate's id is the hash of the
// file's own bytes; with --tags it names the tags from the file.
Status WriteReportCertificate(const ReportOptions& r, const Calibration& named) {
  const std::vector<std::string> rejected = ModelRejectedConstants(named);
  if (!rejected.empty() && !r.accept_rejected_model) {
    std::string list;
    for (const std::string& x : rejected) list += (list.empty() ? " " : "; ") + x;
    return MakeError(fmt::format(
        "{}: the certificate refuses constants marked model_rejected (not written):{}. Refit "
        "as the reason says, or give --accept-rejected-model to certify them with that notice; "
        "to view the file as a page (not a certificate): characterize report {} --html "
        "PAGE.html",
        r.calibration, list, r.calibration));
  }
  Result<std::string> html =
      apps::RenderCertificateFor(named, r.calibration, r.accept_rejected_model);
  // The certificate of a calibration.json that loaded: a render failure is the run's.
  if (!html.ok()) return html.error().WithKind(ErrorKind::kFailed);
  return WriteFileAtomically(r.html, html.value());
}

}  // namespace

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
  std::optional<TagRegistry> tags;
  Result<Calibration> named = LoadCalibrationWithTags(r.calibration, r.tags, &tags);
  if (!named.ok()) return apps::PrintErrorExit(named.error());
  apps::PrintText(stdout, FormatCalibrationReport(named.value()));
  if (tags) {
    apps::PrintText(
        stdout, fmt::format("tags ({}):\n{}", r.tags, apps::CalibrationTagLines(named.value())));
  }
  if (r.html.empty()) return kExitOk;
  if (Status s = WriteReportCertificate(r, named.value()); !s.ok()) {
    return apps::PrintErrorExit(s.error());
  }
  apps::Note(fmt::format("wrote {}\n", r.html));
  return kExitOk;
}

}  // namespace metro::calibrate_app
