// characterize batch DIR|GLOB|FILE... --type-a [--allan] -o OUTDIR [--jobs N] [--html PAGE]
#include "batch_command.hpp"

#include <fmt/format.h>

#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>

#include "analysis_options.hpp"
#include "metro/core/progress.hpp"
#include "metro/report/batch.hpp"
#include "metro/report/batch_page.hpp"
#include "output.hpp"

namespace metro::apps {
namespace {

namespace fs = std::filesystem;

// The library's batch options from the flags, checked: one thread inside each session (the
// sessions themselves run in parallel).
Result<BatchOptions> MakeBatchOptions(const BatchCommandOptions& o) {
  if (Status s = RefuseStdout(o.output_dir, "-o",
                              "batch writes a report per session: name a "
                              "directory");
      !s.ok()) {
    return s.error();
  }
  BatchOptions options;
  options.output_dir = o.output_dir;
  options.session_pages = !o.html.empty();
  options.jobs = o.jobs;
  if (Status s = MakeSessionAnalysisOptions(o.analysis, 1, &options.analysis); !s.ok()) {
    return s.error();
  }
  options.analysis.allan_skip_without_rates = true;
  std::string why;
  if (!options.IsValid(&why)) return MakeError(why);
  return options;
}

// The sessions the inputs name (folders and patterns expanded; what was skipped is a note),
// checked against the batch page: it is never written over a session (nor a device, a
// folder, ...).
Result<std::vector<std::string>> BatchInputs(const BatchCommandOptions& o) {
  std::vector<std::string> skipped;
  Result<std::vector<std::string>> inputs = ExpandBatchInputs(o.inputs, &skipped);
  if (!inputs.ok()) return inputs;
  for (const std::string& line : skipped) Note("note: " + EscapeControlChars(line) + "\n");
  std::vector<NamedPath> sessions = {{"--tags", o.analysis.tag_registry},
                                     {"--columns-file", o.analysis.load.columns_file}};
  for (const std::string& in : inputs.value()) sessions.push_back({"a session", in});
  if (Status s = CheckOutputs({{"--html", o.html}}, sessions); !s.ok()) return s.error();
  return inputs;
}

// The batch page, its links going from the page's folder to the session pages in the output
// directory.
Status WriteBatchPage(const BatchCommandOptions& o, const BatchSummary& summary) {
  BatchPageOptions page;
  if (!IsStdio(o.html)) {
    std::error_code ec;
    const fs::path from = fs::weakly_canonical(fs::absolute(o.html).parent_path(), ec);
    const fs::path to = fs::weakly_canonical(fs::absolute(o.output_dir), ec);
    const fs::path relative = to.lexically_relative(from);
    page.link_prefix = relative.empty() || relative == "." ? "" : relative.generic_string();
  }
  const Result<std::string> html = RenderBatchSummaryHtml(summary.summary, page);
  // The page of the batch just run: a failure is the run's, not the input's.
  if (!html.ok()) return html.error().WithKind(ErrorKind::kFailed);
  return WriteOutput(o.html, html.value());
}

}  // namespace

int RunBatchCommand(const BatchCommandOptions& o) {
  Result<BatchOptions> options = MakeBatchOptions(o);
  if (!options.ok()) return PrintErrorExit(options.error());
  Result<std::vector<std::string>> inputs = BatchInputs(o);
  if (!inputs.ok()) return PrintErrorExit(inputs.error());
  ProgressOptions bar;
  if (Quiet()) bar.mode = ProgressMode::kNever;
  ProgressBar progress("batch", static_cast<int64_t>(inputs.value().size()), stderr, bar);
  options.value().on_progress = [&progress](size_t, size_t) { progress.Advance(); };
  const BatchSummary summary = RunBatch(inputs.value(), options.value());
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
    if (Status s = WriteBatchPage(o, summary); !s.ok()) return PrintErrorExit(s.error());
  }
  PrintTable(summary.table, o.output_dir);
  Note(fmt::format("{} of {} sessions analysed; reports and summary.json in {}\n",
                   summary.items.size() - summary.failed, summary.items.size(), o.output_dir));
  return summary.failed > 0 ? kExitFailed : kExitOk;
}

}  // namespace metro::apps
