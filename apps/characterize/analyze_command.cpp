// The main job: characterize analyze SESSION [windows] [--allan] [--budget B] [-o REPORT.json],
// also spelled characterize SESSION --type-a ... (the options on the top-level app, where
// --accuracy turns it into `characterize accuracy SESSION ...`).
#include <fmt/format.h>
#include <sys/stat.h>

#include <cstdio>
#include <optional>

#include "accuracy_command.hpp"
#include "analysis_options.hpp"
#include "cli_progress.hpp"
#include "commands.hpp"
#include "metro/core/file.hpp"
#include "metro/core/progress.hpp"
#include "metro/io/session_io.hpp"
#include "metro/noise/noise_export.hpp"
#include "metro/noise/spec_library.hpp"
#include "metro/report/html_report.hpp"
#include "metro/report/noise_export_input.hpp"
#include "metro/report/session_analysis.hpp"
#include "metro/report/session_stream_analysis.hpp"
#include "metro/report/spec_decision.hpp"
#include "metro/report/type_a_report.hpp"
#include "metro/uncertainty/budget.hpp"
#include "noise_export_options.hpp"
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
  // --export FORMAT --export-file FILE [--axis-reduction]: the noise terms as an estimator's
  // file (docs/noise.md "Export to estimators"; noise-export has the formats' other options).
  std::string export_format;
  std::string export_file;
  NoiseExportOptions export_options;
  // --spec-part PART [--spec-library FILE] [--spec-rule R]: the noise terms judged against the
  // part's datasheet figures (docs/specs.md), added to the report as "spec".
  std::string spec_part;
  std::string spec_library = DefaultSpecLibrary();
  std::string spec_rule = "guarded";
  // --stream: read the record once in groups and evaluate from spill files (issue #38);
  // chosen by itself, with a note, when the file is larger than --stream-above-memory-share
  // of the memory available.
  bool stream = false;
  double stream_above_memory_share = 0.5;
  size_t stream_group_bytes = size_t{8} << 20;
};

// MemAvailable of /proc/meminfo in bytes, 0 when unknown.
uint64_t AvailableMemoryBytes() {
  std::FILE* f = std::fopen("/proc/meminfo", "r");
  if (f == nullptr) return 0;
  char key[64];
  unsigned long long kib = 0;
  uint64_t bytes = 0;
  while (std::fscanf(f, "%63s %llu kB", key, &kib) == 2) {
    if (std::string(key) == "MemAvailable:") {
      bytes = static_cast<uint64_t>(kib) * 1024;
      break;
    }
  }
  std::fclose(f);
  return bytes;
}

// Whether to stream: asked, or a regular file larger than the share of available memory
// with nothing asked that needs the whole record (then said on stderr).
bool ChooseStreaming(const AnalyzeOptions& o) {
  if (o.stream) return true;
  const WindowOptions& w = o.analysis.window;
  if (!o.html.empty() || !o.budget.empty() || w.settle_auto || w.skip_samples != 0 ||
      w.skip_seconds != 0.0 || w.from_s || w.to_s || o.stream_above_memory_share <= 0.0) {
    return false;
  }
  // Only what the streaming mode reads as the in-memory path would: text sessions (never a
  // run that works in memory turned into refusals).
  struct stat st {};
  if (::stat(o.session.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) return false;
  SessionFormat format = SessionFormat::kAuto;
  if (o.analysis.load.format != "auto" && !ParseSessionFormat(o.analysis.load.format, &format)) {
    return false;
  }
  if (format == SessionFormat::kAuto) {
    Result<SessionFormat> detected = DetectSessionFormat(o.session);
    if (!detected.ok()) return false;
    format = detected.value();
  }
  if (format == SessionFormat::kReceiver || format == SessionFormat::kImuTk ||
      IsBinaryLogFormat(format)) {
    return false;
  }
  const uint64_t available = AvailableMemoryBytes();
  if (available == 0 || static_cast<double>(st.st_size) <=
                            o.stream_above_memory_share * static_cast<double>(available)) {
    return false;
  }
  Note(
      fmt::format("note: {} ({} MB) is larger than {:g} of the available memory ({} MB): "
                  "streaming mode (--stream; --stream-above-memory-share 0 turns this off)\n",
                  o.session, st.st_size >> 20, o.stream_above_memory_share, available >> 20));
  return true;
}

// Options that do nothing in the chosen mode are refused, never silently ignored: the
// accuracy evaluation's own options without --accuracy; the Allan options without --allan;
// with --accuracy, the options only the Type A analysis uses.
Status CheckModeOptions(const CLI::App& app, const AnalyzeOptions& o) {
  // `analyze` has no accuracy options: only the top-level spelling can be given them.
  auto given = [&](const std::string& name) {
    return app.get_option_no_throw(name) != nullptr && app.count(name) > 0;
  };
  if (o.accuracy.enabled) {
    for (const char* name :
         {"--allan", "--taus", "--estimator", "--gaps", "--allan-csv", "--budget", "--quantity",
          "--settle-scope", "--export", "--export-file", "--axis-reduction", "--spec-part"}) {
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
    for (const char* name :
         {"--taus", "--estimator", "--gaps", "--allan-csv", "--export", "--spec-part"}) {
      if (given(name)) return MakeError(fmt::format("{} needs --allan", name));
    }
  }
  if (given("--export") != given("--export-file")) {
    return MakeError("--export FORMAT and --export-file FILE go together");
  }
  if (given("--axis-reduction") && !given("--export")) {
    return MakeError("--axis-reduction needs --export");
  }
  for (const char* name : {"--spec-library", "--spec-rule"}) {
    if (given(name) && !given("--spec-part"))
      return MakeError(fmt::format("{} needs --spec-part", name));
  }
  return {};
}

// The noise file of --export for the analysed session (the one tag with an Allan section, or
// the one --sensor names).
Result<std::string> ExportText(const SessionAnalysis& analysis, const AnalyzeOptions& o) {
  Result<NoiseExportFormat> format = ParseNoiseExportFormat(o.export_format);
  if (!format.ok()) return format.error();
  NoiseExportOptions options = o.export_options;
  options.format = format.value();
  std::optional<int64_t> sensor;
  if (o.analysis.sensors.size() == 1) sensor = o.analysis.sensors.front();
  Result<NoiseExportInput> input = NoiseExportInputFromReport(
      analysis.report, o.output.empty() || o.output == "-" ? "the report" : o.output, sensor);
  if (!input.ok()) return input.error();
  Result<NoiseExport> exported = ExportNoise(input.value(), options);
  if (!exported.ok()) return exported.error();
  return exported.value().text;
}

// --spec-part: the tag's noise terms judged against the part's datasheet figures.
Result<SpecDecisions> SpecDecisionsOf(const SessionAnalysis& analysis, const SpecLibrary& library,
                                      const AnalyzeOptions& o) {
  Result<const SpecPart*> part = library.Find(o.spec_part);
  if (!part.ok()) return part.error();
  std::optional<int64_t> sensor;
  if (o.analysis.sensors.size() == 1) sensor = o.analysis.sensors.front();
  Result<NoiseExportInput> input =
      NoiseExportInputFromReport(analysis.report, "the report", sensor);
  if (!input.ok()) return input.error();
  SpecDecisionOptions options;
  options.rule = *ParseDecisionRule(o.spec_rule);
  return DecideAgainstSpec(input.value(), *part.value(), library.file, options);
}

int RunAnalyze(const AnalyzeOptions& o) {
  if (o.accuracy.enabled) {
    const AnalysisCliOptions& a = o.analysis;
    return RunAccuracy(o.accuracy,
                       {o.session, a.load, a.sensors, o.output, a.window.settle_auto, o.threads,
                        o.type_a, o.html, AccuracyWindow(a), a.tag_registry});
  }
  for (Status s : {RefuseStdout(o.html, "--html", "the HTML report goes to a file"),
                   RefuseStdout(o.allan_csv, "--allan-csv", "the Allan curves go to a file")}) {
    if (!s.ok()) {
      return PrintErrorExit(s.error());
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
  if (Status s = CheckOutputs({{"-o", o.output},
                               {"--allan-csv", o.allan_csv},
                               {"--html", o.html},
                               {"--export-file", o.export_file}},
                              inputs);
      !s.ok()) {
    return PrintErrorExit(s.error());
  }
  SpecLibrary spec_library;
  if (!o.spec_part.empty()) {  // A part the library does not have stops before the analysis.
    Result<SpecLibrary> lib = LoadSpecLibrary(o.spec_library);
    if (!lib.ok()) return PrintErrorExit(lib.error().WithContext("--spec-library"));
    if (Result<const SpecPart*> p = lib.value().Find(o.spec_part); !p.ok()) {
      return PrintErrorExit(p.error().WithContext("--spec-part"));
    }
    spec_library = std::move(lib).value();
  }
  SessionAnalysisOptions options;
  if (Status s = MakeSessionAnalysisOptions(o.analysis, o.threads, &options); !s.ok()) {
    return PrintErrorExit(s.error());
  }
  options.allan_csv = options.allan && !o.allan_csv.empty();
  options.budget_path = o.budget;
  options.stream_group_bytes = o.stream_group_bytes;

  // Load (bytes), Type A, Allan, Monte Carlo (trials): one line each on a terminal.
  TerminalProgress progress(stderr, CliProgressOptions());
  options.progress = &progress;
  const bool stream = ChooseStreaming(o);
  if (stream && !o.html.empty()) {
    return PrintErrorExit(MakeError(
        "--html: the page plots the record's series, which are not available in streaming "
        "mode; run without --stream, or write the JSON report and render it with `characterize "
        "report`"));
  }
  SessionAnalysis analysis =
      stream ? AnalyzeSessionStreamed(o.session, options) : AnalyzeSession(o.session, options);
  progress.Finish();
  if (!analysis.ok) {
    return PrintErrorExit(analysis.error);
  }
  if (analysis.session.rejected_rows > 0) {
    Note(fmt::format("note: --lenient skipped {} malformed rows (first at line {})\n",
                     analysis.session.rejected_rows, analysis.session.rejected_lines.front()));
  }
  std::optional<Error> spec_error;
  if (!o.spec_part.empty()) {
    Result<SpecDecisions> d = SpecDecisionsOf(analysis, spec_library, o);
    if (d.ok()) {
      analysis.report.spec = std::move(d).value();
    } else {
      spec_error = d.error().WithContext("--spec-part " + o.spec_part);
    }
  }
  const std::string json = ToJson(analysis.report) + "\n";
  std::string html;
  if (!o.html.empty()) {
    Result<std::string> rendered = RenderSessionAnalysisHtml(analysis);
    if (!rendered.ok()) {
      // The page of the analysis just made: a failure is the run's, not the input's.
      return PrintErrorExit(rendered.error().WithKind(ErrorKind::kFailed));
    }
    html = std::move(rendered).value();
  }
  // An analysis asked for that produced nothing for a quantity says so here (issue #21).
  for (const std::string& f : analysis.failures) PrintErrorText(f);
  for (const std::string& w : analysis.warnings) PrintWarning(w);
  // No curve at all: no --allan-csv (an empty file would read as an analysis that ran).
  const std::string allan_csv_path = analysis.allan_csv.empty() ? std::string() : o.allan_csv;
  if (!o.allan_csv.empty() && allan_csv_path.empty()) {
    PrintErrorText(
        fmt::format("--allan-csv {}: not written, no Allan curve was computed", o.allan_csv));
  }
  // --export: a term the record did not resolve is refused by name (exit 2); the report is
  // still written, the noise file is not.
  std::optional<Error> export_error;
  std::string exported;
  if (!o.export_format.empty()) {
    Result<std::string> text = ExportText(analysis, o);
    if (text.ok()) {
      exported = std::move(text).value();
    } else {
      export_error = text.error();
    }
  }
  // The JSON (no -o: to stdout, with no table), the Allan CSV, the HTML and the noise file are
  // replaced together or not at all.
  if (Status s = WriteOutputs({{o.output.empty() ? "-" : o.output, json},
                               {allan_csv_path, analysis.allan_csv},
                               {o.html, html},
                               {export_error ? std::string() : o.export_file, exported}});
      !s.ok()) {
    return PrintErrorExit(s.error());
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
  if (analysis.report.spec) Note(SpecDecisionsTable(*analysis.report.spec));
  if (spec_error) return PrintErrorExit(*spec_error);
  if (export_error) {
    return PrintErrorExit(
        export_error->WithContext("--export " + o.export_format + ": not written"));
  }
  return kExitOk;
}

// SESSION and the Type A options, on the top-level app (`accuracy`: also the accuracy
// options, for the --accuracy spelling) or on the `analyze` subcommand.
void AddTypeAOptions(CLI::App& app, AnalyzeOptions* o, bool accuracy) {
  CLI::Option* session =
      app.add_option("session", o->session, "session.csv or receiver capture; - reads stdin")
          ->check(ExistingFileOrStdin());
  if (!accuracy) session->required();
  app.add_flag("--type-a", o->type_a,
               accuracy ? "GUM Type A evaluation of every quantity per tag (the default analysis)"
                        : "GUM Type A evaluation of every quantity per tag (implied: accepted "
                          "for the spelling without the subcommand)");
  AddAnalysisCliOptions(&app, &o->analysis);
  app.add_option("-o,--output", o->output,
                 "write the JSON report here (atomically) and print a table to stdout; -o - "
                 "writes it to stdout and the table to stderr (default: the JSON to stdout)");
  app.add_option("--allan-csv", o->allan_csv, "also write the Allan curves as CSV here");
  app.add_option("--budget", o->budget,
                 "evaluate this uncertainty budget (docs/budget-format.md); its session inputs "
                 "refer to SESSION")
      ->check(CLI::ExistingFile);
  app.add_option("--html", o->html,
                 "also write a self-contained HTML report with plots here (docs/reports.md)");
  app.add_option("--export", o->export_format,
                 "with --allan: also write the noise terms as this estimator's noise file: "
                 "kalibr, openvins, basalt, vins, orbslam3, gtsam, px4-ekf2, ros "
                 "(docs/noise.md; characterize noise-export has their options)")
      ->check(CLI::IsMember(NoiseExportFormatNames()));
  app.add_option("--export-file", o->export_file, "the noise file of --export (atomically)");
  AddAxisReductionOption(&app, &o->export_options.reduction,
                         "with --export: one value over the three axes, max (the largest axis "
                         "and its u) or rms");
  app.add_option("--spec-part", o->spec_part,
                 "with --allan: judge N, B, K against this part's datasheet figures "
                 "(MPU6050, MPU9250, ICM20948, ICM42688P, ...; docs/specs.md): a JCGM 106 "
                 "decision for max/min figures, ratio and E_n for typ ones");
  app.add_option("--spec-library", o->spec_library, "the spec library (datasets/specs/specs.json)")
      ->check(CLI::ExistingFile)
      ->capture_default_str();
  app.add_option("--spec-rule", o->spec_rule,
                 "with --spec-part: the JCGM 106 decision rule for max/min figures")
      ->check(CLI::IsMember({"simple", "guarded", "risk"}))
      ->capture_default_str();
  if (accuracy) AddAccuracyOptions(app, &o->accuracy);
  app.add_option("--threads", o->threads, "worker threads (default: all cores)")
      ->check(CLI::NonNegativeNumber);
  if (accuracy) {
    app.add_flag("--stream", o->stream,
                 "read the record once in groups and evaluate each quantity from a temporary "
                 "file (memory independent of the length; docs/streaming.md)");
    app.add_option("--stream-above-memory-share", o->stream_above_memory_share,
                   "stream by itself when the file is larger than this share of the available "
                   "memory (0: never)")
        ->check(CLI::Range(0.0, 100.0))
        ->default_str("0.5");
    app.add_option("--stream-group-bytes", o->stream_group_bytes,
                   "with --stream: bytes of the file read per group of rows (memory is about 3 "
                   "to 15 times this, the more the narrower the rows)")
        ->check(CLI::PositiveNumber)
        ->default_str("8388608");
  }
}

}  // namespace

void AddAnalyzeOptions(CLI::App& app, int* exit_code) {
  auto o = std::make_shared<AnalyzeOptions>();
  AddTypeAOptions(app, o.get(), /*accuracy=*/true);
  app.callback([&app, o, exit_code] {
    if (!app.get_subcommands().empty()) return;
    if (o->session.empty()) {
      apps::PrintText(stderr, fmt::format("error: no session given\n{}", app.help()));
      *exit_code = kExitUsage;
      return;
    }
    if (Status s = CheckModeOptions(app, *o); !s.ok()) {
      *exit_code = PrintErrorExit(s.error());
      return;
    }
    *exit_code = RunAnalyze(*o);
  });
}

void AddAnalyzeCommand(CLI::App& app, int* exit_code) {
  auto o = std::make_shared<AnalyzeOptions>();
  CLI::App* sub = app.add_subcommand(
      "analyze",
      "GUM Type A evaluation of every quantity per tag, with --allan the noise terms, with "
      "--budget a budget on the session (also: characterize SESSION --type-a ...)");
  AddTypeAOptions(*sub, o.get(), /*accuracy=*/false);
  sub->callback([sub, o, exit_code] {
    if (Status s = CheckModeOptions(*sub, *o); !s.ok()) {
      *exit_code = PrintErrorExit(s.error());
      return;
    }
    *exit_code = RunAnalyze(*o);
  });
}

}  // namespace metro::apps
