// calibrate apply calibration.json SESSION -o calibrated.csv [--t-valid-min-c C]
//   [--t-valid-max-c C] [--tags FILE]
#include "apply_command.hpp"

#include <fmt/format.h>

#include <memory>
#include <optional>

#include "commands.hpp"
#include "metro/calibration/calibration_io.hpp"
#include "metro/core/file.hpp"
#include "metro/io/session_io.hpp"
#include "registry_hooks.hpp"
#include "tags_cli.hpp"
#include "tags_names.hpp"
#include "unix_cli.hpp"

namespace metro::calibrate_app {
namespace {

// The inputs and the output, checked before anything is read: one session (imu_tk: a pair),
// stdin read once, the output none of the inputs nor the registry's files.
Status CheckApplyFiles(const ApplyOptions& a) {
  if (a.inputs.size() != (a.imutk ? 2u : 1u)) {
    return MakeError("apply takes one SESSION (or ACC GYRO with --imutk)");
  }
  if (Status s = apps::CheckStdinInputs(a.inputs, a.imutk); !s.ok()) return s;
  std::vector<apps::NamedPath> inputs = {{"CALIBRATION", a.calibration}, {"--tags", a.tags}};
  for (const std::string& in : a.inputs) inputs.push_back({"SESSION", in});
  return apps::CheckOutputs({{"-o", a.output}}, inputs, RegistryFiles(a.registry.url));
}

// The validity ranges' warnings and the samples outside a range always print; a session
// entirely within its ranges is a note.
void PrintApplyTemperatures(const ApplySummary& summary) {
  for (const std::string& w : summary.warnings) apps::PrintWarning(w);
  for (const SensorTemperatureCount& t : summary.temperature) {
    if (t.outside() > 0 || t.missing > 0) {
      apps::PrintText(stderr, t.Describe() + "\n");
    } else {
      apps::Note(t.Describe() + "\n");
    }
  }
}

}  // namespace

int RunApply(const ApplyOptions& a) {
  if (Status s = CheckApplyFiles(a); !s.ok()) return apps::PrintErrorExit(s.error());
  std::optional<TagRegistry> tags;
  Result<Calibration> cal = LoadCalibrationWithTags(a.calibration, a.tags, &tags);
  if (!cal.ok()) return apps::PrintErrorExit(cal.error());
  OpenedRegistry registry = OpenRegistryOption(a.registry);
  if (registry.exit_code != 0) return registry.exit_code;
  Result<Session> session =
      a.imutk ? LoadImuTk(a.inputs[0], a.inputs[1]) : LoadSession(a.inputs[0]);
  if (!session.ok()) return apps::PrintErrorExit(session.error());
  Session s = std::move(session).value();
  ApplyCalibrationOptions options;
  options.validity.t_valid_min_c = a.t_valid_min_c;
  options.validity.t_valid_max_c = a.t_valid_max_c;
  Result<ApplySummary> summary = ApplyCalibration(cal.value(), &s, options);
  if (!summary.ok()) return apps::PrintErrorExit(summary.error());
  PrintApplyTemperatures(summary.value());
  if (Status w = apps::WriteOutput(a.output, FormatSessionCsv(s, true)); !w.ok()) {
    return apps::PrintErrorExit(w.error());
  }
  apps::Note(fmt::format("wrote {}: {} tags, {} rows calibrated\n",
                         apps::IsStdio(a.output) ? "stdout" : a.output,
                         summary.value().tags_calibrated, summary.value().rows));
  if (tags) {
    apps::Note(fmt::format("calibrations applied ({}):\n{}", a.tags,
                           apps::CalibrationTagLines(cal.value())));
  }
  return RecordAppliedCalibration(registry.registry.get(), cal.value(), a.calibration, a.registry);
}

}  // namespace metro::calibrate_app
