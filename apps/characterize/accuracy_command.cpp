// characterize accuracy SESSION ... (or SESSION --accuracy ...): accuracy of a tag against a
// rotation table.
#include "accuracy_command.hpp"

#include <fmt/format.h>

#include <cstdio>
#include <memory>

#include "analysis_options.hpp"
#include "cli_progress.hpp"
#include "exit_codes.hpp"
#include "metro/accuracy/accuracy.hpp"
#include "metro/accuracy/accuracy_report.hpp"
#include "metro/core/file.hpp"
#include "metro/core/progress.hpp"
#include "metro/io/session_io.hpp"
#include "metro/io/tag_registry.hpp"
#include "metro/report/accuracy_page.hpp"
#include "output.hpp"

namespace metro::apps {
namespace {

// --reference-u: a number is a standard uncertainty in deg; anything else a budget file.
Result<ReferenceUncertainty> ParseReferenceU(const std::string& text) {
  ReferenceUncertainty r;
  if (text.empty()) return r;
  char* end = nullptr;
  const double u = std::strtod(text.c_str(), &end);
  if (end != text.c_str() && *end == '\0') {
    if (!(u >= 0.0) || !std::isfinite(u)) {
      return MakeError("--reference-u must be a standard uncertainty >= 0 deg, got " + text);
    }
    r.u_deg = u;
    r.source = "--reference-u";
    return r;
  }
  return ReferenceUncertaintyFromBudget(text);
}

}  // namespace

const std::vector<std::string>& AccuracyOnlyOptionNames() {
  static const std::vector<std::string> names = {"--table-axis",
                                                 "--reference",
                                                 "--reference-u",
                                                 "--reference-offset-s",
                                                 "--error-model",
                                                 "--min-dwell-s",
                                                 "--settle-s",
                                                 "--plateau-tolerance-deg",
                                                 "--assumed-hysteresis-deg",
                                                 "--lag-tau-s",
                                                 "--no-lag-model",
                                                 "--keep-departures"};
  return names;
}

namespace {

// The inputs and outputs, checked before anything is read: one analysis, stdin read once, no
// page to stdout, no output that names an input (--reference-u is a budget file unless it is a
// number).
Status CheckAccuracyFiles(const AccuracyCliOptions& a, const AccuracyRunInputs& in) {
  if (in.type_a) return MakeError("--accuracy and --type-a are separate analyses: give one");
  if (Status s = CheckStdinInputs({in.session, a.reference}); !s.ok()) return s;
  if (Status s = RefuseStdout(in.html, "--html", "the HTML view goes to a file"); !s.ok()) {
    return s;
  }
  char* number_end = nullptr;
  std::strtod(a.reference_u.c_str(), &number_end);
  const bool reference_u_is_number = number_end != a.reference_u.c_str() && *number_end == '\0';
  const std::string reference_u_file = reference_u_is_number ? "" : a.reference_u;
  return CheckOutputs({{"-o", in.output}, {"--html", in.html}},
                      {{"SESSION", in.session},
                       {"--reference", a.reference},
                       {"--reference-u", reference_u_file},
                       {"--columns-file", in.load.columns_file},
                       {"--tags", in.tags}});
}

// The library's options from the flags (the table axis, the error model, the reference's u),
// checked.
Result<AccuracyOptions> MakeAccuracyOptions(const AccuracyCliOptions& a,
                                            const AccuracyRunInputs& in) {
  AccuracyOptions options = a.library;
  Result<TableAxis> axis = ParseTableAxis(a.table_axis);
  if (!axis.ok()) return axis.error();
  options.axis = axis.value();
  Result<ErrorModel> model = ParseErrorModel(a.model);
  if (!model.ok()) return model.error();
  options.model = model.value();
  if (in.sensors.size() > 1) {
    return MakeError("--accuracy evaluates one tag: give at most one --sensor");
  }
  options.sensor = in.sensors.empty() ? 0 : in.sensors.front();
  options.plateaus.settle_auto = in.settle_auto;
  options.window = in.window;
  options.model_lag = !a.no_lag_model;
  options.plateaus.trim_departures = !a.keep_departures;
  Result<ReferenceUncertainty> reference_u = ParseReferenceU(a.reference_u);
  if (!reference_u.ok()) return reference_u.error();
  options.reference = reference_u.value();
  std::string why;
  if (!options.IsValid(&why)) return MakeError(why);
  return options;
}

// The tag's session (a progress line in bytes on a terminal) and the separate reference log.
struct AccuracyInputs {
  Session session;
  std::optional<Session> reference;
};

Result<AccuracyInputs> LoadAccuracyInputs(const AccuracyCliOptions& a, const AccuracyRunInputs& in,
                                          TerminalProgress* progress) {
  LoadOptions load;
  if (Status s = MakeLoadOptions(in.load, &load); !s.ok()) return s.error();
  load.threads = in.threads;
  BeginLoadPhase(progress, in.session);
  load.on_bytes_parsed = [progress](int64_t n) { progress->Advance(n); };
  Result<Session> session = LoadSession(in.session, load);
  progress->Finish();
  if (!session.ok()) return session.error();
  AccuracyInputs inputs{std::move(session).value(), std::nullopt};
  if (!a.reference.empty()) {
    LoadOptions ref_load;
    ref_load.format = SessionFormat::kCsv;
    ref_load.threads = in.threads;
    Result<Session> loaded = LoadSession(a.reference, ref_load);
    if (!loaded.ok()) return loaded.error();
    inputs.reference = std::move(loaded).value();
  }
  return inputs;
}

// The report's JSON and, with --html, its page.
Result<std::pair<std::string, std::string>> RenderAccuracy(const AccuracyReport& report,
                                                           const AccuracyRunInputs& in) {
  std::string html;
  if (!in.html.empty()) {
    Result<std::string> rendered = RenderAccuracyReportHtml(report, in.output);
    // The view of the evaluation just made: a failure is the run's, not the input's.
    if (!rendered.ok()) return rendered.error().WithKind(ErrorKind::kFailed);
    html = std::move(rendered).value();
  }
  return std::make_pair(ToJson(report) + "\n", std::move(html));
}

}  // namespace

int RunAccuracy(const AccuracyCliOptions& a, const AccuracyRunInputs& in) {
  if (Status s = CheckAccuracyFiles(a, in); !s.ok()) return PrintErrorExit(s.error());
  Result<AccuracyOptions> options = MakeAccuracyOptions(a, in);
  if (!options.ok()) return PrintErrorExit(options.error());
  TagRegistry tags = TagRegistry::Default();
  if (!in.tags.empty()) {
    Result<TagRegistry> loaded = TagRegistry::Load(in.tags);
    if (!loaded.ok()) return PrintErrorExit(loaded.error());
    tags = std::move(loaded).value();
  }
  // One line per phase on a terminal: the load in bytes, then the evaluation.
  TerminalProgress progress(stderr, CliProgressOptions());
  Result<AccuracyInputs> inputs = LoadAccuracyInputs(a, in, &progress);
  if (!inputs.ok()) return PrintErrorExit(inputs.error());
  const Session& session = inputs.value().session;
  const Session* ref = inputs.value().reference ? &*inputs.value().reference : nullptr;
  progress.BeginPhase("accuracy: plateaus, error curve, budget", kUncountedWork);
  Result<AccuracyResult> result = EvaluateAccuracy(session, ref, options.value());
  progress.Finish();
  if (!result.ok()) return PrintErrorExit(result.error());
  const AccuracyReport report = MakeAccuracyReport(result.value(), session, ref, tags);
  Result<std::pair<std::string, std::string>> rendered = RenderAccuracy(report, in);
  if (!rendered.ok()) return PrintErrorExit(rendered.error());
  // No -o: the JSON to stdout and no table; -o -: the same, and the table to stderr. The
  // JSON and the HTML are replaced together or not at all.
  const auto& [json, html] = rendered.value();
  if (Status s = WriteOutputs({{in.output.empty() ? "-" : in.output, json}, {in.html, html}});
      !s.ok()) {
    return PrintErrorExit(s.error());
  }
  if (!in.output.empty()) PrintTable(AccuracyReportTable(report), in.output);
  return kExitOk;
}

int RunAccuracyCommand(AccuracyCommandOptions o) {
  o.accuracy.enabled = true;  // --accuracy is implied here.
  const AnalysisCliOptions& a = o.analysis;
  return RunAccuracy(o.accuracy, {o.session, a.load, a.sensors, o.output, a.window.settle_auto,
                                  o.threads, false, o.html, AccuracyWindow(a), a.tag_registry});
}

}  // namespace metro::apps
