// calibrate report calibration.json
#include <fmt/format.h>

#include <memory>

#include "commands.hpp"
#include "metro/calibration/calibration_io.hpp"

namespace metro::calibrate_app {
namespace {

struct ReportOptions {
  std::string calibration;
};

int RunReport(const ReportOptions& r) {
  Result<Calibration> cal = LoadCalibration(r.calibration);
  if (!cal.ok()) {
    fmt::print(stderr, "error: {}\n", cal.error().ToString());
    return kExitUsage;
  }
  fmt::print("{}", FormatCalibrationReport(cal.value()));
  return kExitOk;
}

}  // namespace

void AddReportCommand(CLI::App& app, int* exit_code) {
  auto o = std::make_shared<ReportOptions>();
  CLI::App* sub = app.add_subcommand("report", "print a readable summary of calibration.json");
  sub->add_option("calibration", o->calibration, "calibration.json")
      ->required()
      ->check(CLI::ExistingFile);
  sub->callback([o, exit_code] { *exit_code = RunReport(*o); });
}

}  // namespace metro::calibrate_app
