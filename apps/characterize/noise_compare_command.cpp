// characterize noise-compare FILE REPORT.json: an estimator's noise file read back and each
// value compared with the measurement (ratio, E_n; docs/noise.md "Compare a noise file").
#include <fmt/format.h>

#include <memory>

#include "commands.hpp"
#include "metro/core/file.hpp"
#include "metro/noise/noise_config_reader.hpp"
#include "metro/noise/spec_library.hpp"
#include "noise_export_options.hpp"
#include "output.hpp"

namespace metro::apps {
namespace {

struct NoiseCompareOptions {
  std::string file;
  std::string format;  // --format: empty, told by the keys.
  NoiseExportCliOptions common;
  // --spec-part PART [--reference DOC]: the part's published figures compared with each other.
  std::string spec_part;
  std::string spec_library = DefaultSpecLibrary();
  std::string reference;
};

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

}  // namespace

void AddNoiseCompareCommand(CLI::App& app, int* exit_code) {
  auto o = std::make_shared<NoiseCompareOptions>();
  CLI::App* sub = app.add_subcommand(
      "noise-compare",
      "read an estimator's noise file (any noise-export format) and compare each value with a "
      "report's measurement: ratio and E_n");
  sub->add_option("file", o->file, "imu.yaml, a VINS/ORB-SLAM3 config, PX4 params, ...")
      ->check(CLI::ExistingFile);
  sub->add_option("report", o->common.report, "REPORT.json made with --allan")
      ->check(CLI::ExistingFile);
  sub->add_option("--spec-part", o->spec_part,
                  "instead of FILE REPORT: the part's published noise figures (datasheet, "
                  "EuRoC's sensor.yaml, Kalibr's sample) side by side, with ratios "
                  "(docs/specs.md)");
  sub->add_option("--spec-library", o->spec_library, "the spec library")
      ->check(CLI::ExistingFile)
      ->capture_default_str();
  sub->add_option("--reference", o->reference,
                  "with --spec-part: the document the ratios are to (default: the first)");
  sub->add_option("--format", o->format, "the file's format (default: told by its keys)")
      ->check(CLI::IsMember(NoiseExportFormatNames()));
  AddNoiseExportCliOptions(sub, &o->common);
  sub->callback([o, exit_code] { *exit_code = RunNoiseCompare(*o); });
}

}  // namespace metro::apps
