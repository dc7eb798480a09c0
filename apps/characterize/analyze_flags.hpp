// The flags of the main job: `characterize SESSION --type-a ...` and `characterize analyze`.
// Included by main.cpp only: the program's one translation unit with CLI11 (issue #39).
#pragma once

#include <CLI/CLI.hpp>
#include <memory>

#include "accuracy_flags.hpp"
#include "analysis_flags.hpp"
#include "analyze_command.hpp"
#include "cli_flags.hpp"
#include "noise_export_flags.hpp"

namespace metro::apps {

// CheckModeOptions' view of a parsed command line.
inline OptionGiven GivenOn(const CLI::App& app) {
  return [&app](const std::string& name) {
    return app.get_option_no_throw(name) != nullptr && app.count(name) > 0;
  };
}

// SESSION and the Type A options, on the top-level app (`accuracy`: also the accuracy
// options, for the --accuracy spelling) or on the `analyze` subcommand.
inline void AddTypeAOptions(CLI::App& app, AnalyzeOptions* o, bool accuracy) {
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

inline void AddAnalyzeOptions(CLI::App& app, int* exit_code) {
  auto o = std::make_shared<AnalyzeOptions>();
  AddTypeAOptions(app, o.get(), /*accuracy=*/true);
  app.callback([&app, o, exit_code] {
    if (!app.get_subcommands().empty()) return;
    if (o->session.empty()) {
      apps::PrintText(stderr, fmt::format("error: no session given\n{}", app.help()));
      *exit_code = kExitUsage;
      return;
    }
    if (Status s = CheckModeOptions(GivenOn(app), *o); !s.ok()) {
      *exit_code = PrintErrorExit(s.error());
      return;
    }
    *exit_code = RunAnalyze(*o);
  });
}

inline void AddAnalyzeCommand(CLI::App& app, int* exit_code) {
  auto o = std::make_shared<AnalyzeOptions>();
  CLI::App* sub = app.add_subcommand(
      "analyze",
      "GUM Type A evaluation of every quantity per tag, with --allan the noise terms, with "
      "--budget a budget on the session (also: characterize SESSION --type-a ...)");
  AddTypeAOptions(*sub, o.get(), /*accuracy=*/false);
  sub->callback([sub, o, exit_code] {
    if (Status s = CheckModeOptions(GivenOn(*sub), *o); !s.ok()) {
      *exit_code = PrintErrorExit(s.error());
      return;
    }
    *exit_code = RunAnalyze(*o);
  });
}

}  // namespace metro::apps
