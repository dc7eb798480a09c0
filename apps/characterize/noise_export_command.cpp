// characterize noise-export REPORT.json --to FORMAT [-o FILE]: the noise terms of a report's
// tag as an estimator's noise file (docs/noise.md "Export to estimators").
#include "noise_export_command.hpp"

#include <fmt/format.h>

#include <memory>

#include "metro/noise/spec_library.hpp"
#include "noise_export_options.hpp"
#include "output.hpp"

namespace metro::apps {
namespace {

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

}  // namespace

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

}  // namespace metro::apps
