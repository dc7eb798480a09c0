// characterize noise-export REPORT.json --to FORMAT [-o FILE]: the noise terms of a report's
// tag as an estimator's noise file (docs/noise.md "Export to estimators").
#include <fmt/format.h>

#include <memory>

#include "commands.hpp"
#include "noise_export_options.hpp"
#include "output.hpp"

namespace metro::apps {
namespace {

struct NoiseExportCommandOptions {
  NoiseExportCliOptions common;
  std::string output = "-";
};

int RunNoiseExport(const NoiseExportCommandOptions& o) {
  if (Status s = CheckOutputs({{"-o", o.output}}, {{"REPORT", o.common.report}}); !s.ok()) {
    return PrintErrorExit(s.error());
  }
  Result<NoiseExportInput> input = LoadNoiseExportInput(o.common);
  if (!input.ok()) return PrintErrorExit(input.error());
  Result<NoiseExport> exported = ExportNoise(input.value(), o.common.library);
  if (!exported.ok()) return PrintErrorExit(exported.error());
  if (Status s = WriteOutput(o.output, exported.value().text); !s.ok()) {
    return PrintErrorExit(s.error());
  }
  if (!IsStdio(o.output)) {
    Note(fmt::format("wrote {} ({}, {} values)\n", o.output,
                     NoiseExportFormatName(o.common.library.format),
                     exported.value().values.size()));
  }
  return kExitOk;
}

}  // namespace

void AddNoiseExportCommand(CLI::App& app, int* exit_code) {
  auto o = std::make_shared<NoiseExportCommandOptions>();
  CLI::App* sub = app.add_subcommand(
      "noise-export",
      "write a report's IEEE 952 noise terms as an estimator's noise file (kalibr, openvins, "
      "basalt, vins, orbslam3, gtsam, px4-ekf2, ros), each value's convention and u beside it");
  sub->add_option("report", o->common.report, "REPORT.json made with --allan")
      ->required()
      ->check(CLI::ExistingFile);
  sub->add_option_function<std::string>(
         "--to",
         [o](const std::string& value) {
           Result<NoiseExportFormat> f = ParseNoiseExportFormat(value);
           if (!f.ok()) throw CLI::ValidationError("--to", f.error().message);
           o->common.library.format = f.value();
         },
         "kalibr, openvins, basalt, vins, orbslam3, gtsam, px4-ekf2 or ros")
      ->required();
  sub->add_option("-o,--output", o->output, "the file to write (atomically; default -: stdout)");
  AddNoiseExportCliOptions(sub, &o->common);
  sub->callback([o, exit_code] { *exit_code = RunNoiseExport(*o); });
}

}  // namespace metro::apps
