// The main job: characterize analyze SESSION [windows] [--allan] [--budget B] [-o REPORT.json],
// also spelled characterize SESSION --type-a ... (the options on the top-level app, where
// --accuracy turns it into `characterize accuracy SESSION ...`).
#include "analyze_command.hpp"

#include <fmt/format.h>
#include <sys/stat.h>

#include <cstdio>
#include <optional>

#include "accuracy_command.hpp"
#include "analysis_options.hpp"
#include "cli_progress.hpp"
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

}  // namespace

// Options that do nothing in the chosen mode are refused, never silently ignored: the
// accuracy evaluation's own options without --accuracy; the Allan options without --allan;
// with --accuracy, the options only the Type A analysis uses.
Status CheckModeOptions(const OptionGiven& given, const AnalyzeOptions& o) {
  // `analyze` has no accuracy options: only the top-level spelling can be given them.
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

namespace {

// The outputs are checked before anything runs: none to stdout that cannot go there, none that
// names an input (the session, the budget and the sessions it names, the tags file).
Status CheckAnalyzeOutputs(const AnalyzeOptions& o) {
  for (Status s : {RefuseStdout(o.html, "--html", "the HTML report goes to a file"),
                   RefuseStdout(o.allan_csv, "--allan-csv", "the Allan curves go to a file")}) {
    if (!s.ok()) return s;
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
  return CheckOutputs({{"-o", o.output},
                       {"--allan-csv", o.allan_csv},
                       {"--html", o.html},
                       {"--export-file", o.export_file}},
                      inputs);
}

// --spec-part: the spec library, loaded before the analysis so that a part it does not have
// stops the run before the work (an empty library without --spec-part).
Result<SpecLibrary> LoadSpecOption(const AnalyzeOptions& o) {
  if (o.spec_part.empty()) return SpecLibrary{};
  Result<SpecLibrary> lib = LoadSpecLibrary(o.spec_library);
  if (!lib.ok()) return lib.error().WithContext("--spec-library");
  if (Result<const SpecPart*> p = lib.value().Find(o.spec_part); !p.ok()) {
    return p.error().WithContext("--spec-part");
  }
  return lib;
}

// The analysis, in memory or streamed (ChooseStreaming), with one progress line per stage on
// a terminal: load (bytes), Type A, Allan, Monte Carlo (trials).
Result<SessionAnalysis> Analyze(const AnalyzeOptions& o) {
  SessionAnalysisOptions options;
  if (Status s = MakeSessionAnalysisOptions(o.analysis, o.threads, &options); !s.ok()) {
    return s.error();
  }
  options.allan_csv = options.allan && !o.allan_csv.empty();
  options.budget_path = o.budget;
  options.stream_group_bytes = o.stream_group_bytes;
  const bool stream = ChooseStreaming(o);
  if (stream && !o.html.empty()) {
    return MakeError(
        "--html: the page plots the record's series, which are not available in streaming "
        "mode; run without --stream, or write the JSON report and render it with `characterize "
        "report`");
  }
  TerminalProgress progress(stderr, CliProgressOptions());
  options.progress = &progress;
  SessionAnalysis analysis =
      stream ? AnalyzeSessionStreamed(o.session, options) : AnalyzeSession(o.session, options);
  progress.Finish();
  if (!analysis.ok) return analysis.error;
  if (analysis.session.rejected_rows > 0) {
    Note(fmt::format("note: --lenient skipped {} malformed rows (first at line {})\n",
                     analysis.session.rejected_rows, analysis.session.rejected_lines.front()));
  }
  return analysis;
}

// What one analysis writes: the JSON report, the HTML page, the Allan CSV and the noise file of
// --export, with the errors of the parts that could not be made (the report is still written).
struct AnalyzeOutputs {
  std::string json;
  std::string html;
  std::string allan_csv_path;  // Empty when no Allan curve was computed.
  std::string exported;
  std::optional<Error> spec_error;
  std::optional<Error> export_error;
};

// Adds the --spec-part decisions to the report and renders it: JSON, HTML, the --export file.
Result<AnalyzeOutputs> RenderOutputs(SessionAnalysis* analysis, const SpecLibrary& spec_library,
                                     const AnalyzeOptions& o) {
  AnalyzeOutputs out;
  if (!o.spec_part.empty()) {
    Result<SpecDecisions> d = SpecDecisionsOf(*analysis, spec_library, o);
    if (d.ok()) {
      analysis->report.spec = std::move(d).value();
    } else {
      out.spec_error = d.error().WithContext("--spec-part " + o.spec_part);
    }
  }
  out.json = ToJson(analysis->report) + "\n";
  if (!o.html.empty()) {
    Result<std::string> rendered = RenderSessionAnalysisHtml(*analysis);
    // The page of the analysis just made: a failure is the run's, not the input's.
    if (!rendered.ok()) return rendered.error().WithKind(ErrorKind::kFailed);
    out.html = std::move(rendered).value();
  }
  // No curve at all: no --allan-csv (an empty file would read as an analysis that ran).
  if (!analysis->allan_csv.empty()) out.allan_csv_path = o.allan_csv;
  // --export: a term the record did not resolve is refused by name (exit 2); the report is
  // still written, the noise file is not.
  if (!o.export_format.empty()) {
    Result<std::string> text = ExportText(*analysis, o);
    if (text.ok()) {
      out.exported = std::move(text).value();
    } else {
      out.export_error = text.error();
    }
  }
  return out;
}

// Failures and warnings of the analysis on stderr (issue #21: an analysis asked for that
// produced nothing for a quantity says so).
void PrintAnalysisProblems(const SessionAnalysis& analysis, const AnalyzeOutputs& out,
                           const AnalyzeOptions& o) {
  for (const std::string& f : analysis.failures) PrintErrorText(f);
  for (const std::string& w : analysis.warnings) PrintWarning(w);
  if (!o.allan_csv.empty() && out.allan_csv_path.empty()) {
    PrintErrorText(
        fmt::format("--allan-csv {}: not written, no Allan curve was computed", o.allan_csv));
  }
}

// The table (or, without one, the report's warnings), then the exit code: 1 when --allan
// produced nothing, 2 for a --spec-part or --export that could not be made.
int FinishAnalyze(const SessionAnalysis& analysis, const AnalyzeOutputs& out,
                  const AnalyzeOptions& o) {
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
  if (out.spec_error) return PrintErrorExit(*out.spec_error);
  if (out.export_error) {
    return PrintErrorExit(
        out.export_error->WithContext("--export " + o.export_format + ": not written"));
  }
  return kExitOk;
}

}  // namespace

int RunAnalyze(const AnalyzeOptions& o) {
  if (o.accuracy.enabled) {
    const AnalysisCliOptions& a = o.analysis;
    return RunAccuracy(o.accuracy,
                       {o.session, a.load, a.sensors, o.output, a.window.settle_auto, o.threads,
                        o.type_a, o.html, AccuracyWindow(a), a.tag_registry});
  }
  if (Status s = CheckAnalyzeOutputs(o); !s.ok()) return PrintErrorExit(s.error());
  Result<SpecLibrary> spec_library = LoadSpecOption(o);
  if (!spec_library.ok()) return PrintErrorExit(spec_library.error());
  Result<SessionAnalysis> analysis = Analyze(o);
  if (!analysis.ok()) return PrintErrorExit(analysis.error());
  Result<AnalyzeOutputs> out = RenderOutputs(&analysis.value(), spec_library.value(), o);
  if (!out.ok()) return PrintErrorExit(out.error());
  PrintAnalysisProblems(analysis.value(), out.value(), o);
  // The JSON (no -o: to stdout, with no table), the Allan CSV, the HTML and the noise file are
  // replaced together or not at all.
  const AnalyzeOutputs& w = out.value();
  if (Status s = WriteOutputs({{o.output.empty() ? "-" : o.output, w.json},
                               {w.allan_csv_path, analysis.value().allan_csv},
                               {o.html, w.html},
                               {w.export_error ? std::string() : o.export_file, w.exported}});
      !s.ok()) {
    return PrintErrorExit(s.error());
  }
  return FinishAnalyze(analysis.value(), w, o);
}

}  // namespace metro::apps
