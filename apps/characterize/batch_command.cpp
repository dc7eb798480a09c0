// characterize batch DIR|GLOB|FILE... --type-a [--allan] -o OUTDIR [--jobs N]
#include <fmt/format.h>

#include <cstdio>
#include <memory>
#include <optional>

#include "commands.hpp"
#include "metro/core/progress.hpp"
#include "metro/noise/allan.hpp"
#include "metro/report/batch.hpp"
#include "output.hpp"

namespace metro::apps {
namespace {

struct BatchCommandOptions {
  std::vector<std::string> inputs;
  std::string output_dir;
  int jobs = 0;
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
  std::string tag_registry;
  bool allan = false;
  std::string taus = "octave";
  std::string estimator = "oadev";
};

int RunBatchCommand(const BatchCommandOptions& o) {
  BatchOptions options;
  options.output_dir = o.output_dir;
  options.jobs = o.jobs;
  SessionAnalysisOptions& a = options.analysis;
  a.load.format = o.format == "csv"        ? SessionFormat::kCsv
                  : o.format == "receiver" ? SessionFormat::kReceiver
                                           : SessionFormat::kAuto;
  a.load.lenient = o.lenient;
  a.load.frame_period_s = o.frame_period_s;
  a.type_a.window.skip_samples = o.skip_samples;
  a.type_a.window.skip_seconds = o.skip_seconds;
  a.type_a.window.from_s = o.from_s;
  a.type_a.window.to_s = o.to_s;
  a.type_a.window.settle_auto = o.settle == "auto";
  a.type_a.sensors = o.sensors;
  a.type_a.quantities = o.quantities;
  if (!o.tag_registry.empty()) {
    auto loaded = TagRegistry::Load(o.tag_registry);
    if (!loaded.ok()) {
      PrintError(loaded.error());
      return kExitUsage;
    }
    a.registry = loaded.value();
  }
  if (o.allan) {
    auto taus = ParseTauSpacing(o.taus);
    auto estimator = ParseAllanEstimator(o.estimator);
    if (!taus.ok() || !estimator.ok()) {
      PrintError(!taus.ok() ? taus.error() : estimator.error());
      return kExitUsage;
    }
    a.allan = true;
    a.allan_options.allan.taus = taus.value();
    a.allan_options.allan.estimator = estimator.value();
    a.allan_options.quantities = o.quantities;
  }
  std::string why;
  if (!options.IsValid(&why)) {
    PrintError(MakeError(why));
    return kExitUsage;
  }
  Result<std::vector<std::string>> inputs = ExpandBatchInputs(o.inputs);
  if (!inputs.ok()) {
    PrintError(inputs.error());
    return kExitUsage;
  }
  ProgressBar progress("batch", static_cast<int64_t>(inputs.value().size()));
  options.on_progress = [&progress](size_t, size_t) { progress.Advance(); };
  const BatchSummary summary = RunBatch(inputs.value(), options);
  progress.Finish();
  if (!summary.error.message.empty()) {
    PrintError(summary.error);
    return summary.items.empty() ? kExitUsage : kExitFailed;
  }
  for (const BatchItem& item : summary.items) {
    if (!item.ok) PrintError(item.error);
  }
  std::fwrite(summary.table.data(), 1, summary.table.size(), stdout);
  fmt::print(stderr, "{} of {} sessions analysed; reports and summary.json in {}\n",
             summary.items.size() - summary.failed, summary.items.size(), o.output_dir);
  return summary.failed > 0 ? kExitFailed : kExitOk;
}

}  // namespace

void AddBatchCommand(CLI::App& app, int* exit_code) {
  auto o = std::make_shared<BatchCommandOptions>();
  CLI::App* sub = app.add_subcommand(
      "batch",
      "analyse many sessions in parallel: one JSON report each, summary.json and a summary "
      "table per tag and quantity; a failing session is named and the others go on");
  sub->add_option("inputs", o->inputs,
                  "session files, directories (their *.csv and *.txt) or glob patterns")
      ->required();
  sub->add_option("-o,--output-dir", o->output_dir, "directory for the reports (created)")
      ->required();
  sub->add_option("--jobs", o->jobs, "sessions in parallel (default: all cores)")
      ->check(CLI::NonNegativeNumber);
  sub->add_flag("--type-a", o->type_a, "GUM Type A evaluation (always done)");
  sub->add_option("--format", o->format, "input format")
      ->check(CLI::IsMember({"auto", "csv", "receiver"}))
      ->capture_default_str();
  sub->add_option("--frame-period-s", o->frame_period_s, "receiver frame period in seconds")
      ->check(CLI::PositiveNumber);
  sub->add_flag("--lenient", o->lenient, "skip malformed rows instead of failing the session");
  sub->add_option("--skip-samples", o->skip_samples, "drop the first N observations of each tag")
      ->check(CLI::NonNegativeNumber);
  sub->add_option("--skip-seconds", o->skip_seconds,
                  "drop each tag's observations in its first S seconds")
      ->check(CLI::NonNegativeNumber);
  sub->add_option("--from-s", o->from_s, "keep observations with t_s >= this");
  sub->add_option("--to-s", o->to_s, "keep observations with t_s <= this");
  sub->add_option("--settle", o->settle, "auto: drop each tag's start-up transient (MSER-5)")
      ->check(CLI::IsMember({"none", "auto"}))
      ->capture_default_str();
  sub->add_option("--sensor", o->sensors, "only this tag (repeatable)");
  sub->add_option("--quantity", o->quantities, "only this quantity (repeatable)");
  sub->add_option("--tag-registry", o->tag_registry, "JSON naming the tags")
      ->check(CLI::ExistingFile);
  sub->add_flag("--allan", o->allan, "Allan deviation and noise terms of the rate quantities");
  sub->add_option("--taus", o->taus, "Allan taus: octave, decade:N, all")->capture_default_str();
  sub->add_option("--estimator", o->estimator, "Allan estimator: oadev, mdev, ohdev")
      ->capture_default_str();
  sub->callback([o, exit_code] { *exit_code = RunBatchCommand(*o); });
}

}  // namespace metro::apps
