// The characterize subcommands. Each Add*Command registers its options and callback on
// the CLI11 app; the callback runs the command and records its exit code.
#pragma once

#include <CLI/CLI.hpp>

#include "exit_codes.hpp"

namespace metro::apps {

// The main job spelled without a subcommand: `characterize SESSION --type-a ...` (and
// `characterize SESSION --accuracy ...`), the options on the top-level app.
void AddAnalyzeOptions(CLI::App& app, int* exit_code);
// `characterize analyze SESSION ...`: the same Type A analysis as a subcommand.
void AddAnalyzeCommand(CLI::App& app, int* exit_code);
// `characterize accuracy SESSION ...` is in accuracy_command.hpp.
void AddConvertCommand(CLI::App& app, int* exit_code);
void AddSimulateCommand(CLI::App& app, int* exit_code);
// `characterize batch` and `characterize report REPORT.json --html FILE` (docs/reports.md).
void AddBatchCommand(CLI::App& app, int* exit_code);
void AddReportCommand(CLI::App& app, int* exit_code);
// `characterize capture --port DEV -o capture.txt` (docs/capture.md).
void AddCaptureCommand(CLI::App& app, int* exit_code);
// `characterize noise-export REPORT.json --to FORMAT` and `noise-compare FILE REPORT.json`
// (docs/noise.md "Export to estimators").
void AddNoiseExportCommand(CLI::App& app, int* exit_code);
void AddNoiseCompareCommand(CLI::App& app, int* exit_code);
// `characterize topics FILE.ulg`: a PX4 ULog's topics (docs/cli.md "topics").
void AddTopicsCommand(CLI::App& app, int* exit_code);

}  // namespace metro::apps
