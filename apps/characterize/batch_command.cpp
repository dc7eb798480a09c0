// characterize batch DIR|GLOB|FILE... --type-a [--allan] -o OUTDIR [--jobs N] [--html PAGE]
#include <fmt/format.h>

#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>

#include "analysis_options.hpp"
#include "commands.hpp"
#include "metro/core/progress.hpp"
#include "metro/report/batch.hpp"
#include "metro/report/batch_page.hpp"
#include "output.hpp"

namespace metro::apps {
namespace {

namespace fs = std::filesystem;

struct BatchCommandOptions {
  std::vector<std::string> inputs;
  std::string output_dir;
  std::string html;  // The batch page; each session's page goes beside its JSON report.
  int jobs = 0;
  bool type_a = false;
  AnalysisCliOptions analysis;  // Input, window, tag names, Allan (analysis_options.hpp).
};

int RunBatchCommand(const BatchCommandOptions& o) {
  if (Status s = RefuseStdout(o.output_dir, "-o",
                              "batch writes a report per session: name a "
                              "directory");
      !s.ok()) {
    return PrintErrorExit(s.error());
  }
  BatchOptions options;
  options.output_dir = o.output_dir;
  options.session_pages = !o.html.empty();
  options.jobs = o.jobs;
  // One thread inside each session: the sessions themselves run in parallel.
  if (Status s = MakeSessionAnalysisOptions(o.analysis, 1, &options.analysis); !s.ok()) {
    return PrintErrorExit(s.error());
  }
  options.analysis.allan_skip_without_rates = true;
  std::string why;
  if (!options.IsValid(&why)) {
    return PrintErrorExit(MakeError(why));
  }
  std::vector<std::string> skipped;
  Result<std::vector<std::string>> inputs = ExpandBatchInputs(o.inputs, &skipped);
  if (!inputs.ok()) {
    return PrintErrorExit(inputs.error());
  }
  for (const std::string& line : skipped) Note("note: " + EscapeControlChars(line) + "\n");
  // The batch page is never written over a session (nor a device, a folder, ...).
  std::vector<NamedPath> sessions = {{"--tags", o.analysis.tag_registry},
                                     {"--columns-file", o.analysis.load.columns_file}};
  for (const std::string& in : inputs.value()) sessions.push_back({"a session", in});
  if (Status s = CheckOutputs({{"--html", o.html}}, sessions); !s.ok()) {
    return PrintErrorExit(s.error());
  }
  ProgressOptions bar;
  if (Quiet()) bar.mode = ProgressMode::kNever;
  ProgressBar progress("batch", static_cast<int64_t>(inputs.value().size()), stderr, bar);
  options.on_progress = [&progress](size_t, size_t) { progress.Advance(); };
  const BatchSummary summary = RunBatch(inputs.value(), options);
  progress.Finish();
  for (const std::string& line : summary.skipped) Note("note: " + EscapeControlChars(line) + "\n");
  if (!summary.error.message.empty()) {
    PrintError(summary.error);
    return summary.items.empty() ? kExitUsage : kExitFailed;
  }
  for (const BatchItem& item : summary.items) {
    if (!item.ok) PrintError(item.error);
  }
  if (!o.html.empty()) {
    // Links from the page's folder to the session pages in the output directory.
    BatchPageOptions page;
    if (!IsStdio(o.html)) {
      std::error_code ec;
      const fs::path from = fs::weakly_canonical(fs::absolute(o.html).parent_path(), ec);
      const fs::path to = fs::weakly_canonical(fs::absolute(o.output_dir), ec);
      const fs::path relative = to.lexically_relative(from);
      page.link_prefix = relative.empty() || relative == "." ? "" : relative.generic_string();
    }
    const Result<std::string> html = RenderBatchSummaryHtml(summary.summary, page);
    if (!html.ok()) {
      // The page of the batch just run: a failure is the run's, not the input's.
      return PrintErrorExit(html.error().WithKind(ErrorKind::kFailed));
    }
    if (Status s = WriteOutput(o.html, html.value()); !s.ok()) {
      return PrintErrorExit(s.error());
    }
  }
  PrintTable(summary.table, o.output_dir);
  Note(fmt::format("{} of {} sessions analysed; reports and summary.json in {}\n",
                   summary.items.size() - summary.failed, summary.items.size(), o.output_dir));
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
  sub->add_option("--html", o->html,
                  "also write the batch page here (- for stdout): a row per session and tag with "
                  "dead tags marked, spread plots per quantity, links to each session's page, "
                  "written beside its JSON report (docs/reports.md, \"Batch page\")");
  sub->add_flag("--type-a", o->type_a, "GUM Type A evaluation (always done)");
  AddAnalysisCliOptions(sub, &o->analysis);
  sub->callback([o, exit_code] { *exit_code = RunBatchCommand(*o); });
}

}  // namespace metro::apps
