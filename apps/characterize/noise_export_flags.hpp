// The flags of `characterize noise-export` and the ones it shares with `noise-compare` and
// `--export` (noise_export_options.hpp).
// Included by main.cpp only: the program's one translation unit with CLI11 (issue #39).
#pragma once

#include <CLI/CLI.hpp>
#include <memory>

#include "cli_flags.hpp"
#include "noise_export_command.hpp"
#include "noise_export_options.hpp"

namespace metro::apps {

inline void AddAxisReductionOption(CLI::App* app, AxisReduction* reduction,
                                   const std::string& help) {
  app->add_option_function<std::string>(
         "--axis-reduction",
         [reduction](const std::string& value) {
           Result<AxisReduction> r = ParseAxisReduction(value);
           if (!r.ok()) throw CLI::ValidationError("--axis-reduction", r.error().message);
           *reduction = r.value();
         },
         help)
      ->check(CLI::IsMember(
          {AxisReductionName(AxisReduction::kMax), AxisReductionName(AxisReduction::kRms)}))
      ->default_str(AxisReductionName(*reduction));
}

inline void AddNoiseExportCliOptions(CLI::App* app, NoiseExportCliOptions* o) {
  app->add_option_function<int64_t>(
      "--sensor", [o](int64_t n) { o->sensor = n; },
      "the tag whose terms to take (default: the one tag with an Allan section)");
  AddAxisReductionOption(app, &o->library.reduction,
                         "one value over the three axes for the scalar formats: max (the "
                         "largest axis and its u) or rms");
  app->add_option("--rostopic", o->library.rostopic, "kalibr, openvins: the IMU topic named")
      ->capture_default_str();
  app->add_option("--px4-predict-rate-hz", o->library.px4_predict_rate_hz,
                  "px4-ekf2: the EKF2 prediction rate its parameters are per step of")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
}

inline void AddNoiseExportCommand(CLI::App& app, int* exit_code) {
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
