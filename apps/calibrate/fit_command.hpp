// calibrate fit SESSION... -o calibration.json [--html CERT] [--thermal]: the calibration of
// every tag with the uncertainty of every constant (docs/calibration-model.md, docs/thermal.md).
// Its flags are bound in main.cpp, the program's one translation unit with CLI11.
#pragma once

#include <string>
#include <vector>

#include "conformity_cli.hpp"
#include "load_cli.hpp"
#include "metro/calibration/calibrate.hpp"
#include "metro/calibration/thermal_fit.hpp"
#include "registry_hooks.hpp"

namespace metro::calibrate_app {

struct FitOptions {
  std::vector<std::string> inputs;
  std::string output;
  bool imutk = false;  // Inputs are imu_tk pairs: ACC GYRO [ACC GYRO ...].
  // --sensor, --model, --accel-model, --gyro-model, --gravity-mps2, --accel-fs-g, --gyro-fs-dps,
  // --temperature, --loss, --loss-scale, --accel-only, --min-static-s: the library's options
  // and defaults, bound directly (--accel-model none is fit_accel = false).
  CalibrationOptions calibration;
  std::string segments;                // Annotated segments instead of the detector.
  std::string html;                    // Calibration certificate (docs/reports.md).
  bool accept_rejected_model = false;  // --accept-rejected-model: certify them anyway.
  std::string tags;                    // --tags FILE: device IDs into calibration.json.
  apps::LoadCliOptions load;    // --format, --column, --rate-hz, ... (--accel-fs-g is fit's).
  SpecCliOptions spec;          // --spec, --fail-on-nonconformity (docs/conformity.md)
  RegistryCliOptions registry;  // --registry, --station, --operator (docs/registry.md)
  // --thermal: bias versus temperature from one static record per tag (docs/thermal.md).
  bool thermal = false;
  ThermalFitOptions thermal_options;
};

int RunFit(const FitOptions& o);

}  // namespace metro::calibrate_app
