#include "metro/core/angles.hpp"

#include <algorithm>
#include <cmath>

#include "metro/core/check.hpp"

namespace metro {
namespace {
constexpr double kDegPerRad = 180.0 / M_PI;
}  // namespace

EulerDeg EulerFromQuaternion(const Quaternion& q) {
  // The angles do not depend on the quaternion's scale (every term below is quadratic), so
  // it is scaled by its largest component first: no product overflows (qw = 1e308) or
  // underflows (1e-170).
  const double m = std::max({std::fabs(q.w), std::fabs(q.x), std::fabs(q.y), std::fabs(q.z)});
  const double k = m > 0.0 && std::isfinite(m) ? 1.0 / m : 1.0;
  const double w = q.w * k, x = q.x * k, y = q.y * k, z = q.z * k;
  const double norm2 = w * w + x * x + y * y + z * z;
  EulerDeg e;
  e.yaw_deg = std::atan2(2.0 * (x * y + w * z), w * w + x * x - y * y - z * z) * kDegPerRad;
  const double s = norm2 > 0.0 ? std::clamp(2.0 * (x * z - w * y) / norm2, -1.0, 1.0) : 0.0;
  e.pitch_deg = -std::asin(s) * kDegPerRad;
  e.roll_deg = std::atan2(2.0 * (y * z + w * x), w * w - x * x - y * y + z * z) * kDegPerRad;
  return e;
}

Quaternion QuaternionFromEuler(const EulerDeg& e) {
  // q = q_z(yaw) * q_y(pitch) * q_x(roll), the inverse of EulerFromQuaternion.
  const double cy = std::cos(0.5 * e.yaw_deg / kDegPerRad);
  const double sy = std::sin(0.5 * e.yaw_deg / kDegPerRad);
  const double cp = std::cos(0.5 * e.pitch_deg / kDegPerRad);
  const double sp = std::sin(0.5 * e.pitch_deg / kDegPerRad);
  const double cr = std::cos(0.5 * e.roll_deg / kDegPerRad);
  const double sr = std::sin(0.5 * e.roll_deg / kDegPerRad);
  Quaternion q;
  q.w = cr * cp * cy + sr * sp * sy;
  q.x = sr * cp * cy - cr * sp * sy;
  q.y = cr * sp * cy + sr * cp * sy;
  q.z = cr * cp * sy - sr * sp * cy;
  return q;
}

double WrapDeg180(double angle_deg) {
  METRO_CHECK(std::isfinite(angle_deg));
  double a = std::fmod(angle_deg, 360.0);
  if (a <= -180.0) a += 360.0;
  if (a > 180.0) a -= 360.0;
  return a;
}

int UnwrapDegInPlace(std::vector<double>* angles_deg) {
  METRO_CHECK(angles_deg != nullptr);
  auto& a = *angles_deg;
  int jumps = 0;
  double offset = 0.0;
  for (size_t i = 1; i < a.size(); ++i) {
    const double raw_step = (a[i] + offset) - a[i - 1];
    if (raw_step > 180.0 || raw_step < -180.0) {
      offset -= 360.0 * std::round(raw_step / 360.0);
      ++jumps;
    }
    a[i] += offset;
  }
  return jumps;
}

}  // namespace metro
