// Simulated calibration sessions with known truth: multi-pose static records with hand
// rotations between the poses, optionally with rotation-table runs at each pose and a
// temperature ramp. The output is raw MPU6050 counts (ax_lsb.. gx_lsb.., int16, saturating),
// so the calibrator sees what a tag sends.
//
// Truth (drawn when random_truth, seedable, per the MPU-6050 datasheet,
// PS-MPU-6000A-00 rev 3.4): accel zero-g offset uniform in +-50 mg (x, y) and +-80 mg (z),
// sensitivity uniform in +-3 % of 16384 LSB/g (at +-2 g), cross-axis uniform in +-2 %;
// gyro zero-rate offset uniform in +-20 deg/s, sensitivity +-3 % of 131 LSB/(deg/s),
// cross-axis +-2 %; temperature coefficients uniform in +-0.5 mg/degC (accel, 35 mg over
// 70 degC) and +-0.16 deg/s/degC (gyro, 20 deg/s over 125 degC).
// Noise: white, standard deviation density * sqrt(bandwidth_hz) per sample: 400 ug/sqrt(Hz)
// and 0.005 deg/s/sqrt(Hz). raw = round(M^-1 * truth + b(temp) + noise), clamped to int16.
//
// Motion: pose i has gravity ("up", the accelerometer's specific force) along body direction
// u_i and a random heading. Between poses the body turns about one fixed body axis with a
// minimum-jerk angle profile; the gyroscope sample at t_k is the mean body rate over
// (t_{k-1}, t_k], so integrating sample k over that interval is exact. The tag turns about its
// own origin (no linear acceleration). On the table the tag turns about the vertical.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "metro/calibration/imu_model.hpp"
#include "metro/core/status.hpp"
#include "metro/io/session.hpp"

namespace metro {

struct ImuTruth {
  SensorModel accel;  // LSB -> g
  SensorModel gyro;   // LSB -> deg/s
};

enum class PoseSet {
  kCube,       // Faces, then corners, then edges of a cube (26 directions), cycled.
  kSphere,     // A Fibonacci sphere of `poses` directions.
  kUpperOnly,  // Directions with the body z axis at least 30 deg above the horizon (bad).
  kFaces,      // The 6 faces of a cube only, cycled (too few distinct directions: bad).
};

struct SimulationOptions {
  uint64_t seed = 1;
  int sensor = 1;
  double rate_hz = 100.0;
  int poses = 26;
  PoseSet pose_set = PoseSet::kCube;
  double dwell_s = 3.0;  // Static time at each pose.
  double move_s = 2.0;   // Duration of each hand rotation.
  double accel_fs_g = 2.0;
  double gyro_fs_dps = 250.0;
  double gravity_mps2 = kStandardGravityMps2;
  double accel_noise_ug_rthz = 400.0;
  double gyro_noise_dps_rthz = 0.005;
  double bandwidth_hz = 50.0;
  std::vector<double> table_rates_dps;  // Runs at each pose, in this order; empty: no table.
  double table_run_s = 4.0;
  bool write_table_column = false;  // table_rate_dps even without runs (all 0).
  bool temperature = false;         // temp_c column, ramp temp_start_c -> temp_end_c.
  double temp_start_c = 25.0;
  double temp_end_c = 35.0;
  // Half-widths of the drawn cross-axis (misalignment) terms, uniform in +-each [rad]: the
  // datasheet's 2 % by default; 0 draws a truth without cross-axis terms (the scale model
  // holds), 0.01 / 0.015 the realistic terms of issue #36.
  double accel_cross_axis = 0.02;
  double gyro_cross_axis = 0.02;
  // A pose's gravity direction tilted from its nominal one (a tag placed by hand on a face that
  // is not level, issue #36): by an angle uniform in 0 .. pose_tilt_deg about a horizontal axis
  // of uniform direction, drawn from its own stream (0: the nominal directions, and every other
  // draw as without it).
  double pose_tilt_deg = 0.0;
  bool random_truth = true;  // Draw the truth; else use `truth` as given.
  ImuTruth truth;            // Used when !random_truth (units LSB -> g and LSB -> deg/s).

  bool IsValid(std::string* why) const;
};

struct SimulatedSession {
  Session session;  // One tag, columns t_s ax_lsb.. gx_lsb.. [temp_c] [table_rate_dps].
  ImuTruth truth;
  std::vector<Eigen::Vector3d> true_accel_g;   // Per sample, body frame.
  std::vector<Eigen::Vector3d> true_gyro_dps;  // Per sample, mean over (t_{k-1}, t_k].
  int saturated_samples = 0;
};

// Draws a truth per the datasheet tolerances above (full models, temperature terms included
// when `temperature`).
// The cross-axis terms are uniform in +-accel_cross_axis and +-gyro_cross_axis (the same
// random draws whatever the half-widths, so other constants do not change with them).
ImuTruth DrawImuTruth(uint64_t seed, double accel_fs_g, double gyro_fs_dps, bool temperature,
                      double accel_cross_axis = 0.02, double gyro_cross_axis = 0.02);

Result<SimulatedSession> SimulateCalibrationSession(const SimulationOptions& options);

// One reading through a sensor's truth, as the simulators make it: round(truth.Invert(value,
// temp_c)) per axis [LSB], clamped to the int16 range; *saturated is set (never cleared) when
// an axis reached -32768 or 32767. `value` is the true input plus noise (g or deg/s).
Eigen::Vector3d TruthToCounts(const SensorModel& truth, const Eigen::Vector3d& value, double temp_c,
                              bool* saturated);

// The truth of a simulated session as JSON text ("metro.calibration-truth/1",
// docs/simulator.md "Calibration sessions"): the options that shaped the record and, per
// sensor, the constants the simulation used under calibration.json's keys (`bias` [LSB],
// `scale` [g/LSB, deg/s/LSB], `misalignment` [rad], `matrix` = T K, `sensitivity` = 1/k,
// `temperature` {`t_ref_c`, `bias_per_c` [LSB/degC]}), so a fit compares key by key.
// 2-space indent, trailing newline; the same options give the same bytes.
std::string CalibrationTruthJson(const SimulationOptions& options, const SimulatedSession& sim);

}  // namespace metro
