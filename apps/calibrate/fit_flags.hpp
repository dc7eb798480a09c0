// The flags of `calibrate fit`.
// Included by main.cpp only: the program's one translation unit with CLI11 (issue #39).
#pragma once

#include <CLI/CLI.hpp>
#include <memory>

#include "cli_flags.hpp"
#include "common_flags.hpp"
#include "fit_command.hpp"

namespace metro::calibrate_app {

inline void AddFitCommand(CLI::App& app, int* exit_code) {
  auto o = std::make_shared<FitOptions>();
  CLI::App* sub = app.add_subcommand(
      "fit",
      "fit the calibration of every tag in the sessions (static poses, table runs, "
      "hand rotations) and write calibration.json");
  sub->add_option("sessions", o->inputs,
                  "SESSION... (session.csv; ACC GYRO pairs with --imutk); - reads stdin")
      ->required()
      ->check(apps::ExistingFileOrStdin());
  sub->add_option("-o,--output", o->output, "calibration.json to write (- for stdout)")->required();
  sub->add_flag("--imutk", o->imutk, "inputs are imu_tk file pairs: ACC GYRO [ACC GYRO ...]");
  apps::AddLoadCliOptions(sub, &o->load, /*full_scale_flags=*/false);
  CalibrationOptions& c = o->calibration;
  sub->add_option("--sensor", c.sensor, "calibrate only this tag (0 = every tag)");
  // --model sets both sensors' model unless --accel-model or --gyro-model names its own
  // (callbacks run once the whole command line is parsed, so the counts are final). The
  // default is auto (issue #36): the smallest model of bias < scale < full the data accept.
  c.accel_auto = true;
  c.gyro_auto = true;
  c.compare_models = true;
  const auto model_kind = [](const std::string& name) { return *ParseModelKind(name); };
  sub->add_option_function<std::string>(
         "--model",
         [o, sub, model_kind](const std::string& v) {
           const bool automatic = v == "auto";
           if (sub->count("--accel-model") == 0) {
             o->calibration.accel_auto = automatic;
             if (!automatic) o->calibration.accel_model = model_kind(v);
           }
           if (sub->count("--gyro-model") == 0) {
             o->calibration.gyro_auto = automatic;
             if (!automatic) o->calibration.gyro_model = model_kind(v);
           }
         },
         "auto (default: the smallest model the data accept) | bias | scale | full, for both "
         "sensors")
      ->check(CLI::IsMember({"auto", "bias", "scale", "full"}));
  sub->add_option_function<std::string>(
         "--accel-model",
         [o, model_kind](const std::string& v) {
           o->calibration.accel_auto = v == "auto";
           if (v == "none") {
             o->calibration.fit_accel = false;  // The accel model stays --model's (unused).
           } else if (v != "auto") {
             o->calibration.accel_model = model_kind(v);
           }
         },
         "override --model for the accelerometer: auto | bias | scale | full, or none (with "
         "--gyro-model bias: the gyroscope's bias at rest from one static record)")
      ->check(CLI::IsMember({"auto", "bias", "scale", "full", "none"}));
  sub->add_option_function<std::string>(
         "--gyro-model",
         [o, model_kind](const std::string& v) {
           o->calibration.gyro_auto = v == "auto";
           if (v != "auto") o->calibration.gyro_model = model_kind(v);
         },
         "override --model for the gyroscope: auto | bias | scale | full")
      ->check(CLI::IsMember({"auto", "bias", "scale", "full"}));
  sub->add_option("--gravity-mps2", c.gravity_mps2,
                  "local gravity [m/s^2] (default: standard gravity 9.80665, CGPM 1901)")
      ->check(CLI::PositiveNumber);
  sub->add_option_function<double>(
      "--gravity-u-mps2", [o](double v) { o->calibration.gravity_u_mps2 = v; },
      "standard uncertainty of --gravity-mps2 [m/s^2], stated in calibration.json and in the "
      "certificate's accelerometer budget");
  sub->add_option("--accel-fs-g", c.accel_fs_g, "accelerometer full scale of raw counts [g]")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sub->add_option("--gyro-fs-dps", c.gyro_fs_dps, "gyroscope full scale of raw counts [deg/s]")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sub->add_option_function<std::string>(
         "--temperature",
         [o](const std::string& v) {
           o->calibration.temperature = v == "on"    ? TemperatureMode::kOn
                                        : v == "off" ? TemperatureMode::kOff
                                                     : TemperatureMode::kAuto;
         },
         "linear temperature term of the biases: auto (when temp_c varies), on, off")
      ->check(CLI::IsMember({"auto", "on", "off"}));
  sub->add_option_function<std::string>(
         "--loss", [o](const std::string& v) { o->calibration.loss = *ParseLossKind(v); },
         "robust loss: none | huber | cauchy")
      ->check(CLI::IsMember({"none", "huber", "cauchy"}));
  sub->add_option("--loss-scale", c.loss_scale, "robust loss scale, in standard deviations")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sub->add_flag_callback(
      "--accel-only", [o] { o->calibration.fit_gyro = false; }, "calibrate the accelerometer only");
  sub->add_option("--min-static-s", c.segmentation.min_static_s,
                  "shortest still period kept as a pose [s] (default 1; below 1 s the detector's "
                  "window shrinks with it, so poses of about twice this are found)");
  sub->add_option("--segments", o->segments,
                  "CSV of annotated segments used instead of the static detector: "
                  "kind,start_s,end_s[,table_rate_dps][,input] (docs/calibration-model.md)")
      ->check(CLI::ExistingFile);
  sub->add_option("--html", o->html, "also write the calibration certificate (HTML) here");
  sub->add_flag("--thermal", o->thermal,
                "bias versus temperature (polynomial, order by F-tests) from one static record "
                "over a temperature range; writes metro.thermal-fit/1 JSON (docs/thermal.md)");
  sub->add_option("--thermal-order", o->thermal_options.order,
                  "--thermal: fixed polynomial order 1..4 (0: chosen by the data)")
      ->check(CLI::Range(0, 4))
      ->capture_default_str();
  sub->add_option("--thermal-bin-c", o->thermal_options.bin_width_c,
                  "--thermal: temperature bin width; every bin weighs the same")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sub->add_flag("--accept-rejected-model", o->accept_rejected_model,
                "certify constants marked model_rejected (a model the data reject or an exact "
                "fit), with that notice on the certificate");
  AddTagsOption(sub, &o->tags);
  AddSpecOptions(sub, &o->spec);
  AddRegistryOptions(sub, &o->registry);
  sub->callback([o, exit_code, sub] {
    o->calibration.gravity_given = sub->count("--gravity-mps2") > 0;
    *exit_code = RunFit(*o);
  });
}

}  // namespace metro::calibrate_app
