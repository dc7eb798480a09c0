#include "metro/core/angles.hpp"

#include <catch2/catch.hpp>
#include <cmath>
#include <vector>

namespace metro {
namespace {

// Thesis Listing 1: MATLAB quat2angle output for two sensors (6 printed decimals).
TEST_CASE("Euler angles reproduce thesis Listing 1", "[core][angles]") {
  const EulerDeg s1 = EulerFromQuaternion({0.996276, 0.078654, 0.007692, 0.034479});
  CHECK(s1.yaw_deg == Approx(4.009102).margin(5e-4));
  CHECK(s1.pitch_deg == Approx(0.567438).margin(5e-4));
  CHECK(s1.roll_deg == Approx(9.047937).margin(5e-4));
  const EulerDeg s2 = EulerFromQuaternion({0.967565, 0.015171, -0.011132, 0.251919});
  CHECK(s2.yaw_deg == Approx(29.167585).margin(5e-4));
  CHECK(s2.pitch_deg == Approx(-1.672434).margin(5e-4));
  CHECK(s2.roll_deg == Approx(1.361458).margin(5e-4));
}

TEST_CASE("Euler and quaternion conversions invert each other", "[core][angles]") {
  for (double yaw : {-179.0, -90.0, 0.0, 45.0, 170.0}) {
    for (double pitch : {-80.0, -10.0, 0.0, 33.0, 89.0}) {
      for (double roll : {-175.0, 0.0, 12.5, 179.0}) {
        const EulerDeg back = EulerFromQuaternion(QuaternionFromEuler({yaw, pitch, roll}));
        CHECK(back.yaw_deg == Approx(yaw).margin(1e-9));
        CHECK(back.pitch_deg == Approx(pitch).margin(1e-9));
        CHECK(back.roll_deg == Approx(roll).margin(1e-9));
      }
    }
  }
}

TEST_CASE("asin argument is clamped at gimbal lock", "[core][angles]") {
  // A quaternion for pitch = +90 deg whose rounding pushes |2(xz - wy)| just over 1.
  const double h = std::sqrt(0.5) * (1.0 + 1e-12);
  const EulerDeg e = EulerFromQuaternion({h, 0.0, h, 0.0});
  CHECK(std::isfinite(e.pitch_deg));
  CHECK(std::abs(e.pitch_deg) == Approx(90.0).margin(1e-6));
}

TEST_CASE("WrapDeg180 maps into the half-open range from -180 to 180", "[core][angles]") {
  CHECK(WrapDeg180(180.0) == 180.0);
  CHECK(WrapDeg180(-180.0) == 180.0);
  CHECK(WrapDeg180(190.0) == Approx(-170.0));
  CHECK(WrapDeg180(-190.0) == Approx(170.0));
  CHECK(WrapDeg180(720.5) == Approx(0.5));
}

TEST_CASE("UnwrapDegInPlace removes jumps across +-180", "[core][angles]") {
  std::vector<double> a = {179.0, 179.5, -179.8, -179.0, 179.9, -178.0};
  const int jumps = UnwrapDegInPlace(&a);
  CHECK(jumps == 3);
  const std::vector<double> expected = {179.0, 179.5, 180.2, 181.0, 179.9, 182.0};
  for (size_t i = 0; i < a.size(); ++i) CHECK(a[i] == Approx(expected[i]));
}

}  // namespace
}  // namespace metro
