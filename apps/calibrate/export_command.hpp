// calibrate export CALIBRATION.json --to FORMAT: a calibration in another tool's format
// (docs/calibration-interchange.md).
// Its flags are bound in main.cpp, the program's one translation unit with CLI11.
#pragma once

#include <string>

#include "metro/calibration/autopilot_export.hpp"

namespace metro::calibrate_app {

struct ExportCliOptions {
  std::string calibration;
  std::string to;
  std::string output;
  std::string covariance;  // The sidecar; empty: the default (see above).
  AutopilotExportOptions options;
};

int RunExport(const ExportCliOptions& o);

}  // namespace metro::calibrate_app
