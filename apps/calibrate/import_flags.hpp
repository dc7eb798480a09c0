// The flags of `calibrate import`.
// Included by main.cpp only: the program's one translation unit with CLI11 (issue #39).
#pragma once

#include <CLI/CLI.hpp>
#include <memory>

#include "cli_flags.hpp"
#include "import_command.hpp"

namespace metro::calibrate_app {

inline void AddImportCommand(CLI::App& app, int* exit_code) {
  auto o = std::make_shared<ImportCliOptions>();
  CLI::App* sub = app.add_subcommand(
      "import",
      "read another tool's intrinsics (Kalibr, OpenVINS, basalt, librealsense, PX4, ArduPilot) "
      "as calibration.json; what the format did not carry and implausible constants are named "
      "(docs/calibration-interchange.md)");
  sub->add_option("FILE", o->file, "the tool's file")->required()->check(CLI::ExistingFile);
  sub->add_option("--from", o->from, "kalibr, openvins, basalt, realsense, px4 or ardupilot")
      ->required();
  sub->add_option("--instance", o->instance,
                  "imu<i> (kalibr, openvins), imus[i] (realsense), the autopilot's IMU index "
                  "(default 0)");
  sub->add_option("--sensor", o->sensor, "the tag number calibration.json gets (default 1)");
  sub->add_option("--covariance", o->covariance,
                  "the covariance sidecar (default FILE.covariance.json when it exists; "
                  "without one the uncertainties are unknown)");
  sub->add_option("-o,--output", o->output, "calibration.json to write (default - for stdout)");
  sub->callback([o, exit_code] { *exit_code = RunImport(*o); });
}

}  // namespace metro::calibrate_app
