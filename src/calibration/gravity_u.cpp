// The gravity value's uncertainty in the accelerometer's calibration (gravity_u.hpp).
#include "metro/calibration/gravity_u.hpp"

#include <fmt/format.h>

#include <cmath>

#include "metro/calibration/calibrate.hpp"

namespace metro {

namespace {

std::string Short(double x, int digits) { return fmt::format("{:.{}g}", x, digits); }

}  // namespace

GravityUncertainty GravityUncertaintyOf(double gravity_mps2, const std::string& gravity_source,
                                        const std::optional<double>& gravity_u_mps2) {
  GravityUncertainty out;
  out.gravity_mps2 = gravity_mps2;
  if (gravity_u_mps2) {
    out.u_mps2 = *gravity_u_mps2;
    out.basis = "stated";
    out.statement = fmt::format("u(g) = {} m/s^2 as stated (calibrate fit --gravity-u-mps2)",
                                Short(out.u_mps2, 3));
  } else if (gravity_source == "given") {
    // The value as written (shortest round trip), read as rounded to its last digit.
    const std::string written = fmt::format("{}", gravity_mps2);
    const size_t dot = written.find('.');
    const int decimals = dot == std::string::npos ? 0 : static_cast<int>(written.size() - dot - 1);
    const double half = 0.5 * std::pow(10.0, -decimals);
    out.u_mps2 = half / std::sqrt(3.0);  // Rectangular, JCGM 100:2008 4.3.7.
    out.basis = "given_value_rounding";
    out.statement = fmt::format(
        "u(g) = {} m/s^2: the given value {} m/s^2 read as rounded to its last digit (+-{} "
        "m/s^2, rectangular, JCGM 100:2008 4.3.7); give --gravity-u-mps2 to state its own u",
        Short(out.u_mps2, 3), written, Short(half, 3));
  } else {
    constexpr double kHalfWidth = 0.03;  // 9.777 .. 9.837 m/s^2.
    out.u_mps2 = kHalfWidth / std::sqrt(3.0);
    out.basis = "standard_gravity_range";
    out.statement = fmt::format(
        "u(g) = {} m/s^2: standard gravity {} m/s^2 stands for the local gravity, which lies "
        "within +-{} m/s^2 of it at the Earth's surface (9.780 at the equator to 9.832 m/s^2 at "
        "the poles at sea level, 0.003 m/s^2 less per km of height), rectangular (JCGM 100:2008 "
        "4.3.7); give the local value with --gravity-mps2 and --gravity-u-mps2",
        Short(out.u_mps2, 3), Short(gravity_mps2, 8), kHalfWidth);
  }
  return out;
}

GravityUncertainty GravityUncertaintyOf(const Calibration& calibration) {
  return GravityUncertaintyOf(calibration.gravity_mps2, calibration.gravity_source,
                              calibration.gravity_u_mps2);
}

GravityShare GravityShareOf(const SensorCalibration& accel, const GravityUncertainty& gravity) {
  GravityShare out;
  out.gravity = gravity;
  const double rel = gravity.Relative();
  // u_c(x) = sqrt(u(x)^2 + (x u(g) / g)^2), JCGM 100:2008 5.1.2; a held constant (u = 0) stays.
  const auto with_g = [rel](double x, double u) { return u > 0.0 ? std::hypot(u, x * rel) : u; };
  const Eigen::Matrix3d m = accel.M();
  for (int a = 0; a < 3; ++a) {
    out.scale_u[a] = with_g(accel.model.scale[a], accel.scale_u[a]);
    out.sensitivity_u[a] = with_g(accel.sensitivity[a], accel.sensitivity_u[a]);
    for (int c = 0; c < 3; ++c) out.matrix_u(a, c) = with_g(m(a, c), accel.matrix_u(a, c));
  }
  return out;
}

}  // namespace metro
