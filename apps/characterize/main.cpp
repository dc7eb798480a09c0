// characterize: GUM Type A/Type B evaluation, Monte Carlo and noise analysis of IMU tag
// sessions. A dispatch table: each subcommand's flags are bound to its options struct in its
// *_flags.hpp, the work is done by its Run function (*_command.hpp) and the metro library.
// This is the program's one translation unit with CLI11 (issue #39: CLI11 is header-only and
// costs seconds of compile time per file that includes it).
#include <CLI/CLI.hpp>
#include <cstdio>
#include <memory>
#include <new>

#include "accuracy_flags.hpp"
#include "analysis_flags.hpp"
#include "analyze_flags.hpp"
#include "batch_flags.hpp"
#include "budget_flags.hpp"
#include "capture_flags.hpp"
#include "convert_flags.hpp"
#include "noise_compare_flags.hpp"
#include "noise_export_flags.hpp"
#include "report_flags.hpp"
#include "simulate_flags.hpp"
#include "topics_flags.hpp"

int main(int argc, char** argv) {
  // SIGINT/SIGTERM remove the temporaries of outputs being written; SIGXFSZ is ignored.
  metro::InstallInterruptCleanup();
  CLI::App app{"metro characterize: uncertainty evaluation of IMU sensor-tag sessions"};
  app.require_subcommand(0, 1);
  int exit_code = metro::apps::kExitOk;
  metro::apps::AddAnalyzeOptions(app, &exit_code);  // characterize SESSION --type-a|--accuracy
  metro::apps::AddAnalyzeCommand(app, &exit_code);
  metro::apps::AddAccuracyCommand(app, &exit_code);
  metro::apps::AddConvertCommand(app, &exit_code);
  metro::apps::AddSimulateCommand(app, &exit_code);
  metro::apps::AddBudgetCommand(app, &exit_code);
  metro::apps::AddBatchCommand(app, &exit_code);
  metro::apps::AddReportCommand(app, &exit_code);
  metro::apps::AddCaptureCommand(app, &exit_code);
  metro::apps::AddNoiseExportCommand(app, &exit_code);
  metro::apps::AddNoiseCompareCommand(app, &exit_code);
  metro::apps::AddTopicsCommand(app, &exit_code);
  metro::apps::AddVersionFlag(app, "characterize");
  metro::apps::AddQuietFlag(app);  // On the app and every subcommand (docs/unix.md).
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return metro::apps::FinishStdout(code == 0 ? 0 : metro::apps::kExitUsage);
  } catch (const std::bad_alloc&) {
    // The loaders turn this into an error naming the file; anything else that runs out.
    std::fputs("error: out of memory\n", stderr);
    return metro::apps::kExitFailed;
  }
  return metro::apps::FinishStdout(exit_code);
}
