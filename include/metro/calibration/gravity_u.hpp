// The gravity value's uncertainty in the accelerometer's calibration (issue #36 point 7;
// docs/calibration-model.md "Gravity").
//
// The accelerometer is fitted to the norm g / g_n (calibrate.hpp), so the gravity value g scales
// M = T K (and K, and 1 / sensitivity) by one factor and leaves the biases and misalignment terms
// unchanged: u(g) / g is a relative uncertainty of every scale factor k, sensitivity s = 1 / k and
// element of M. With the fit's own u and g independent of the data (JCGM 100:2008 5.1.2):
//
//   u_c(k) = sqrt(u(k)^2 + (k u(g) / g)^2),   u_c(s) = sqrt(u(s)^2 + (s u(g) / g)^2),
//   u_c(M_ij) = sqrt(u(M_ij)^2 + (M_ij u(g) / g)^2).
//
// u(g): `calibrate fit --gravity-u-mps2` when given ("stated"); a value given without it
// (--gravity-mps2) read as rounded to its last written digit, rectangular (JCGM 100:2008 4.3.7;
// "given_value_rounding"); standard gravity standing for the local one, within +-0.03 m/s^2 of
// it at the Earth's surface, rectangular ("standard_gravity_range").
#pragma once

#include <Eigen/Core>
#include <optional>
#include <string>

namespace metro {

struct Calibration;
struct SensorCalibration;

struct GravityUncertainty {
  double gravity_mps2 = 0;  // The value the fit used.
  double u_mps2 = 0;        // Its standard uncertainty (k = 1).
  // "stated", "given_value_rounding" or "standard_gravity_range" (above).
  std::string basis;
  std::string statement;  // The sentence the certificate prints, e.g. "u(g) = 0.0173 m/s^2: ...".
  double Relative() const { return gravity_mps2 > 0 ? u_mps2 / gravity_mps2 : 0.0; }
};

// From calibration.json's gravity_mps2, gravity_source ("standard", "given" or empty) and
// gravity_u_mps2 (unset: not stated).
GravityUncertainty GravityUncertaintyOf(double gravity_mps2, const std::string& gravity_source,
                                        const std::optional<double>& gravity_u_mps2);
GravityUncertainty GravityUncertaintyOf(const Calibration& calibration);

// The accelerometer's u with gravity's (calibration.json's `gravity_uncertainty`,
// `scale_u_with_gravity`, `sensitivity_u_with_gravity`, `matrix_u_with_gravity`); the fit's
// covariance and its *_u stay the fit's alone.
struct GravityShare {
  GravityUncertainty gravity;
  Eigen::Vector3d scale_u = Eigen::Vector3d::Zero();
  Eigen::Vector3d sensitivity_u = Eigen::Vector3d::Zero();
  Eigen::Matrix3d matrix_u = Eigen::Matrix3d::Zero();
};

// The share of `accel` (an accelerometer calibration with its u derived: scale_u, sensitivity,
// sensitivity_u, matrix_u) under `gravity`, by the formulas above. A scale held fixed (the bias
// model) keeps u = 0: the constant is not estimated.
GravityShare GravityShareOf(const SensorCalibration& accel, const GravityUncertainty& gravity);

}  // namespace metro
