// calibrate export calibration.json --to px4|ardupilot|kalibr|openvins|basalt|realsense
//   --sensor N [--instance I] [--px4-accel-device-id ID] [--px4-gyro-device-id ID]
//   [--covariance FILE] -o FILE
// A tag's constants as an autopilot's parameter file (autopilot_export.hpp) or an estimator's
// intrinsics (interchange.hpp); what the form cannot hold is named on stderr and in the file.
// The kalibr, openvins, basalt and realsense files come with a covariance sidecar
// (FILE.covariance.json, or --covariance FILE); px4 and ardupilot only with --covariance.
#include <memory>

#include "commands.hpp"
#include "metro/calibration/autopilot_export.hpp"
#include "metro/calibration/calibration_io.hpp"
#include "metro/calibration/interchange.hpp"
#include "unix_cli.hpp"

namespace metro::calibrate_app {
namespace {

struct ExportCliOptions {
  std::string calibration;
  std::string to;
  std::string output;
  std::string covariance;  // The sidecar; empty: the default (see above).
  AutopilotExportOptions options;
};

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

}  // namespace

void AddExportCommand(CLI::App& app, int* exit_code) {
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
