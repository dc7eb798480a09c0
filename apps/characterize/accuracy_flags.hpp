// The flags of `characterize accuracy` and of --accuracy on the top-level app.
// Included by main.cpp only: the program's one translation unit with CLI11 (issue #39).
#pragma once

#include <CLI/CLI.hpp>
#include <memory>

#include "accuracy_command.hpp"
#include "analysis_flags.hpp"
#include "cli_flags.hpp"

namespace metro::apps {

inline void AddAccuracyOptions(CLI::App& app, AccuracyCliOptions* o) {
  app.add_flag("--accuracy", o->enabled,
               "accuracy against a rotation table: plateaus, error curve, hysteresis, budget "
               "(docs/accuracy.md)");
  app.add_option("--table-axis", o->table_axis, "the tag axis the table turns")
      ->type_name("TEXT:{yaw,pitch,roll}")
      ->capture_default_str();
  app.add_option("--reference", o->reference,
                 "separate reference log (t_s, table_angle_deg), aligned on t_s; - reads stdin")
      ->check(ExistingFileOrStdin());
  app.add_option("--reference-u", o->reference_u,
                 "the table's standard uncertainty in deg, or a budget file for it "
                 "(docs/budget-format.md)");
  app.add_option("--reference-offset-s", o->library.alignment.offset_s,
                 "reference clock minus tag clock in s (default: estimated)");
  app.add_option("--error-model", o->model,
                 "the fitted error curve (auto: the order the data support; docs/accuracy.md)")
      ->type_name("TEXT:{auto,linear,harmonic1,harmonic2}")
      ->capture_default_str();
  app.add_option("--min-dwell-s", o->library.plateaus.min_dwell_s,
                 "shortest table rest that is a plateau")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_option("--settle-s", o->library.plateaus.settle_s,
                 "seconds dropped after the table stops")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app.add_option("--plateau-tolerance-deg", o->library.plateaus.tolerance_deg,
                 "largest reference change within a plateau")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app.add_option("--assumed-hysteresis-deg", o->library.assumed_hysteresis_deg,
                 "hysteresis the corrected U assumes when no angle was visited both ways")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app.add_option("--lag-tau-s", o->library.lag_tau_s,
                 "the tag's response time in s (default: estimated from the motion)")
      ->check(CLI::NonNegativeNumber);
  app.add_flag("--no-lag-model", o->no_lag_model,
               "do not model the tag's lag: plateaus settle by --settle-s alone");
  app.add_flag("--keep-departures", o->keep_departures,
               "keep a plateau's start and end where the tag's error departs from its level "
               "(default: trimmed and said so)");
}

inline void AddAccuracyCommand(CLI::App& app, int* exit_code) {
  auto o = std::make_shared<AccuracyCommandOptions>();
  CLI::App* sub = app.add_subcommand(
      "accuracy",
      "accuracy of a tag against a rotation table: plateaus, error curve, hysteresis, budget "
      "(docs/accuracy.md; also: characterize SESSION --accuracy ...)");
  sub->add_option("session", o->session, "session.csv or receiver capture; - reads stdin")
      ->required()
      ->check(ExistingFileOrStdin());
  AddAnalysisCliOptions(sub, &o->analysis, AnalysisCliKind::kAccuracy);
  sub->add_option("-o,--output", o->output,
                  "write the JSON report here (atomically) and print a table to stdout; -o - "
                  "writes it to stdout and the table to stderr (default: the JSON to stdout)");
  sub->add_option("--html", o->html, "also write the HTML view here (docs/reports.md)");
  AddAccuracyOptions(*sub, &o->accuracy);
  sub->add_option("--threads", o->threads, "worker threads (default: all cores)")
      ->check(CLI::NonNegativeNumber);
  sub->callback([o, exit_code] { *exit_code = RunAccuracyCommand(*o); });
}

}  // namespace metro::apps
