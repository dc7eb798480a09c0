// A simulated tag streaming raw counts live, moved by a (simulated) operator: the calibration
// station's test and demonstration source (issue #44, docs/station.md "Simulator").
//
// Truth and noise are the calibration simulator's (calibration_session.hpp: DrawImuTruth, the
// datasheet tolerances; white noise of the bundled session's densities; counts through
// TruthToCounts). The operator's actions append samples at rate_hz:
//   Hold(s)         the tag still in its current orientation;
//   Move(up, s)     a hand rotation (minimum-jerk angle profile about one body axis, the
//                   calibration simulator's) to the orientation with body direction `up`
//                   pointing up and a random heading; the gyroscope sample at t_k is the mean
//                   body rate over (t_{k-1}, t_k];
//   Knock(peak_g)   an 80 ms jolt: a half-sine linear acceleration of peak_g in a random body
//                   direction and a 1 deg wobble about a random axis that returns to the pose;
//   Reseat(s)       lifted and set down again on the same face at another heading.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "metro/sim/calibration_session.hpp"

namespace metro {

struct RawTagOptions {
  uint64_t seed = 1;
  double rate_hz = 100.0;
  double accel_fs_g = 2.0;
  double gyro_fs_dps = 250.0;
  double accel_noise_ug_rthz = 400.0;  // The bundled session's (SimulationOptions).
  double gyro_noise_dps_rthz = 0.005;
  double bandwidth_hz = 50.0;
  double accel_cross_axis = 0.02;
  double gyro_cross_axis = 0.02;
  bool random_truth = true;  // Draw the truth from the seed; else `truth`.
  ImuTruth truth;
  Eigen::Vector3d start_up = Eigen::Vector3d::UnitZ();  // Body direction up at the start.

  bool IsValid(std::string* why) const;
};

struct RawTagSample {
  double t_s = 0;
  std::array<int32_t, 6> counts{};  // ax ay az gx gy gz [LSB]
  bool saturated = false;
};

class SimulatedRawTag {
 public:
  // Precondition: options.IsValid().
  explicit SimulatedRawTag(const RawTagOptions& options);
  ~SimulatedRawTag();
  SimulatedRawTag(const SimulatedRawTag&) = delete;
  SimulatedRawTag& operator=(const SimulatedRawTag&) = delete;

  const ImuTruth& Truth() const;
  Eigen::Vector3d UpBody() const;  // The body direction pointing up now.
  double TimeS() const;            // Time of the next sample.

  void Hold(double duration_s, std::vector<RawTagSample>* out);
  void Move(const Eigen::Vector3d& up_body, double duration_s, std::vector<RawTagSample>* out);
  void Knock(double peak_g, std::vector<RawTagSample>* out);
  void Reseat(double duration_s, std::vector<RawTagSample>* out);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace metro
