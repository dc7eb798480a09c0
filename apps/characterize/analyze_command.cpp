// The main job: characterize SESSION --type-a [windows] [-o REPORT.json]
#include <fmt/format.h>

#include <cstdio>
#include <optional>

#include "accuracy_command.hpp"
#include "analysis_options.hpp"
#include "cli_progress.hpp"
#include "commands.hpp"
#include "metro/core/file.hpp"
#include "metro/core/json_text.hpp"
#include "metro/core/progress.hpp"
#include "metro/io/session_io.hpp"
#include "metro/report/html_report.hpp"
#include "metro/report/session_analysis.hpp"
#include "metro/report/type_a_report.hpp"
#include "metro/uncertainty/budget.hpp"
#include "output.hpp"

namespace metro::apps {
namespace {

struct AnalyzeOptions {
  std::string session;
  bool type_a = false;
  AnalysisCliOptions analysis;  // Input, window, tag names, Allan (analysis_options.hpp).
  std::string output;
  int threads = 0;
  std::string allan_csv;
  std::string budget;
  AccuracyCliOptions accuracy;  // --accuracy and its options (accuracy_command.hpp).
  std::string html;
};

// Options that do nothing in the chosen mode are refused, never silently ignored: the
// accuracy evaluation's own options without --accuracy; the Allan options without --allan;
// with --accuracy, the options only the Type A analysis uses.
Status CheckModeOptions(const CLI::App& app, const AnalyzeOptions& o) {
  auto given = [&](const std::string& name) { return app.count(name) > 0; };
  if (o.accuracy.enabled) {
    for (const char* name : {"--allan", "--taus", "--estimator", "--gaps", "--allan-csv",
                             "--budget", "--quantity", "--settle-scope"}) {
      if (given(name)) {
        return MakeError(fmt::format(
            "{} does nothing with --accuracy (the accuracy evaluation takes the table axis's "
            "angle: --table-axis); run the Type A analysis separately for it",
            name));
      }
    }
    return {};
  }
  for (const std::string& name : AccuracyOnlyOptionNames()) {
    if (given(name)) {
      return MakeError(
          fmt::format("{} applies to the accuracy evaluation only: add --accuracy", name));
    }
  }
  if (!o.analysis.allan) {
    for (const char* name : {"--taus", "--estimator", "--gaps", "--allan-csv"}) {
      if (given(name)) return MakeError(fmt::format("{} needs --allan", name));
    }
  }
  return {};
}

int RunAnalyze(const AnalyzeOptions& o) {
  if (o.accuracy.enabled) {
    const AnalysisCliOptions& a = o.analysis;
    WindowOptions window;
    window.skip_samples = a.skip_samples;
    window.skip_seconds = a.skip_seconds;
    window.from_s = a.from_s;
    window.to_s = a.to_s;
    return RunAccuracy(o.accuracy, {o.session, a.load, a.sensors, o.output, a.settle, o.threads,
                                    o.type_a, o.html, window});
  }
  for (Status s : {RefuseStdout(o.html, "--html", "the HTML report goes to a file"),
                   RefuseStdout(o.allan_csv, "--allan-csv", "the Allan curves go to a file")}) {
    if (!s.ok()) {
      PrintError(s.error());
      return kExitUsage;
    }
  }
  std::vector<NamedPath> inputs = {{"SESSION", o.session},
                                   {"--budget", o.budget},
                                   {"--tag-registry", o.analysis.tag_registry},
                                   {"--columns-file", o.analysis.load.columns_file}};
  if (!o.budget.empty()) {
    for (std::string& session : SessionsNamedInBudget(o.budget)) {
      inputs.push_back({"a session of --budget", std::move(session)});
    }
  }
  if (Status s = CheckOutputs({{"-o", o.output}, {"--allan-csv", o.allan_csv}, {"--html", o.html}},
                              inputs);
      !s.ok()) {
    PrintError(s.error());
    return kExitUsage;
  }
  SessionAnalysisOptions options;
  if (Status s = MakeSessionAnalysisOptions(o.analysis, o.threads, &options); !s.ok()) {
    PrintError(s.error());
    return kExitUsage;
  }
  options.allan_csv = options.allan && !o.allan_csv.empty();
  options.budget_path = o.budget;

  // Load (bytes), Type A, Allan, Monte Carlo (trials): one line each on a terminal.
  TerminalProgress progress(stderr, CliProgressOptions());
  options.progress = &progress;
  SessionAnalysis analysis = AnalyzeSession(o.session, options);
  progress.Finish();
  if (!analysis.ok) {
    PrintError(analysis.error);
    return analysis.input_error ? kExitUsage : kExitFailed;
  }
  if (analysis.session.rejected_rows > 0) {
    Note(fmt::format("note: --lenient skipped {} malformed rows (first at line {})\n",
                     analysis.session.rejected_rows, analysis.session.rejected_lines.front()));
  }
  const std::string json = JsonText(analysis.report, 2) + "\n";
  std::string html;
  if (!o.html.empty()) {
    Result<std::string> rendered = RenderSessionAnalysisHtml(analysis);
    if (!rendered.ok()) {
      PrintError(rendered.error());
      return kExitFailed;
    }
    html = std::move(rendered).value();
  }
  // An analysis asked for that produced nothing for a quantity says so here (issue #21).
  for (const std::string& f : analysis.failures) PrintErrorText(f);
  // No curve at all: no --allan-csv (an empty file would read as an analysis that ran).
  const std::string allan_csv_path = analysis.allan_csv.empty() ? std::string() : o.allan_csv;
  if (!o.allan_csv.empty() && allan_csv_path.empty()) {
    PrintErrorText(
        fmt::format("--allan-csv {}: not written, no Allan curve was computed", o.allan_csv));
  }
  // The JSON (no -o: to stdout, with no table), the Allan CSV and the HTML are replaced
  // together or not at all.
  if (Status s = WriteOutputs({{o.output.empty() ? "-" : o.output, json},
                               {allan_csv_path, analysis.allan_csv},
                               {o.html, html}});
      !s.ok()) {
    PrintError(s.error());
    return kExitFailed;
  }
  if (!o.output.empty() && !Quiet()) {
    PrintTable(analysis.table, o.output);
  } else if (const std::string w = TypeAReportWarnings(analysis.report); !w.empty()) {
    // No table (--quiet, or the JSON alone on stdout): the warnings still reach stderr.
    PrintText(stderr, std::string_view(w).substr(1));
  }
  if (analysis.nothing_produced) {
    PrintErrorText("--allan produced no curve for any quantity (reasons above and in the report)");
    return kExitFailed;
  }
  return kExitOk;
}

}  // namespace

void AddAnalyzeOptions(CLI::App& app, int* exit_code) {
  auto o = std::make_shared<AnalyzeOptions>();
  app.add_option("session", o->session, "session.csv or receiver capture; - reads stdin")
      ->check(ExistingFileOrStdin());
  app.add_flag("--type-a", o->type_a,
               "GUM Type A evaluation of every quantity per tag (the default analysis)");
  AddAnalysisCliOptions(&app, &o->analysis);
  app.add_option("-o,--output", o->output,
                 "write the JSON report here (atomically) and print a table to stdout; -o - "
                 "writes it to stdout and the table to stderr");
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
      apps::PrintText(stderr, fmt::format("error: no session given\n{}", app.help()));
      *exit_code = kExitUsage;
      return;
    }
    if (Status s = CheckModeOptions(app, *o); !s.ok()) {
      PrintError(s.error());
      *exit_code = kExitUsage;
      return;
    }
    *exit_code = RunAnalyze(*o);
  });
}

}  // namespace metro::apps
