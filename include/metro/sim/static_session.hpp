// Simulated static tag sessions with known truth (docs/simulator.md).
//
// Model of the tag's DMP attitude output, per axis a in {yaw, pitch, roll}, at t_k:
//   angle_a(t) = attitude_a + offset_a exp(-t / transient_tau_s)      start-up transient
//              + [a = yaw] yaw_drift_dps t                             yaw drift (no magnetometer)
//              + e_a(t),  e_a AR(1): e_k = phi e_{k-1} + sqrt(1 - phi^2) sigma_a w_k
//   then rounded to quantization_deg (the packets' 0.01 deg) and sent as a binary32
//   quaternion (w, x, y, z) built from the rounded Euler angles (sequence (1,2,3)).
// Defaults: sigma = thesis Table 8.3 s (0.060, 0.031, 0.026 deg), phi = 0.9 per 0.1 s
// frame, tau = 8 s (the ~10 s DMP calibration of thesis 8.4.2).
// Raw IMU columns (columns kImu/kAll) use MPU6050 datasheet figures: accelerometer
// a = R^T (0, 0, 1 g) + bias + white noise of 400 ug/sqrt(Hz); gyroscope bias + white
// noise of 0.005 deg/s/sqrt(Hz); noise std = density * sqrt(rate_hz / 2); temperature
// 25 degC warming by 5 degC with a 600 s time constant, in steps of 1/340 degC.
// Packet loss: each frame independently has no new packet with probability
// packet_loss (receiver: a stale row; session.csv: no row).
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "metro/core/angles.hpp"
#include "metro/core/status.hpp"
#include "metro/io/receiver.hpp"
#include "metro/io/session.hpp"

namespace metro {

enum class SimColumns { kAngles, kImu, kAll };

struct StaticSimulationOptions {
  uint64_t seed = 1;
  std::vector<int> sensors = {2};  // Tags that send.
  std::vector<int> never_sensors;  // Tags that never connect (receiver: ff rows).
  double duration_s = 500.0;
  double rate_hz = 0.0;  // session.csv sample rate; 0: one sample per receiver frame.
  double frame_period_s = kReceiverFramePeriodS;
  double noise_std_deg[3] = {0.060, 0.031, 0.026};  // yaw, pitch, roll
  double noise_ar1 = 0.9;                           // Lag-1 correlation per frame period.
  double transient_std_deg[3] = {3.0, 1.0, 1.0};    // Offsets drawn N(0, this^2).
  double transient_tau_s = 8.0;
  double yaw_drift_dps = 2e-4;
  double quantization_deg = 0.01;
  double packet_loss = 0.02;
  SimColumns columns = SimColumns::kAngles;

  bool IsValid(std::string* why) const;
};

// What the simulator put in, per tag, for tests and for docs.
struct StaticTagTruth {
  int sensor = 0;
  EulerDeg attitude;
  EulerDeg transient_offset;
  double accel_bias_g[3] = {0, 0, 0};
  double gyro_bias_dps[3] = {0, 0, 0};
};

// Consumes the output text in chunks (e.g. an AtomicFileWriter).
using TextSink = std::function<Status(std::string_view)>;

// Writes a session in `format` (kCsv or kReceiver) to `sink`.
Status SimulateStaticSession(const StaticSimulationOptions& options, SessionFormat format,
                             const TextSink& sink, std::vector<StaticTagTruth>* truth = nullptr);

}  // namespace metro
