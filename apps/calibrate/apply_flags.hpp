// The flags of `calibrate apply`.
// Included by main.cpp only: the program's one translation unit with CLI11 (issue #39).
#pragma once

#include <CLI/CLI.hpp>
#include <memory>

#include "apply_command.hpp"
#include "cli_flags.hpp"
#include "common_flags.hpp"

namespace metro::calibrate_app {

inline void AddApplyCommand(CLI::App& app, int* exit_code) {
  auto o = std::make_shared<ApplyOptions>();
  CLI::App* sub = app.add_subcommand(
      "apply",
      "write a session with calibrated ax_g.. and gx_dps.. columns (all rows and "
      "columns kept)");
  sub->add_option("calibration", o->calibration, "calibration.json")
      ->required()
      ->check(CLI::ExistingFile);
  sub->add_option("session", o->inputs, "SESSION (or ACC GYRO with --imutk); - reads stdin")
      ->required()
      ->check(apps::ExistingFileOrStdin());
  sub->add_option("-o,--output", o->output, "calibrated session.csv to write (- for stdout)")
      ->required();
  sub->add_flag("--imutk", o->imutk, "the session is an imu_tk pair: ACC GYRO");
  sub->add_option("--t-valid-min-c", o->t_valid_min_c,
                  "lower end of the temperature validity range, as given to calibrate blob "
                  "(default: the fitted span - 5 degC)");
  sub->add_option("--t-valid-max-c", o->t_valid_max_c,
                  "upper end of the temperature validity range (default: the fitted span + 5 "
                  "degC)");
  AddRegistryOptions(sub, &o->registry);
  AddTagsOption(sub, &o->tags);
  sub->callback([o, exit_code] { *exit_code = RunApply(*o); });
}

}  // namespace metro::calibrate_app
