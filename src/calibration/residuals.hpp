// Private: the residual blocks of the calibration problem (model: imu_model.hpp).
//
// Parameter blocks, in this order wherever a residual takes them (ParameterBlocks,
// parameter_blocks.hpp, fixes it):
//   accel  b(3) k(3) t(3) b1(3)        gyro  b(3) k(3) t(6) b1(3)
// Residuals are multiplied by `weight` (1 / the group's standard deviation when whitened).
#pragma once

#include <Eigen/Core>
#include <vector>

namespace ceres {
class CostFunction;
}

namespace metro::calibration_internal {

// |T K (r_mean - b - b1 dtemp_c)| - target_norm   (1 residual; blocks accel b k t b1).
// Automatic derivatives.
ceres::CostFunction* NewAccelNormCost(const Eigen::Vector3d& raw_mean, double dtemp_c,
                                      double target_norm, double weight);

// r_mean - b - b1 dtemp_c   (3 residuals, input units; blocks gyro b b1). A static interval.
ceres::CostFunction* NewGyroStaticCost(const Eigen::Vector3d& raw_mean, double dtemp_c,
                                       double weight);

// |T K (r_mean - b - b1 dtemp_c)| - |rate_dps|   (1 residual; blocks gyro b k t b1).
ceres::CostFunction* NewGyroTableCost(const Eigen::Vector3d& raw_mean, double dtemp_c,
                                      double rate_abs_dps, double weight);

// One hand rotation between static poses i and j (imu_tk's gyroscope residual, with the bias
// free): u_i, u_j are the calibrated accelerometer directions of the two poses,
// u = normalize(M_a (r_mean - b_a(temp))); q is the integrated body rotation
//   q = Exp(w_1 dt_1) * ... * Exp(w_n dt_n),   w_k = M_g (g_k - b_g(temp_k)) [rad/s]
// (sample k covers (t_{k-1}, t_k], Exp is the exact unit quaternion of a rotation vector,
// Hamilton product, w first), and the residual is R(q)^T u_i - u_j (3 residuals; all 8 blocks).
// Derivatives: forward-mode jets over the gyroscope's 15 parameters for the integration, jets
// over the accelerometer's 12 parameters for u_i and u_j, combined by the chain rule.
struct RotationData {
  Eigen::Vector3d accel_start = Eigen::Vector3d::Zero();  // Raw mean of pose i.
  Eigen::Vector3d accel_end = Eigen::Vector3d::Zero();    // Raw mean of pose j.
  double dtemp_start_c = 0;
  double dtemp_end_c = 0;
  std::vector<Eigen::Vector3d> gyro;  // Raw samples k = e_i .. b_j.
  std::vector<double> dt_s;           // t_k - t_{k-1}.
  std::vector<double> dtemp_c;        // temp_k - t_ref (0 without temperature).
  double weight = 1;
  int pose_start = -1, pose_end = -1;  // Indices of poses i and j (for the noise model).
};
ceres::CostFunction* NewRotationCost(RotationData data);

// The rotation residual's predicted and measured directions for given parameters (doubles),
// used for the initial scale search and for reporting. gyro_scale_rad multiplies M_g to give
// rad/s.
Eigen::Vector3d RotationResidual(const RotationData& data, const double* const* params);

// R(q)^T, the matrix that carries u_i to its predicted u_j, for given parameters (doubles).
Eigen::Matrix3d PredictionMatrix(const RotationData& data, const double* const* params);

// Degrees to radians as the gyroscope residuals use it.
inline constexpr double kRadPerDeg = 3.14159265358979323846 / 180.0;

}  // namespace metro::calibration_internal
