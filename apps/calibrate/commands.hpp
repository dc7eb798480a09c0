// The calibrate subcommands. Each Add*Command registers its options and callback on the CLI11
// app; the callback runs the command and records its exit code.
#pragma once

#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <optional>
#include <string>

#include "exit_codes.hpp"
#include "metro/core/status.hpp"

namespace metro::calibrate_app {

using apps::kExitFailed;
using apps::kExitOk;
using apps::kExitUsage;

void AddFitCommand(CLI::App& app, int* exit_code);
void AddApplyCommand(CLI::App& app, int* exit_code);
void AddReportCommand(CLI::App& app, int* exit_code);
void AddBlobCommand(CLI::App& app, int* exit_code);
void AddInspectCommand(CLI::App& app, int* exit_code);
void AddPushCommand(CLI::App& app, int* exit_code);
void AddRegistryCommand(CLI::App& app, int* exit_code);
void AddExportCommand(CLI::App& app, int* exit_code);
void AddImportCommand(CLI::App& app, int* exit_code);
void AddStationCommand(CLI::App& app, int* exit_code);

// An error about calibration.json `calibration` as printed: at the file:line:column of the
// value when the library found it there (CalibrationErrorAt), else after the file's name.
inline std::string CalibrationErrorText(const std::string& calibration, const Error& error) {
  return error.file.empty() ? fmt::format("{}: {}", calibration, error.ToString())
                            : error.ToString();
}

// --profile mpu6050|generic, --accel-fs-g G, --gyro-fs-dps D of `blob` and `push`: the nominal
// sensitivity a blob section declares (metro::blob::SensorProfile, docs/calibration-blob.md 10).
inline void AddSensorProfileOptions(CLI::App* sub, std::string* profile,
                                    std::optional<double>* accel_fs_g,
                                    std::optional<double>* gyro_fs_dps) {
  sub->add_option("--profile", *profile,
                  "the IMU: mpu6050 (its datasheet sensitivity at the declared or matching "
                  "full-scale setting) or generic (another IMU: 32768 / the declared full scale, "
                  "else the calibration's own); default: the tags file's, else mpu6050")
      ->check(CLI::IsMember({"mpu6050", "generic"}));
  sub->add_option("--accel-fs-g", *accel_fs_g,
                  "declared accelerometer full scale [g] (mpu6050: 2, 4, 8 or 16; default: the "
                  "setting M matches)");
  sub->add_option("--gyro-fs-dps", *gyro_fs_dps,
                  "declared gyroscope full scale [deg/s] (mpu6050: 250, 500, 1000 or 2000; "
                  "default: the setting M matches)");
}

}  // namespace metro::calibrate_app
