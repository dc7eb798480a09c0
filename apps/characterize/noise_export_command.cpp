// characterize noise-export REPORT.json --to FORMAT [-o FILE]: the noise terms of a report's
// tag as an estimator's noise file (docs/noise.md "Export to estimators").
#include <fmt/format.h>

#include <memory>

#include "commands.hpp"
#include "metro/noise/spec_library.hpp"
#include "noise_export_options.hpp"
#include "output.hpp"

namespace metro::apps {
namespace {

struct NoiseExportCommandOptions {
  NoiseExportCliOptions common;
  std::string output = "-";
  // --from-spec PART: a datasheet's figures as Kalibr's imu.yaml (docs/specs.md "To Kalibr").
  std::string from_spec;
  std::string spec_library = DefaultSpecLibrary();
  SpecToKalibrOptions spec;
};

int RunSpecExport(const NoiseExportCommandOptions& o) {
  if (!o.common.report.empty()) {
    return PrintErrorExit(MakeError("--from-spec writes a datasheet's figures: give no REPORT"));
  }
  if (o.common.library.format != NoiseExportFormat::kKalibr) {
    return PrintErrorExit(
        MakeError("--from-spec: only --to kalibr (convert the imu.yaml onward with a measured "
                  "report; the other formats' conventions need the record's rate and u)"));
  }
  if (Status s = CheckOutputs({{"-o", o.output}}, {{"--spec-library", o.spec_library}}); !s.ok()) {
    return PrintErrorExit(s.error());
  }
  Result<SpecLibrary> lib = LoadSpecLibrary(o.spec_library);
  if (!lib.ok()) return PrintErrorExit(lib.error());
  Result<const SpecPart*> part = lib.value().Find(o.from_spec);
  if (!part.ok()) return PrintErrorExit(part.error());
  SpecToKalibrOptions spec = o.spec;
  spec.rostopic = o.common.library.rostopic;
  Result<std::string> text = SpecToKalibrYaml(*part.value(), spec, o.spec_library);
  if (!text.ok()) return PrintErrorExit(text.error().WithContext("--from-spec " + o.from_spec));
  if (Status s = WriteOutput(o.output, text.value()); !s.ok()) return PrintErrorExit(s.error());
  return kExitOk;
}

int RunNoiseExport(const NoiseExportCommandOptions& o) {
  if (!o.from_spec.empty()) return RunSpecExport(o);
  if (o.common.report.empty()) {
    return PrintErrorExit(
        MakeError("expected REPORT.json (made with --allan), or --from-spec PART"));
  }
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
  sub->add_option("--from-spec", o->from_spec,
                  "instead of REPORT: a part's datasheet noise figures as Kalibr's imu.yaml, "
                  "assumptions stated in the file (docs/specs.md)");
  sub->add_option("--spec-library", o->spec_library, "the spec library")
      ->check(CLI::ExistingFile)
      ->capture_default_str();
  sub->add_option("--spec-source", o->spec.source,
                  "with --from-spec: the document of the part (default: its first datasheet)");
  sub->add_option("--update-rate-hz", o->spec.update_rate_hz,
                  "with --from-spec: the rate the IMU is read at (Kalibr's update_rate)")
      ->check(CLI::PositiveNumber);
  sub->add_flag("--partial", o->spec.partial,
                "with --from-spec: write the file without the K keys the datasheet cannot give "
                "(Kalibr will not read it as is)");
  sub->callback([o, exit_code] { *exit_code = RunNoiseExport(*o); });
}

}  // namespace metro::apps
