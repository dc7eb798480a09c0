#include "metro/calibration/imu_model.hpp"

#include <catch2/catch.hpp>

namespace metro {
namespace {

TEST_CASE("Misalignment matrices follow the documented layout", "[calibration]") {
  const double a[3] = {0.01, 0.02, 0.03};
  const Eigen::Matrix3d ta = MisalignmentMatrix(ImuSensor::kAccel, a);
  Eigen::Matrix3d expected_a;
  expected_a << 1, -0.01, 0.02, 0, 1, -0.03, 0, 0, 1;
  CHECK(ta.isApprox(expected_a, 1e-15));
  const double g[6] = {0.01, 0.02, 0.03, 0.04, 0.05, 0.06};
  const Eigen::Matrix3d tg = MisalignmentMatrix(ImuSensor::kGyro, g);
  Eigen::Matrix3d expected_g;
  expected_g << 1, -0.01, 0.02, 0.03, 1, -0.04, -0.05, 0.06, 1;
  CHECK(tg.isApprox(expected_g, 1e-15));
}

TEST_CASE("Apply removes the bias before scaling and Invert undoes Apply", "[calibration]") {
  SensorModel m;
  m.sensor = ImuSensor::kGyro;
  m.bias = Eigen::Vector3d(100, -200, 50);
  m.scale = Eigen::Vector3d(1.0 / 131, 1.0 / 130, 1.0 / 132);
  m.misalignment = {0.01, -0.02, 0.005, 0.01, -0.01, 0.02};
  m.has_temperature = true;
  m.bias_per_c = Eigen::Vector3d(2, -1, 0.5);
  m.t_ref_c = 30;
  const Eigen::Vector3d raw(1000, -3000, 2500);
  const double temp_c = 34;
  // By hand: b(34) = b0 + 4 b1 = (108, -204, 52); y = T K (raw - b).
  const Eigen::Vector3d v(1000 - 108, -3000 + 204, 2500 - 52);
  const Eigen::Vector3d kv(v[0] / 131, v[1] / 130, v[2] / 132);
  const Eigen::Vector3d expected(kv[0] - 0.01 * kv[1] - 0.02 * kv[2],
                                 0.005 * kv[0] + kv[1] - 0.01 * kv[2],
                                 0.01 * kv[0] + 0.02 * kv[1] + kv[2]);
  const Eigen::Vector3d y = m.Apply(raw, temp_c);
  CHECK(y.isApprox(expected, 1e-12));
  CHECK(m.Invert(y, temp_c).isApprox(raw, 1e-12));
}

TEST_CASE("Nominal scales are the MPU6050 datasheet sensitivities", "[calibration]") {
  CHECK(NominalScale(ImuSensor::kAccel, "LSB", 2).value() == Approx(1.0 / 16384));
  CHECK(NominalScale(ImuSensor::kAccel, "LSB", 16).value() == Approx(1.0 / 2048));
  CHECK(NominalScale(ImuSensor::kGyro, "LSB", 250).value() == Approx(1.0 / 131));
  CHECK(NominalScale(ImuSensor::kGyro, "LSB", 1000).value() == Approx(1.0 / 32.8));
  CHECK(NominalScale(ImuSensor::kAccel, "m/s^2", 0).value() == Approx(1.0 / 9.80665));
  CHECK(NominalScale(ImuSensor::kGyro, "rad/s", 0).value() == Approx(57.29577951308232));
  CHECK_FALSE(NominalScale(ImuSensor::kGyro, "g", 0).has_value());
  CHECK_FALSE(NominalScale(ImuSensor::kAccel, "LSB", 0).has_value());
  CHECK(ParseModelKind("full") == ModelKind::kFull);
  CHECK_FALSE(ParseModelKind("affine").has_value());
}

}  // namespace
}  // namespace metro
