// The main job: characterize analyze SESSION [windows] [--allan] [--budget B] [-o REPORT.json],
// also spelled characterize SESSION --type-a ... (the options on the top-level app, where
// --accuracy turns it into `characterize accuracy SESSION ...`). Its flags are bound in
// main.cpp, the program's one translation unit with CLI11.
#pragma once

#include <cstddef>
#include <functional>
#include <string>

#include "accuracy_command.hpp"
#include "analysis_options.hpp"
#include "metro/core/status.hpp"
#include "metro/noise/noise_export.hpp"
#include "noise_export_options.hpp"

namespace metro::apps {

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

// Whether the option `name` (e.g. "--allan") was given on the command line.
using OptionGiven = std::function<bool(const std::string& name)>;

// Options that do nothing in the chosen mode are refused, never silently ignored: the
// accuracy evaluation's own options without --accuracy; the Allan options without --allan;
// with --accuracy, the options only the Type A analysis uses.
Status CheckModeOptions(const OptionGiven& given, const AnalyzeOptions& o);

// Runs the analysis (or, with --accuracy, the accuracy evaluation); the exit code.
int RunAnalyze(const AnalyzeOptions& o);

}  // namespace metro::apps
