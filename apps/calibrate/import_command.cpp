// calibrate import FILE --from kalibr|openvins|basalt|realsense|px4|ardupilot [--instance I]
//   [--sensor N] [--covariance FILE] [-o calibration.json]
// Another tool's intrinsics as calibration.json (interchange.hpp): what the format did not
// carry and every implausible constant named on stderr and in the tag's warnings; the
// uncertainties from the covariance sidecar (FILE.covariance.json when present) or unknown.
#include <memory>

#include "commands.hpp"
#include "metro/calibration/calibration_io.hpp"
#include "metro/calibration/interchange.hpp"
#include "metro/core/file.hpp"
#include "metro/core/utc_time.hpp"
#include "metro/core/version.hpp"
#include "unix_cli.hpp"

namespace metro::calibrate_app {
namespace {

struct ImportCliOptions {
  std::string file;
  std::string from;
  std::string output = "-";
  std::string covariance;  // The sidecar; empty: FILE.covariance.json when it exists.
  int instance = 0;
  int sensor = 1;
};

int RunImport(const ImportCliOptions& c) {
  const std::optional<InterchangeFormat> format = ParseInterchangeFormat(c.from);
  if (!format) {
    apps::PrintErrorText("--from '" + c.from +
                         "': expected kalibr, openvins, basalt, realsense, px4 or ardupilot");
    return kExitUsage;
  }
  Result<std::string> text = ReadFile(c.file);
  if (!text.ok()) return apps::PrintErrorExit(text.error());
  InterchangeReadOptions ro;
  ro.format = *format;
  ro.instance = c.instance;
  Result<InterchangeFile> file = ReadInterchangeFile(text.value(), ro, c.file);
  if (!file.ok()) return apps::PrintErrorExit(file.error());
  InterchangeImportOptions io;
  io.sensor = c.sensor;
  io.date_utc = UtcIso8601Now();
  io.tool_version = std::string(kToolName) + " " + kVersion;
  io.sidecar_file = c.covariance.empty() ? InterchangeSidecarPath(c.file) : c.covariance;
  if (!c.covariance.empty() || apps::OutputExists(io.sidecar_file)) {
    Result<std::string> sidecar = ReadFile(io.sidecar_file);
    if (!sidecar.ok()) return apps::PrintErrorExit(sidecar.error());
    io.sidecar_text = sidecar.value();
  }
  Result<InterchangeImport> imported = ImportInterchange(file.value(), io);
  if (!imported.ok()) return apps::PrintErrorExit(imported.error());
  for (const std::string& n : imported.value().not_carried) {
    apps::PrintWarning(c.file + ": not carried: " + n);
  }
  for (const std::string& f : imported.value().flags) apps::PrintWarning(c.file + ": " + f);
  if (!imported.value().uncertainty_known) {
    apps::PrintWarning(c.file + ": " +
                       imported.value().calibration.tags[0].accel->model_check->reason);
  }
  const std::string json = FormatCalibrationJson(imported.value().calibration);
  if (Status s = apps::WriteOutput(c.output, json); !s.ok()) return apps::PrintErrorExit(s.error());
  return 0;
}

}  // namespace

void AddImportCommand(CLI::App& app, int* exit_code) {
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
