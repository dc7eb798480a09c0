// The flags of `calibrate export`.
// Included by main.cpp only: the program's one translation unit with CLI11 (issue #39).
#pragma once

#include <CLI/CLI.hpp>
#include <memory>

#include "cli_flags.hpp"
#include "export_command.hpp"

namespace metro::calibrate_app {

inline void AddExportCommand(CLI::App& app, int* exit_code) {
  auto o = std::make_shared<ExportCliOptions>();
  CLI::App* sub = app.add_subcommand(
      "export",
      "write a tag's constants as an autopilot's parameters (PX4 CAL_ACCn_/CAL_GYROn_, ArduPilot "
      "INS_ACC*/INS_GYR*) or an estimator's intrinsics (Kalibr, OpenVINS, basalt, librealsense); "
      "what the form cannot hold is named (docs/calibration-interchange.md)");
  sub->add_option("CALIBRATION", o->calibration, "calibration.json")
      ->required()
      ->check(CLI::ExistingFile);
  sub->add_option("--to", o->to,
                  "px4 (QGroundControl .params), ardupilot (.param), kalibr (imu-chain yaml), "
                  "openvins (kalibr_imu_chain.yaml), basalt (calibration.json keys), realsense "
                  "(rs-imu-calibration's calibration.json)")
      ->required();
  sub->add_option("--sensor", o->options.sensor, "the tag in calibration.json")->required();
  sub->add_option("--instance", o->options.instance,
                  "the autopilot's IMU index (PX4 0..3: CAL_ACC<i>_; ArduPilot 0..2: INS_ACC, "
                  "INS_ACC2, INS_ACC3; default 0); kalibr/openvins: imu<i>; realsense: imus[i]");
  sub->add_option("--px4-accel-device-id", o->options.px4_accel_device_id,
                  "PX4's device ID of the accelerometer (CAL_ACCn_ID; PX4 applies the values "
                  "only to that device)");
  sub->add_option("--px4-gyro-device-id", o->options.px4_gyro_device_id,
                  "PX4's device ID of the gyroscope (CAL_GYROn_ID)");
  sub->add_option("--covariance", o->covariance,
                  "the covariance sidecar to write (default for kalibr, openvins, basalt, "
                  "realsense: FILE.covariance.json; px4, ardupilot: only when given)");
  sub->add_option("-o,--output", o->output, "the file to write (- for stdout)")->required();
  sub->callback([o, exit_code] { *exit_code = RunExport(*o); });
}

}  // namespace metro::calibrate_app
