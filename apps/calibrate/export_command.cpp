// calibrate export calibration.json --to px4|ardupilot --sensor N [--instance I]
//   [--px4-accel-device-id ID] [--px4-gyro-device-id ID] -o FILE
// A tag's constants as an autopilot's parameter file (autopilot_export.hpp); what the
// autopilot's form cannot hold is named on stderr and in the file.
#include <memory>

#include "commands.hpp"
#include "metro/calibration/autopilot_export.hpp"
#include "metro/calibration/calibration_io.hpp"
#include "unix_cli.hpp"

namespace metro::calibrate_app {
namespace {

struct ExportCliOptions {
  std::string calibration;
  std::string to;
  std::string output;
  AutopilotExportOptions options;
};

int RunExport(ExportCliOptions c) {
  const std::optional<AutopilotFormat> format = ParseAutopilotFormat(c.to);
  if (!format) {
    apps::PrintErrorText("--to '" + c.to + "': expected px4 or ardupilot");
    return kExitUsage;
  }
  c.options.format = *format;
  Result<Calibration> cal = LoadCalibration(c.calibration);
  if (!cal.ok()) return apps::PrintErrorExit(cal.error());
  Result<AutopilotExport> exported = ExportAutopilotParameters(cal.value(), c.options);
  if (!exported.ok()) return apps::PrintErrorExit(exported.error());
  for (const std::string& w : exported.value().warnings) apps::PrintWarning(w);
  if (Status s = apps::WriteOutput(c.output, exported.value().text); !s.ok()) {
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
      "INS_ACC*/INS_GYR*); what the autopilot cannot hold is named (docs/calibration-model.md)");
  sub->add_option("CALIBRATION", o->calibration, "calibration.json")
      ->required()
      ->check(CLI::ExistingFile);
  sub->add_option("--to", o->to, "px4 (QGroundControl .params) or ardupilot (.param)")->required();
  sub->add_option("--sensor", o->options.sensor, "the tag in calibration.json")->required();
  sub->add_option("--instance", o->options.instance,
                  "the autopilot's IMU index (PX4 0..3: CAL_ACC<i>_; ArduPilot 0..2: INS_ACC, "
                  "INS_ACC2, INS_ACC3; default 0)");
  sub->add_option("--px4-accel-device-id", o->options.px4_accel_device_id,
                  "PX4's device ID of the accelerometer (CAL_ACCn_ID; PX4 applies the values "
                  "only to that device)");
  sub->add_option("--px4-gyro-device-id", o->options.px4_gyro_device_id,
                  "PX4's device ID of the gyroscope (CAL_GYROn_ID)");
  sub->add_option("-o,--output", o->output, "the parameter file to write (- for stdout)")
      ->required();
  sub->callback([o, exit_code] { *exit_code = RunExport(*o); });
}

}  // namespace metro::calibrate_app
