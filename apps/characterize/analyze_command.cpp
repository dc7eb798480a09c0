// The main job: characterize SESSION --type-a [windows] [-o REPORT.json]
#include <fmt/format.h>

#include <cstdio>
#include <optional>

#include "commands.hpp"
#include "metro/core/file.hpp"
#include "metro/io/session_io.hpp"
#include "metro/io/tag_registry.hpp"
#include "metro/noise/allan.hpp"
#include "metro/report/allan_section.hpp"
#include "metro/report/type_a_report.hpp"
#include "metro/stats/session_type_a.hpp"
#include "metro/uncertainty/budget_report.hpp"
#include "metro/uncertainty/session_resolver.hpp"
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
};

int RunAnalyze(const AnalyzeOptions& o) {
  LoadOptions load;
  load.format = o.format == "csv"        ? SessionFormat::kCsv
                : o.format == "receiver" ? SessionFormat::kReceiver
                                         : SessionFormat::kAuto;
  load.lenient = o.lenient;
  load.frame_period_s = o.frame_period_s;
  load.threads = o.threads;
  SessionTypeAOptions options;
  options.window.skip_samples = o.skip_samples;
  options.window.skip_seconds = o.skip_seconds;
  options.window.from_s = o.from_s;
  options.window.to_s = o.to_s;
  options.window.settle_auto = o.settle == "auto";
  options.sensors = o.sensors;
  options.quantities = o.quantities;
  options.threads = o.threads;
  std::string why;
  if (!load.IsValid(&why) || !options.IsValid(&why)) {
    PrintError(MakeError(why));
    return kExitUsage;
  }
  TagRegistry registry = TagRegistry::Default();
  if (!o.tag_registry.empty()) {
    auto loaded = TagRegistry::Load(o.tag_registry);
    if (!loaded.ok()) {
      PrintError(loaded.error());
      return kExitUsage;
    }
    registry = loaded.value();
  }
  for (const std::string* out : {&o.output, &o.allan_csv}) {
    if (out->empty()) continue;
    if (Status s = CheckOutputPath(*out, {o.session, o.budget}); !s.ok()) {
      PrintError(s.error());
      return kExitUsage;
    }
  }
  auto session = LoadSession(o.session, load);
  if (!session.ok()) {
    PrintError(session.error());
    return kExitUsage;
  }
  if (session.value().rejected_rows > 0) {
    fmt::print(stderr, "note: --lenient skipped {} malformed rows (first at line {})\n",
               session.value().rejected_rows, session.value().rejected_lines.front());
  }
  auto result = EvaluateSessionTypeA(session.value(), options);
  if (!result.ok()) {
    PrintError(result.error());
    return kExitUsage;
  }
  auto report = TypeAReportJson(session.value(), result.value(), options, registry);
  std::string allan_csv;
  if (o.allan) {
    SessionAllanOptions allan;
    auto taus = ParseTauSpacing(o.taus);
    auto estimator = ParseAllanEstimator(o.estimator);
    if (!taus.ok() || !estimator.ok()) {
      PrintError(!taus.ok() ? taus.error() : estimator.error());
      return kExitUsage;
    }
    allan.allan.taus = taus.value();
    allan.allan.estimator = estimator.value();
    allan.allan.threads = o.threads;
    allan.quantities = o.quantities;
    if (Status s = AddAllanToReport(session.value(), result.value(), allan, &report,
                                    o.allan_csv.empty() ? nullptr : &allan_csv);
        !s.ok()) {
      PrintError(s.error());
      return kExitUsage;
    }
  }
  std::string budget_table;
  if (!o.budget.empty()) {
    // Budget inputs without a "session" refer to this session, in the same window.
    auto budget = LoadBudget(
        o.budget, MakeSessionQuantityResolver(session.value(), result.value(), options.window));
    if (!budget.ok()) {
      PrintError(budget.error());
      return kExitUsage;
    }
    auto evaluation = EvaluateBudget(budget.value());
    if (!evaluation.ok()) {
      PrintError(evaluation.error());
      return kExitFailed;
    }
    report["budget"] = BudgetReportJson(evaluation.value());
    budget_table = BudgetReportTable(evaluation.value());
  }
  const std::string json = report.dump(2) + "\n";
  if (!o.allan_csv.empty()) {
    if (Status s = WriteFileAtomically(o.allan_csv, allan_csv); !s.ok()) {
      PrintError(s.error());
      return kExitFailed;
    }
  }
  if (o.output.empty()) {
    std::fwrite(json.data(), 1, json.size(), stdout);
    return kExitOk;
  }
  if (Status s = WriteFileAtomically(o.output, json); !s.ok()) {
    PrintError(s.error());
    return kExitFailed;
  }
  const std::string table = TypeAReportTable(report) + budget_table;
  std::fwrite(table.data(), 1, table.size(), stdout);
  return kExitOk;
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
