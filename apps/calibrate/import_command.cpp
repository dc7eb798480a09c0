// calibrate import FILE --from kalibr|openvins|basalt|realsense|px4|ardupilot [--instance I]
//   [--sensor N] [--covariance FILE] [-o calibration.json]
// Another tool's intrinsics as calibration.json (interchange.hpp): what the format did not
// carry and every implausible constant named on stderr and in the tag's warnings; the
// uncertainties from the covariance sidecar (FILE.covariance.json when present) or unknown.
#include "import_command.hpp"

#include <memory>

#include "commands.hpp"
#include "metro/calibration/calibration_io.hpp"
#include "metro/calibration/interchange.hpp"
#include "metro/core/file.hpp"
#include "metro/core/utc_time.hpp"
#include "metro/core/version.hpp"
#include "unix_cli.hpp"

namespace metro::calibrate_app {
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

}  // namespace metro::calibrate_app
