// calibrate export calibration.json --to px4|ardupilot|kalibr|openvins|basalt|realsense
//   --sensor N [--instance I] [--px4-accel-device-id ID] [--px4-gyro-device-id ID]
//   [--covariance FILE] -o FILE
// A tag's constants as an autopilot's parameter file (autopilot_export.hpp) or an estimator's
// intrinsics (interchange.hpp); what the form cannot hold is named on stderr and in the file.
// The kalibr, openvins, basalt and realsense files come with a covariance sidecar
// (FILE.covariance.json, or --covariance FILE); px4 and ardupilot only with --covariance.
#include "export_command.hpp"

#include <memory>

#include "commands.hpp"
#include "metro/calibration/autopilot_export.hpp"
#include "metro/calibration/calibration_io.hpp"
#include "metro/calibration/interchange.hpp"
#include "unix_cli.hpp"

namespace metro::calibrate_app {
namespace {

int RunAutopilotExport(const ExportCliOptions& c, AutopilotFormat format, const Calibration& cal) {
  AutopilotExportOptions o = c.options;
  o.format = format;
  Result<AutopilotExport> exported = ExportAutopilotParameters(cal, o);
  if (!exported.ok()) return apps::PrintErrorExit(exported.error());
  for (const std::string& w : exported.value().warnings) apps::PrintWarning(w);
  std::string sidecar;
  if (!c.covariance.empty()) {
    InterchangeExportOptions io;
    io.format =
        format == AutopilotFormat::kPx4 ? InterchangeFormat::kPx4 : InterchangeFormat::kArduPilot;
    io.sensor = o.sensor;
    io.instance = o.instance;
    Result<InterchangeExport> values = ExportInterchange(cal, io);
    if (!values.ok()) return apps::PrintErrorExit(values.error());
    sidecar = InterchangeSidecarJson(values.value(), c.output, c.calibration, o.sensor);
  }
  if (Status s = apps::WriteOutputs({{c.output, exported.value().text}, {c.covariance, sidecar}});
      !s.ok()) {
    return apps::PrintErrorExit(s.error());
  }
  return 0;
}

}  // namespace

int RunExport(const ExportCliOptions& c) {
  const std::optional<InterchangeFormat> format = ParseInterchangeFormat(c.to);
  if (!format) {
    apps::PrintErrorText(
        "--to '" + c.to +
        "': expected px4 or ardupilot (autopilots), or kalibr, openvins, basalt or "
        "realsense (estimators)");
    return kExitUsage;
  }
  Result<Calibration> cal = LoadCalibration(c.calibration);
  if (!cal.ok()) return apps::PrintErrorExit(cal.error());
  if (const std::optional<AutopilotFormat> ap = ParseAutopilotFormat(c.to)) {
    return RunAutopilotExport(c, *ap, cal.value());
  }
  InterchangeExportOptions o;
  o.format = *format;
  o.sensor = c.options.sensor;
  o.instance = c.options.instance;
  Result<InterchangeExport> exported = ExportInterchange(cal.value(), o);
  if (!exported.ok()) return apps::PrintErrorExit(exported.error());
  for (const std::string& w : exported.value().warnings) apps::PrintWarning(w);
  const std::string sidecar_path = !exported.value().uncertainty_known ? std::string()
                                   : !c.covariance.empty()             ? c.covariance
                                   : apps::IsStdio(c.output)           ? std::string()
                                                             : InterchangeSidecarPath(c.output);
  const std::string sidecar =
      sidecar_path.empty()
          ? std::string()
          : InterchangeSidecarJson(exported.value(), c.output, c.calibration, o.sensor);
  if (Status s = apps::WriteOutputs({{c.output, exported.value().text}, {sidecar_path, sidecar}});
      !s.ok()) {
    return apps::PrintErrorExit(s.error());
  }
  return 0;
}

}  // namespace metro::calibrate_app
