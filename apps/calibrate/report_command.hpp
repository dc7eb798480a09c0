// calibrate report CALIBRATION.json [--html CERT]: a readable summary of calibration.json.
// Its flags are bound in main.cpp, the program's one translation unit with CLI11.
#pragma once

#include <string>

namespace metro::calibrate_app {

struct ReportOptions {
  std::string calibration;
  std::string html;                    // Calibration certificate (docs/reports.md).
  std::string tags;                    // --tags FILE: the tags' names, device IDs and profiles.
  bool accept_rejected_model = false;  // --accept-rejected-model: certify them anyway.
};

int RunReport(const ReportOptions& o);

}  // namespace metro::calibrate_app
