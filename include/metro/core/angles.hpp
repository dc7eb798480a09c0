// Attitude conversions and wrap-safe angle arithmetic.
//
// Quaternions are stored w, x, y, z (scalar first), as the tags send them.
//
// Euler angles use the aerospace sequence (1,2,3) of the thesis (eq. 4.41), i.e. the
// z-y-x intrinsic yaw-pitch-roll:
//   yaw   = atan2(2(x y + w z), w^2 + x^2 - y^2 - z^2)
//   pitch = -asin(2(x z - w y))            (argument clamped to [-1, 1])
//   roll  = atan2(2(y z + w x), w^2 - x^2 - y^2 + z^2)
// yaw and roll lie in (-180, 180] deg, pitch in [-90, 90] deg. The formulas use the
// quaternion as given (no normalisation is assumed: the atan2 terms are scale-invariant
// and the asin term is divided by the squared norm).
#pragma once

#include <vector>

namespace metro {

struct Quaternion {
  double w = 1.0, x = 0.0, y = 0.0, z = 0.0;
};

struct EulerDeg {
  double yaw_deg = 0.0;
  double pitch_deg = 0.0;
  double roll_deg = 0.0;
};

EulerDeg EulerFromQuaternion(const Quaternion& q);
Quaternion QuaternionFromEuler(const EulerDeg& e);

// |pitch| at or above this is reported as close to gimbal lock (yaw and roll then trade
// off against each other and their statistics lose meaning).
inline constexpr double kGimbalLockWarnPitchDeg = 85.0;

// Wraps an angle into (-180, 180] deg.
double WrapDeg180(double angle_deg);

// Removes 360-deg jumps from a series in place (each step is taken as the shortest turn,
// i.e. |difference| <= 180 deg), so that statistics of an angle that wanders across
// +-180 deg are computed on a continuous series. Returns the number of jumps removed.
int UnwrapDegInPlace(std::vector<double>* angles_deg);

}  // namespace metro
