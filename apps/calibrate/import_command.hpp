// calibrate import FILE --from FORMAT -o calibration.json: another tool's calibration as
// calibration.json (docs/calibration-interchange.md).
// Its flags are bound in main.cpp, the program's one translation unit with CLI11.
#pragma once

#include <string>

namespace metro::calibrate_app {

struct ImportCliOptions {
  std::string file;
  std::string from;
  std::string output = "-";
  std::string covariance;  // The sidecar; empty: FILE.covariance.json when it exists.
  int instance = 0;
  int sensor = 1;
};

int RunImport(const ImportCliOptions& o);

}  // namespace metro::calibrate_app
