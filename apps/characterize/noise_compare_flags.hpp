// The flags of `characterize noise-compare`.
// Included by main.cpp only: the program's one translation unit with CLI11 (issue #39).
#pragma once

#include <CLI/CLI.hpp>
#include <memory>

#include "cli_flags.hpp"
#include "noise_compare_command.hpp"
#include "noise_export_flags.hpp"

namespace metro::apps {

inline void AddNoiseCompareCommand(CLI::App& app, int* exit_code) {
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
