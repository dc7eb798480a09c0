// The main job: characterize SESSION --type-a [windows] [-o REPORT.json]
#include <fmt/format.h>

#include <cstdio>
#include <optional>

#include "accuracy_command.hpp"
#include "commands.hpp"
#include "metro/core/file.hpp"
#include "metro/core/progress.hpp"
#include "metro/noise/allan.hpp"
#include "metro/report/html_report.hpp"
#include "metro/report/session_analysis.hpp"
#include "output.hpp"

namespace metro::apps {
namespace {

struct AnalyzeOptions {
  std::string session;
  bool type_a = false;
  std::string format = "auto";
  double frame_period_s = kReceiverFramePeriodS;
  bool lenient = false;
  int64_t skip_samples = 0;
  double skip_seconds = 0.0;
  std::optional<double> from_s;
  std::optional<double> to_s;
  std::string settle = "none";
  std::vector<int> sensors;
  std::vector<std::string> quantities;
  std::string output;
  std::string tag_registry;
  int threads = 0;
  bool allan = false;
  std::string taus = "octave";
  std::string estimator = "oadev";
  std::string allan_csv;
  std::string budget;
  AccuracyCliOptions accuracy;  // --accuracy and its options (accuracy_command.hpp).
  std::string html;
};

int RunAnalyze(const AnalyzeOptions& o) {
  if (o.accuracy.enabled) {
    return RunAccuracy(o.accuracy, {o.session, o.format, o.frame_period_s, o.lenient, o.sensors,
                                    o.output, o.settle, o.threads, o.type_a, o.html});
  }
  SessionAnalysisOptions options;
  LoadOptions& load = options.load;
  load.format = o.format == "csv"        ? SessionFormat::kCsv
                : o.format == "receiver" ? SessionFormat::kReceiver
                                         : SessionFormat::kAuto;
  load.lenient = o.lenient;
  load.frame_period_s = o.frame_period_s;
  load.threads = o.threads;
  SessionTypeAOptions& type_a = options.type_a;
  type_a.window.skip_samples = o.skip_samples;
  type_a.window.skip_seconds = o.skip_seconds;
  type_a.window.from_s = o.from_s;
  type_a.window.to_s = o.to_s;
  type_a.window.settle_auto = o.settle == "auto";
  type_a.sensors = o.sensors;
  type_a.quantities = o.quantities;
  type_a.threads = o.threads;
  std::string why;
  if (!options.IsValid(&why)) {
    PrintError(MakeError(why));
    return kExitUsage;
  }
  if (!o.tag_registry.empty()) {
    auto loaded = TagRegistry::Load(o.tag_registry);
    if (!loaded.ok()) {
      PrintError(loaded.error());
      return kExitUsage;
    }
    options.registry = loaded.value();
  }
  for (const std::string* out : {&o.output, &o.allan_csv, &o.html}) {
    if (out->empty()) continue;
    if (Status s = CheckOutputPath(*out, {o.session, o.budget}); !s.ok()) {
      PrintError(s.error());
      return kExitUsage;
    }
  }
  if (o.allan) {
    auto taus = ParseTauSpacing(o.taus);
    auto estimator = ParseAllanEstimator(o.estimator);
    if (!taus.ok() || !estimator.ok()) {
      PrintError(!taus.ok() ? taus.error() : estimator.error());
      return kExitUsage;
    }
    options.allan = true;
    options.allan_options.allan.taus = taus.value();
    options.allan_options.allan.estimator = estimator.value();
    options.allan_options.allan.threads = o.threads;
    options.allan_options.quantities = o.quantities;
    options.allan_csv = !o.allan_csv.empty();
  }
  options.budget_path = o.budget;

  // A running line on a terminal for big inputs (AnalyzeSession has no progress hook).
  ElapsedTicker ticker(fmt::format("analyse {}", o.session), stderr,
                       {IsBigInput(o.session) ? ProgressMode::kAuto : ProgressMode::kNever});
  const SessionAnalysis analysis = AnalyzeSession(o.session, options);
  ticker.Finish();
  if (!analysis.ok) {
    PrintError(analysis.error);
    return analysis.input_error ? kExitUsage : kExitFailed;
  }
  if (analysis.session.rejected_rows > 0) {
    fmt::print(stderr, "note: --lenient skipped {} malformed rows (first at line {})\n",
               analysis.session.rejected_rows, analysis.session.rejected_lines.front());
  }
  const std::string json = analysis.report.dump(2) + "\n";
  if (!o.allan_csv.empty()) {
    if (Status s = WriteFileAtomically(o.allan_csv, analysis.allan_csv); !s.ok()) {
      PrintError(s.error());
      return kExitFailed;
    }
  }
  // The HTML report, after the JSON: a failed render never costs the JSON.
  auto write_html = [&o, &analysis]() -> int {
    if (o.html.empty()) return kExitOk;
    Result<std::string> html = RenderSessionAnalysisHtml(analysis);
    Status s = html.ok() ? WriteFileAtomically(o.html, html.value()) : Status(html.error());
    if (!s.ok()) {
      PrintError(s.error());
      return kExitFailed;
    }
    return kExitOk;
  };
  if (o.output.empty()) {
    std::fwrite(json.data(), 1, json.size(), stdout);
    std::fflush(stdout);
    return write_html();
  }
  if (Status s = WriteFileAtomically(o.output, json); !s.ok()) {
    PrintError(s.error());
    return kExitFailed;
  }
  std::fwrite(analysis.table.data(), 1, analysis.table.size(), stdout);
  return write_html();
}

}  // namespace

void AddAnalyzeOptions(CLI::App& app, int* exit_code) {
  auto o = std::make_shared<AnalyzeOptions>();
  app.add_option("session", o->session, "session.csv or receiver capture")
      ->check(CLI::ExistingFile);
  app.add_flag("--type-a", o->type_a,
               "GUM Type A evaluation of every quantity per tag (the default analysis)");
  app.add_option("--format", o->format, "input format")
      ->check(CLI::IsMember({"auto", "csv", "receiver"}))
      ->capture_default_str();
  app.add_option("--frame-period-s", o->frame_period_s,
                 "receiver frame period in seconds (default 3281/32768 = 0.10013)")
      ->check(CLI::PositiveNumber);
  app.add_flag("--lenient", o->lenient,
               "skip malformed rows (counted in input.rejected_rows) instead of stopping");
  app.add_option("--skip-samples", o->skip_samples, "drop the first N observations of each tag")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--skip-seconds", o->skip_seconds,
                 "drop each tag's observations in its first S seconds")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--from-s", o->from_s, "keep observations with t_s >= this");
  app.add_option("--to-s", o->to_s, "keep observations with t_s <= this");
  app.add_option("--settle", o->settle,
                 "auto: drop each tag's start-up transient (MSER-5, docs/type-a.md)")
      ->check(CLI::IsMember({"none", "auto"}))
      ->capture_default_str();
  app.add_option("--sensor", o->sensors, "only this tag (repeatable)");
  app.add_option("--quantity", o->quantities, "only this quantity, e.g. pitch_deg (repeatable)");
  app.add_option("-o,--output", o->output,
                 "write the JSON report here (atomically) and print a table to stdout");
  app.add_option("--tag-registry", o->tag_registry,
                 R"(JSON {"1": "Forehead", ...} naming the tags (default: thesis Table 5.2))")
      ->check(CLI::ExistingFile);
  app.add_flag("--allan", o->allan,
               "Allan deviation and IEEE 952 noise terms of the rate quantities (docs/noise.md)");
  app.add_option("--taus", o->taus, "Allan taus: octave, decade:N, all")->capture_default_str();
  app.add_option("--estimator", o->estimator, "Allan estimator: oadev, mdev, ohdev")
      ->capture_default_str();
  app.add_option("--allan-csv", o->allan_csv, "also write the Allan curves as CSV here");
  app.add_option("--budget", o->budget,
                 "evaluate this uncertainty budget (docs/budget-format.md); its session inputs "
                 "refer to SESSION")
      ->check(CLI::ExistingFile);
  app.add_option("--html", o->html,
                 "also write a self-contained HTML report with plots here (docs/reports.md)");
  AddAccuracyOptions(app, &o->accuracy);
  app.add_option("--threads", o->threads, "worker threads (default: all cores)")
      ->check(CLI::NonNegativeNumber);
  app.callback([&app, o, exit_code] {
    if (!app.get_subcommands().empty()) return;
    if (o->session.empty()) {
      fmt::print(stderr, "error: no session given\n{}", app.help());
      *exit_code = kExitUsage;
      return;
    }
    *exit_code = RunAnalyze(*o);
  });
}

}  // namespace metro::apps
