// Simulated thermal sessions with known truth (issue #42 step 3, docs/thermal.md): one tag at
// rest in one pose (gravity along body +z) over a temperature profile, in raw MPU6050 counts
// (ax_lsb.. gx_lsb.., temp_c), so `calibrate fit --thermal` sees what a tag sends.
//
// Temperature profile temp_c(t) (the die temperature, read at 1/340 degC, MPU6050):
//   kRamp    temp_low_c -> temp_high_c linearly over ramp_s (a chamber ramp);
//   kSteps   `steps` equally spaced levels low .. high, step_dwell_s each, the die following
//            each level with a first-order lag of time constant step_tau_s (a chamber with steps);
//   kWarmup  low + (high - low) (1 - exp(-t / warmup_tau_s)) over warmup_s (power-on warm-up).
// With cooling_leg (ramp, steps) the profile returns from high to low the same way.
//
// Bias model, per sensor and axis a, in raw counts [LSB], x = temp_c - t_ref_c:
//   b_a(T) = b0_a + sum_{j=1..order} c_{a,j} x^j  + leg * h_a / 2,
//   leg = +1 on the heating leg, -1 on the cooling leg (thermal hysteresis h_a = heating minus
//   cooling; 0 without a cooling leg).
// raw = round(M^-1 (truth + noise) + b(T)), M = diag(1/16384 g, 1/131 deg/s per LSB) with the
// datasheet's sensitivity, t_ref_c = (temp_low_c + temp_high_c) / 2.
// Drawn truth (random_truth): the polynomial of x / half_span has coefficients of magnitude
// uniform in [0.3, 1] * A / order with random signs, A = accel_excursion_g (default 0.075 g,
// iNav #73: 0.05-0.10 g over 45 degC) or gyro_excursion_dps (default 3 deg/s: -2..+4 deg/s);
// b0 uniform in +-50 mg / +-20 deg/s (datasheet zero offsets).
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "metro/core/status.hpp"
#include "metro/io/session.hpp"

namespace metro {

enum class ThermalProfile { kRamp, kSteps, kWarmup };
const char* ThermalProfileName(ThermalProfile profile);  // "ramp", "steps", "warmup"

struct ThermalSimulationOptions {
  uint64_t seed = 1;
  int sensor = 1;
  double rate_hz = 10.0;
  ThermalProfile profile = ThermalProfile::kRamp;
  double temp_low_c = -10.0;
  double temp_high_c = 35.0;
  double ramp_s = 3600.0;
  int steps = 6;
  double step_dwell_s = 600.0;
  double step_tau_s = 60.0;
  double warmup_tau_s = 600.0;
  double warmup_s = 3600.0;
  bool cooling_leg = false;
  int bias_order = 3;  // 1..4, the truth's polynomial order (both sensors, every axis).
  double accel_excursion_g = 0.075;
  double gyro_excursion_dps = 3.0;
  double accel_hysteresis_g = 0.0;  // h (heating minus cooling), every axis; needs cooling_leg.
  double gyro_hysteresis_dps = 0.0;
  double accel_noise_ug_rthz = 400.0;
  double gyro_noise_dps_rthz = 0.005;
  double bandwidth_hz = 50.0;
  // Temperature read errors: this many isolated samples whose temp_c reads temp_glitch_c more
  // (a sensor read error), at random rows; their lines are in the truth.
  int temp_glitches = 0;
  double temp_glitch_c = 40.0;

  bool IsValid(std::string* why) const;
};

// One sensor's truth: coefficients [LSB/degC^j], j = 0..order, and the hysteresis [LSB].
struct ThermalSensorTruth {
  std::array<Eigen::VectorXd, 3> coefficients;
  Eigen::Vector3d hysteresis_lsb = Eigen::Vector3d::Zero();
  double lsb_per_unit = 1.0;  // 16384 LSB/g, 131 LSB/(deg/s).
  // b(T) on leg (+1 heating, -1 cooling, 0 the mean of the legs) [LSB].
  double BiasAt(int axis, double temp_c, double t_ref_c, int leg) const;
};

struct ThermalTruth {
  double t_ref_c = 0.0;
  int order = 0;
  ThermalSensorTruth accel;
  ThermalSensorTruth gyro;
  std::vector<int64_t> glitch_lines;  // 1-based session.csv lines of the read errors.
};

struct SimulatedThermalSession {
  Session session;  // One tag: t_s ax_lsb ay_lsb az_lsb gx_lsb gy_lsb gz_lsb temp_c.
  ThermalTruth truth;
  std::vector<double> true_temp_c;  // Per sample, before the read errors and quantization.
  std::vector<int> leg;             // Per sample: +1 heating, -1 cooling.
};

Result<SimulatedThermalSession> SimulateThermalSession(const ThermalSimulationOptions& options);

// The truth as JSON ("metro.thermal-truth/1", docs/simulator.md "Thermal sessions"): the
// options and, per sensor, every coefficient c_j [LSB/degC^j] (j = 0..order), t_ref_c, the
// hysteresis [LSB] and the glitch lines. 2-space indent, trailing newline.
std::string ThermalTruthJson(const ThermalSimulationOptions& options,
                             const SimulatedThermalSession& sim);

}  // namespace metro
