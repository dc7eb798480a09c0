// characterize report REPORT.json --html FILE [--session SESSION] [--tags FILE]
#include "report_command.hpp"

#include <fmt/format.h>

#include <memory>

#include "metro/calibration/calibration_io.hpp"
#include "metro/core/file.hpp"
#include "metro/report/html_report.hpp"
#include "metro/report/session_report.hpp"
#include "output.hpp"
#include "tags_names.hpp"

namespace metro::apps {
namespace {

// The page of REPORT.json with the tags named from `tags_path`: a session report
// (metro.report/1) takes each sensor's name from the file, a calibration.json (its
// certificate) each tag's name, profile and, where it records none, device ID. Other
// documents have no tags to name: an input error.
Result<std::string> RenderWithTags(const ReportCommandOptions& o) {
  Result<TagRegistry> tags = TagRegistry::Load(o.tags);
  if (!tags.ok()) return tags.error();
  Result<std::string> text = ReadFile(o.json);
  if (!text.ok()) return text.error();
  const std::string schema = JsonSchemaOf(text.value());
  // Not JSON, or no schema: the renderer's own error names what is wrong.
  if (schema.empty()) return RenderJsonFileHtml(o.json);
  if (schema == kReportSchema) {
    Result<SessionReport> report = SessionReportFromJson(text.value(), o.json);
    if (!report.ok()) return report.error();
    // Each sensor's name from the tags file where it names the sensor, as `characterize
    // analyze --tags FILE` names them; else the report's own (a topic, a default name).
    SessionFormat format = SessionFormat::kCsv;
    ParseSessionFormat(report.value().input.format, &format);
    for (SensorReport& s : report.value().sensors) {
      s.name = tags.value().Name(static_cast<int>(s.sensor), format, s.name);
    }
    return RenderSessionReportHtml(report.value());
  }
  if (schema == kCalibrationSchema) {
    Result<Calibration> cal = LoadCalibration(o.json);
    if (!cal.ok()) return cal.error();
    if (Status s = ApplyTagsToCalibration(tags.value(), o.tags, &cal.value()); !s.ok()) {
      return s.error();
    }
    return RenderCertificateFor(cal.value(), o.json, false, /*view=*/true);
  }
  return MakeError(o.json, 0,
                   fmt::format("--tags names the tags of a session report ({}) or a "
                               "calibration.json ({}); this is a {} document",
                               kReportSchema, kCalibrationSchema, schema));
}

// A calibration.json with constants marked model_rejected renders as a view, not a certificate
// (issue #36): said on stderr, with what refuses them.
void RejectedModelNote(const std::string& path) {
  Result<std::string> text = ReadFile(path);
  if (!text.ok() || JsonSchemaOf(text.value()) != kCalibrationSchema) return;
  Result<Calibration> cal = CalibrationFromJson(text.value(), path);
  if (!cal.ok()) return;
  for (const std::string& r : ModelRejectedConstants(cal.value())) {
    PrintText(stderr, fmt::format("warning: {}: {} (the page is a view, not a certificate; "
                                  "calibrate blob, push and the certificate refuse these "
                                  "constants unless --accept-rejected-model)\n",
                                  path, EscapeControlChars(r)));
  }
}

}  // namespace

int RunReportCommand(const ReportCommandOptions& o) {
  if (Status s = CheckOutputs({{"--html", o.html}},
                              {{"REPORT", o.json}, {"--session", o.session}, {"--tags", o.tags}});
      !s.ok()) {
    return PrintErrorExit(s.error());
  }
  if (!o.session.empty()) {
    // Older scripts pass the session; the page no longer needs it (said, not silently taken).
    Note(
        fmt::format("note: --session {} is not read: the page is drawn from the report alone (its "
                    "plot data, docs/report-schema.md)\n",
                    o.session));
  }
  Result<std::string> html = o.tags.empty() ? RenderJsonFileHtml(o.json) : RenderWithTags(o);
  if (!html.ok()) {
    return PrintErrorExit(html.error());
  }
  if (Status s = WriteOutput(o.html, html.value()); !s.ok()) {
    return PrintErrorExit(s.error());
  }
  Note(fmt::format("wrote {}\n", IsStdio(o.html) ? "stdout" : o.html));
  RejectedModelNote(o.json);
  return kExitOk;
}

}  // namespace metro::apps
