// calibrate apply calibration.json SESSION -o calibrated.csv
#include <fmt/format.h>

#include <memory>

#include "commands.hpp"
#include "metro/calibration/calibration_io.hpp"
#include "metro/core/file.hpp"
#include "metro/io/session_io.hpp"
#include "unix_cli.hpp"

namespace metro::calibrate_app {
namespace {

struct ApplyOptions {
  std::string calibration;
  std::vector<std::string> inputs;  // SESSION, or ACC GYRO with --imutk.
  std::string output;
  bool imutk = false;
};

int RunApply(const ApplyOptions& a) {
  if (a.inputs.size() != (a.imutk ? 2u : 1u)) {
    apps::PrintErrorText("apply takes one SESSION (or ACC GYRO with --imutk)");
    return kExitUsage;
  }
  if (Status s = apps::CheckStdinInputs(a.inputs, a.imutk); !s.ok()) {
    apps::PrintError(s.error());
    return kExitUsage;
  }
  std::vector<apps::NamedPath> inputs = {{"CALIBRATION", a.calibration}};
  for (const std::string& in : a.inputs) inputs.push_back({"SESSION", in});
  if (Status s = apps::CheckOutputs({{"-o", a.output}}, inputs); !s.ok()) {
    apps::PrintError(s.error());
    return kExitUsage;
  }
  Result<Calibration> cal = LoadCalibration(a.calibration);
  if (!cal.ok()) {
    apps::PrintError(cal.error());
    return kExitUsage;
  }
  Result<Session> session =
      a.imutk ? LoadImuTk(a.inputs[0], a.inputs[1]) : LoadSession(a.inputs[0]);
  if (!session.ok()) {
    apps::PrintError(session.error());
    return kExitUsage;
  }
  Session s = std::move(session).value();
  Result<ApplySummary> summary = ApplyCalibration(cal.value(), &s);
  if (!summary.ok()) {
    apps::PrintError(summary.error());
    return kExitUsage;
  }
  if (Status w = apps::WriteOutput(a.output, FormatSessionCsv(s, true)); !w.ok()) {
    apps::PrintError(w.error());
    return kExitFailed;
  }
  apps::Note(fmt::format("wrote {}: {} tags, {} rows calibrated\n",
                         apps::IsStdio(a.output) ? "stdout" : a.output,
                         summary.value().tags_calibrated, summary.value().rows));
  return kExitOk;
}

}  // namespace

void AddApplyCommand(CLI::App& app, int* exit_code) {
  auto o = std::make_shared<ApplyOptions>();
  CLI::App* sub = app.add_subcommand(
      "apply",
      "write a session with calibrated ax_g.. and gx_dps.. columns (all rows and "
      "columns kept)");
  sub->add_option("calibration", o->calibration, "calibration.json")
      ->required()
      ->check(CLI::ExistingFile);
  sub->add_option("session", o->inputs, "SESSION (or ACC GYRO with --imutk); - reads stdin")
      ->required()
      ->check(apps::ExistingFileOrStdin());
  sub->add_option("-o,--output", o->output, "calibrated session.csv to write (- for stdout)")
      ->required();
  sub->add_flag("--imutk", o->imutk, "the session is an imu_tk pair: ACC GYRO");
  sub->callback([o, exit_code] { *exit_code = RunApply(*o); });
}

}  // namespace metro::calibrate_app
