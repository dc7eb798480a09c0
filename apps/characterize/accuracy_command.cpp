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

void AddAccuracyOptions(CLI::App& app, AccuracyCliOptions* o) {
  app.add_flag("--accuracy", o->enabled,
               "accuracy against a rotation table: plateaus, error curve, hysteresis, budget "
               "(docs/accuracy.md)");
  app.add_option("--table-axis", o->table_axis, "the tag axis the table turns")
      ->type_name("TEXT:{yaw,pitch,roll}")
      ->capture_default_str();
  app.add_option("--reference", o->reference,
                 "separate reference log (t_s, table_angle_deg), aligned on t_s; - reads stdin")
      ->check(ExistingFileOrStdin());
  app.add_option("--reference-u", o->reference_u,
                 "the table's standard uncertainty in deg, or a budget file for it "
                 "(docs/budget-format.md)");
  app.add_option("--reference-offset-s", o->library.alignment.offset_s,
                 "reference clock minus tag clock in s (default: estimated)");
  app.add_option("--error-model", o->model,
                 "the fitted error curve (auto: the order the data support; docs/accuracy.md)")
      ->type_name("TEXT:{auto,linear,harmonic1,harmonic2}")
      ->capture_default_str();
  app.add_option("--min-dwell-s", o->library.plateaus.min_dwell_s,
                 "shortest table rest that is a plateau")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_option("--settle-s", o->library.plateaus.settle_s,
                 "seconds dropped after the table stops")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app.add_option("--plateau-tolerance-deg", o->library.plateaus.tolerance_deg,
                 "largest reference change within a plateau")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app.add_option("--assumed-hysteresis-deg", o->library.assumed_hysteresis_deg,
                 "hysteresis the corrected U assumes when no angle was visited both ways")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app.add_option("--lag-tau-s", o->library.lag_tau_s,
                 "the tag's response time in s (default: estimated from the motion)")
      ->check(CLI::NonNegativeNumber);
  app.add_flag("--no-lag-model", o->no_lag_model,
               "do not model the tag's lag: plateaus settle by --settle-s alone");
  app.add_flag("--keep-departures", o->keep_departures,
               "keep a plateau's start and end where the tag's error departs from its level "
               "(default: trimmed and said so)");
}

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

int RunAccuracy(const AccuracyCliOptions& a, const AccuracyRunInputs& in) {
  if (in.type_a) {
    return PrintErrorExit(MakeError("--accuracy and --type-a are separate analyses: give one"));
  }
  if (Status s = CheckStdinInputs({in.session, a.reference}); !s.ok()) {
    return PrintErrorExit(s.error());
  }
  if (Status s = RefuseStdout(in.html, "--html", "the HTML view goes to a file"); !s.ok()) {
    return PrintErrorExit(s.error());
  }
  // --reference-u is a budget file unless it is a number.
  char* number_end = nullptr;
  std::strtod(a.reference_u.c_str(), &number_end);
  const bool reference_u_is_number = number_end != a.reference_u.c_str() && *number_end == '\0';
  const std::string reference_u_file = reference_u_is_number ? "" : a.reference_u;
  if (Status s = CheckOutputs({{"-o", in.output}, {"--html", in.html}},
                              {{"SESSION", in.session},
                               {"--reference", a.reference},
                               {"--reference-u", reference_u_file},
                               {"--columns-file", in.load.columns_file},
                               {"--tags", in.tags}});
      !s.ok()) {
    return PrintErrorExit(s.error());
  }
  AccuracyOptions options = a.library;
  auto axis = ParseTableAxis(a.table_axis);
  if (!axis.ok()) {
    return PrintErrorExit(axis.error());
  }
  options.axis = axis.value();
  auto model = ParseErrorModel(a.model);
  if (!model.ok()) {
    return PrintErrorExit(model.error());
  }
  options.model = model.value();
  if (in.sensors.size() > 1) {
    return PrintErrorExit(MakeError("--accuracy evaluates one tag: give at most one --sensor"));
  }
  options.sensor = in.sensors.empty() ? 0 : in.sensors.front();
  options.plateaus.settle_auto = in.settle_auto;
  options.window = in.window;
  options.model_lag = !a.no_lag_model;
  options.plateaus.trim_departures = !a.keep_departures;
  auto reference_u = ParseReferenceU(a.reference_u);
  if (!reference_u.ok()) {
    return PrintErrorExit(reference_u.error());
  }
  options.reference = reference_u.value();
  std::string why;
  if (!options.IsValid(&why)) {
    return PrintErrorExit(MakeError(why));
  }
  TagRegistry tags = TagRegistry::Default();
  if (!in.tags.empty()) {
    Result<TagRegistry> loaded = TagRegistry::Load(in.tags);
    if (!loaded.ok()) return PrintErrorExit(loaded.error());
    tags = std::move(loaded).value();
  }
  LoadOptions load;
  if (Status s = MakeLoadOptions(in.load, &load); !s.ok()) {
    return PrintErrorExit(s.error());
  }
  load.threads = in.threads;
  // One line per phase on a terminal: the load in bytes, then the evaluation.
  TerminalProgress progress(stderr, CliProgressOptions());
  BeginLoadPhase(&progress, in.session);
  load.on_bytes_parsed = [&progress](int64_t n) { progress.Advance(n); };
  auto session = LoadSession(in.session, load);
  progress.Finish();
  if (!session.ok()) {
    return PrintErrorExit(session.error());
  }
  std::optional<Session> reference;
  if (!a.reference.empty()) {
    LoadOptions ref_load;
    ref_load.format = SessionFormat::kCsv;
    ref_load.threads = in.threads;
    auto loaded = LoadSession(a.reference, ref_load);
    if (!loaded.ok()) {
      return PrintErrorExit(loaded.error());
    }
    reference = std::move(loaded).value();
  }
  const Session* ref = reference ? &*reference : nullptr;
  progress.BeginPhase("accuracy: plateaus, error curve, budget", kUncountedWork);
  auto result = EvaluateAccuracy(session.value(), ref, options);
  progress.Finish();
  if (!result.ok()) {
    return PrintErrorExit(result.error());
  }
  const AccuracyReport report = MakeAccuracyReport(result.value(), session.value(), ref, tags);
  const std::string json = ToJson(report) + "\n";
  std::string html;
  if (!in.html.empty()) {
    Result<std::string> rendered = RenderAccuracyReportHtml(report, in.output);
    if (!rendered.ok()) {
      // The view of the evaluation just made: a failure is the run's, not the input's.
      return PrintErrorExit(rendered.error().WithKind(ErrorKind::kFailed));
    }
    html = std::move(rendered).value();
  }
  // No -o: the JSON to stdout and no table; -o -: the same, and the table to stderr. The
  // JSON and the HTML are replaced together or not at all.
  if (Status s = WriteOutputs({{in.output.empty() ? "-" : in.output, json}, {in.html, html}});
      !s.ok()) {
    return PrintErrorExit(s.error());
  }
  if (!in.output.empty()) PrintTable(AccuracyReportTable(report), in.output);
  return kExitOk;
}

namespace {

struct AccuracyCommandOptions {
  std::string session;
  AnalysisCliOptions analysis;  // Input and window (AnalysisCliKind::kAccuracy).
  AccuracyCliOptions accuracy;
  std::string output;
  std::string html;
  int threads = 0;
};

}  // namespace

void AddAccuracyCommand(CLI::App& app, int* exit_code) {
  auto o = std::make_shared<AccuracyCommandOptions>();
  CLI::App* sub = app.add_subcommand(
      "accuracy",
      "accuracy of a tag against a rotation table: plateaus, error curve, hysteresis, budget "
      "(docs/accuracy.md; also: characterize SESSION --accuracy ...)");
  sub->add_option("session", o->session, "session.csv or receiver capture; - reads stdin")
      ->required()
      ->check(ExistingFileOrStdin());
  AddAnalysisCliOptions(sub, &o->analysis, AnalysisCliKind::kAccuracy);
  sub->add_option("-o,--output", o->output,
                  "write the JSON report here (atomically) and print a table to stdout; -o - "
                  "writes it to stdout and the table to stderr (default: the JSON to stdout)");
  sub->add_option("--html", o->html, "also write the HTML view here (docs/reports.md)");
  AddAccuracyOptions(*sub, &o->accuracy);
  sub->add_option("--threads", o->threads, "worker threads (default: all cores)")
      ->check(CLI::NonNegativeNumber);
  sub->callback([o, exit_code] {
    o->accuracy.enabled = true;  // --accuracy is implied here.
    const AnalysisCliOptions& a = o->analysis;
    *exit_code =
        RunAccuracy(o->accuracy, {o->session, a.load, a.sensors, o->output, a.window.settle_auto,
                                  o->threads, false, o->html, AccuracyWindow(a), a.tag_registry});
  });
}

}  // namespace metro::apps
