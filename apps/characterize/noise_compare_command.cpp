// characterize noise-compare FILE REPORT.json: an estimator's noise file read back and each
// value compared with the measurement (ratio, E_n; docs/noise.md "Compare a noise file").
#include "noise_compare_command.hpp"

#include <fmt/format.h>

#include <memory>

#include "metro/core/file.hpp"
#include "metro/noise/noise_config_reader.hpp"
#include "metro/noise/spec_library.hpp"
#include "noise_export_options.hpp"
#include "output.hpp"

namespace metro::apps {
namespace {

// noise-compare --spec-part PART: every published source of the part side by side.
int RunSpecCompare(const NoiseCompareOptions& o) {
  if (!o.file.empty() || !o.common.report.empty()) {
    return PrintErrorExit(MakeError(
        "--spec-part compares the part's published sources with each other: give no FILE or "
        "REPORT (to compare a file with a measurement: noise-compare FILE REPORT.json)"));
  }
  Result<SpecLibrary> lib = LoadSpecLibrary(o.spec_library);
  if (!lib.ok()) return PrintErrorExit(lib.error());
  Result<const SpecPart*> part = lib.value().Find(o.spec_part);
  if (!part.ok()) return PrintErrorExit(part.error());
  Result<std::string> table = SpecSourcesTable(*part.value(), o.reference);
  if (!table.ok()) return PrintErrorExit(table.error());
  if (Status s = WriteOutput("-", table.value()); !s.ok()) return PrintErrorExit(s.error());
  return kExitOk;
}

}  // namespace

int RunNoiseCompare(const NoiseCompareOptions& o) {
  if (!o.spec_part.empty()) return RunSpecCompare(o);
  if (o.file.empty() || o.common.report.empty()) {
    return PrintErrorExit(
        MakeError("expected FILE REPORT.json (a noise file and a report made with --allan), or "
                  "--spec-part PART"));
  }
  Result<std::string> text = ReadFile(o.file);
  if (!text.ok()) return PrintErrorExit(text.error());
  Result<NoiseConfigFile> config = ReadNoiseConfig(text.value(), o.file);
  if (!config.ok()) return PrintErrorExit(config.error());
  NoiseExportOptions options = o.common.library;
  Result<NoiseExportFormat> format =
      o.format.empty() ? DetectNoiseConfigFormat(config.value()) : ParseNoiseExportFormat(o.format);
  if (!format.ok()) return PrintErrorExit(format.error());
  options.format = format.value();
  Result<NoiseExportInput> input = LoadNoiseExportInput(o.common);
  if (!input.ok()) return PrintErrorExit(input.error());
  Result<NoiseComparison> c = CompareNoiseConfig(config.value(), input.value(), options);
  if (!c.ok()) return PrintErrorExit(c.error());
  const std::string header = fmt::format(
      "{} ({}) against {}\n", o.file, NoiseExportFormatName(options.format), input.value().source);
  if (Status s = WriteOutput("-", header + NoiseComparisonTable(c.value())); !s.ok()) {
    return PrintErrorExit(s.error());
  }
  return kExitOk;
}

}  // namespace metro::apps
