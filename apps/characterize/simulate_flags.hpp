// The flags of `characterize simulate`.
// Included by main.cpp only: the program's one translation unit with CLI11 (issue #39).
#pragma once

#include <CLI/CLI.hpp>
#include <memory>

#include "cli_flags.hpp"
#include "simulate_command.hpp"

namespace metro::apps {

inline void AddThermalSimulateOptions(CLI::App* sub, SimulateOptions* o) {
  ThermalSimulationOptions& t = o->thermal;
  sub->add_option("--thermal-profile", o->thermal_profile,
                  "thermal: ramp (chamber ramp), steps (chamber steps) or warmup (power-on)")
      ->check(CLI::IsMember({"ramp", "steps", "warmup"}))
      ->capture_default_str();
  sub->add_option("--temp-low-c", t.temp_low_c, "thermal: lowest temperature")
      ->capture_default_str();
  sub->add_option("--temp-high-c", t.temp_high_c, "thermal: highest temperature")
      ->capture_default_str();
  sub->add_option("--ramp-s", t.ramp_s, "thermal: ramp duration (one leg)")->capture_default_str();
  sub->add_option("--steps", t.steps, "thermal: chamber levels")->capture_default_str();
  sub->add_option("--step-dwell-s", t.step_dwell_s, "thermal: time at each level")
      ->capture_default_str();
  sub->add_option("--step-tau-s", t.step_tau_s, "thermal: die time constant after a step")
      ->capture_default_str();
  sub->add_option("--warmup-tau-s", t.warmup_tau_s, "thermal: warm-up time constant")
      ->capture_default_str();
  sub->add_option("--warmup-s", t.warmup_s, "thermal: warm-up record length")
      ->capture_default_str();
  sub->add_flag("--cooling-leg", t.cooling_leg, "thermal: return from high to low (ramp, steps)");
  sub->add_option("--bias-order", t.bias_order, "thermal truth: bias polynomial order")
      ->check(CLI::Range(1, 4))
      ->capture_default_str();
  sub->add_option("--accel-excursion-g", t.accel_excursion_g,
                  "thermal truth: accel bias excursion scale over the span")
      ->capture_default_str();
  sub->add_option("--gyro-excursion-dps", t.gyro_excursion_dps,
                  "thermal truth: gyro bias excursion scale over the span")
      ->capture_default_str();
  sub->add_option("--accel-hysteresis-g", t.accel_hysteresis_g,
                  "thermal truth: heating minus cooling accel bias (needs --cooling-leg)")
      ->capture_default_str();
  sub->add_option("--gyro-hysteresis-dps", t.gyro_hysteresis_dps,
                  "thermal truth: heating minus cooling gyro bias (needs --cooling-leg)")
      ->capture_default_str();
  sub->add_option("--temp-glitches", t.temp_glitches,
                  "thermal: isolated temperature read errors (+40 degC) at random rows")
      ->capture_default_str();
}

inline void AddSimulateCommand(CLI::App& app, int* exit_code) {
  auto o = std::make_shared<SimulateOptions>();
  CLI::App* sub = app.add_subcommand(
      "simulate", "write a static tag session with known truth (docs/simulator.md)");
  sub->add_option("-o,--output", o->output, "file to write (- for stdout)")->required();
  sub->add_option("--format", o->format, "csv or receiver")
      ->check(CLI::IsMember({"csv", "receiver"}))
      ->capture_default_str();
  sub->add_option("--columns", o->columns,
                  "session.csv columns: angles (qw..qz), imu (ax_g..gz_dps, temp_c) or all")
      ->check(CLI::IsMember({"angles", "imu", "all"}))
      ->capture_default_str();
  sub->add_option("--seed", o->sim.seed, "random seed")->capture_default_str();
  sub->add_option("--sensor", o->sim.sensors, "a tag that sends (repeatable; default 2)");
  sub->add_option("--tags", o->tags, "tags 1..N send (instead of --sensor)")
      ->check(CLI::Range(1, 255));
  sub->add_option("--never", o->sim.never_sensors, "a tag that never connects (repeatable)");
  sub->add_option("--duration-s", o->sim.duration_s, "length in seconds")->capture_default_str();
  sub->add_option("--rate-hz", o->sim.rate_hz,
                  "session.csv sample rate (default: one sample per 0.10013 s frame)");
  sub->add_option("--packet-loss", o->sim.packet_loss, "probability a frame has no new packet")
      ->capture_default_str();
  sub->add_option("--transient-tau-s", o->sim.transient_tau_s,
                  "time constant of the start-up transient")
      ->capture_default_str();
  sub->add_option("--yaw-drift-dps", o->sim.yaw_drift_dps, "yaw drift rate")->capture_default_str();
  sub->add_option("--kind", o->kind,
                  "static; table: a rotation-table sweep; calibration: a multi-pose calibration "
                  "session in raw LSB; thermal: one pose over a temperature profile in raw LSB "
                  "(docs/simulator.md)")
      ->check(CLI::IsMember({"static", "table", "calibration", "thermal"}))
      ->capture_default_str();
  sub->add_option("--poses", o->calibration.poses,
                  "calibration: static poses (cube faces, corners, edges, cycled)")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  sub->add_option("--accel-cross-axis", o->calibration.accel_cross_axis,
                  "calibration: the accelerometer's cross-axis terms are drawn uniform in +- this "
                  "(0.02 = the MPU6050 datasheet's 2 %; 0 = none)")
      ->check(CLI::Range(0.0, 0.1))
      ->capture_default_str();
  sub->add_option("--gyro-cross-axis", o->calibration.gyro_cross_axis,
                  "calibration: the gyroscope's cross-axis terms are drawn uniform in +- this")
      ->check(CLI::Range(0.0, 0.1))
      ->capture_default_str();
  sub->add_option("--pose-dwell-s", o->calibration.dwell_s,
                  "calibration: still time per pose (the first twice as long)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sub->add_option("--move-s", o->calibration.move_s,
                  "calibration: duration of each hand rotation between poses")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sub->add_option("--run-rate-dps", o->calibration.table_rates_dps,
                  "calibration: a rate-table run at every pose, logger running (repeatable; "
                  "default 90)");
  sub->add_option("--run-s", o->calibration.table_run_s, "calibration: length of each table run")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sub->add_option("--temp-start-c", o->calibration.temp_start_c,
                  "calibration: temperature ramp start")
      ->capture_default_str();
  sub->add_option("--temp-end-c", o->calibration.temp_end_c, "calibration: temperature ramp end")
      ->capture_default_str();
  sub->add_flag("--no-temperature", o->no_temperature,
                "calibration: no temp_c column and no temperature terms in the truth");
  sub->add_option("--table-axis", o->table_axis, "table: the tag axis turned (yaw, pitch, roll)")
      ->capture_default_str();
  sub->add_option("--table-start-deg", o->table.start_deg, "table: first plateau angle")
      ->capture_default_str();
  sub->add_option("--table-end-deg", o->table.end_deg, "table: last plateau angle")
      ->capture_default_str();
  sub->add_option("--table-step-deg", o->table.step_deg, "table: step between plateaus")
      ->capture_default_str();
  sub->add_option("--sweeps", o->table.sweeps, "table: up-and-down sweeps")->capture_default_str();
  sub->add_option("--dwell-s", o->table.dwell_s, "table: dwell per plateau")->capture_default_str();
  sub->add_option("--table-rate-dps", o->table.move_rate_dps, "table: rate between plateaus")
      ->capture_default_str();
  sub->add_option("--offset-deg", o->table.offset_deg, "table truth: error offset")
      ->capture_default_str();
  sub->add_option("--scale-error", o->table.scale_error, "table truth: scale error (deg/deg)")
      ->capture_default_str();
  sub->add_option("--cos1-deg", o->table.cos1_deg, "table truth: misalignment cos(theta) term")
      ->capture_default_str();
  sub->add_option("--sin1-deg", o->table.sin1_deg, "table truth: misalignment sin(theta) term")
      ->capture_default_str();
  sub->add_option("--hysteresis-deg", o->table.hysteresis_deg, "table truth: up minus down")
      ->capture_default_str();
  sub->add_option("--tilt-deg", o->table.tilt_deg, "table truth: cross-axis mounting tilt")
      ->capture_default_str();
  sub->add_option("--noise-deg", o->table.noise_std_deg, "table truth: noise std (AR(1))")
      ->capture_default_str();
  sub->add_option("--lag-tau-s", o->table.lag_tau_s, "table truth: tag response time constant")
      ->capture_default_str();
  sub->add_option("--reference-output", o->reference_output,
                  "table: write the reference as a separate log (t_s, table_angle_deg) here");
  sub->add_option("--reference-offset-s", o->table.reference_clock_offset_s,
                  "table: the reference log's clock runs this far ahead")
      ->capture_default_str();
  sub->add_option("--truth-output", o->truth_output,
                  "table, calibration: the truth as JSON (default: OUTPUT.truth.json when -o is a "
                  "file)");
  sub->add_option("--table-readout", o->table_readout,
                  "table: continuous (0..360 as turned) or wrap180 (signed, (-180, 180])")
      ->check(CLI::IsMember({"continuous", "wrap180"}))
      ->capture_default_str();
  sub->add_flag("--table-pitch-through-90", o->table.pitch_through_90,
                "table: let a pitch table pass +-90 deg (the tag's Euler pitch folds there)");
  sub->add_flag("--table-up-only", o->table.up_only,
                "table: one pass up, no down pass (hysteresis not measured; --sweeps 1)");
  sub->add_option("--noise-ar1", o->table.noise_ar1,
                  "table truth: lag-1 correlation of the noise per frame")
      ->capture_default_str();
  AddThermalSimulateOptions(sub, o.get());
  sub->callback([o, exit_code] { *exit_code = RunSimulate(*o); });
}

}  // namespace metro::apps
