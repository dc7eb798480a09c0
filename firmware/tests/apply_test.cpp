// metro_fw_apply against the model written out in double precision in the test.
#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <random>

#include "metro_fw/blob.h"
#include "test_support.hpp"

namespace {

// y = M * (r - b0 - b1*dT - b2*dT^2), dT = clamp(T) - t_ref, in double.
std::array<double, 3> Reference(const fwtest::Sensor& s, const int16_t r[3], double t_c) {
  const double t = std::min<double>(std::max<double>(t_c, s.t_valid_min_c), s.t_valid_max_c);
  const double dt = t - s.t_ref_c;
  double d[3];
  for (int i = 0; i < 3; ++i) d[i] = r[i] - s.b0[i] - s.b1[i] * dt - s.b2[i] * dt * dt;
  std::array<double, 3> y{};
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) y[i] += double{s.m[3 * i + j]} * d[j];
  }
  return y;
}

}  // namespace

TEST_CASE("Defaults turn counts into SI with the nominal sensitivity", "[fw][apply]") {
  metro_fw_sensor_cal accel, gyro;
  REQUIRE(metro_fw_sensor_defaults(METRO_FW_ACCEL, 0, &accel) == METRO_FW_OK);
  REQUIRE(metro_fw_sensor_defaults(METRO_FW_GYRO, 3, &gyro) == METRO_FW_OK);
  const int16_t one_g[3] = {0, 0, 16384};
  float y[3];
  REQUIRE(metro_fw_apply(&accel, one_g, 25.0f, y) == METRO_FW_OK);
  CHECK(y[2] == Approx(9.80665).epsilon(1e-6));
  CHECK(y[0] == 0.0f);
  // fs_sel 3: 16.4 LSB per deg/s; 1640 LSB = 100 deg/s = 1.745329 rad/s.
  const int16_t rate[3] = {1640, 0, 0};
  REQUIRE(metro_fw_apply(&gyro, rate, 25.0f, y) == METRO_FW_OK);
  CHECK(y[0] == Approx(1640.0 * 2000.0 / 32768.0 * fwtest::kPi / 180.0).epsilon(1e-6));
}

TEST_CASE("Apply equals the double-precision model within float32", "[fw][apply]") {
  std::mt19937 rng(3);
  std::uniform_int_distribution<int> raw(-32768, 32767);
  std::uniform_real_distribution<double> temp(-20.0, 70.0);
  for (const auto& s : {fwtest::GoodAccel(), fwtest::GoodGyro()}) {
    const auto cal = fwtest::CalOf(s);
    for (int n = 0; n < 2000; ++n) {
      const int16_t r[3] = {static_cast<int16_t>(raw(rng)), static_cast<int16_t>(raw(rng)),
                            static_cast<int16_t>(raw(rng))};
      const double t = temp(rng);
      float y[3];
      REQUIRE(metro_fw_apply(&cal, r, static_cast<float>(t), y) == METRO_FW_OK);
      const auto ref = Reference(s, r, static_cast<float>(t));
      const double full_scale = 32768.0 * 1.1 * std::fabs(double{s.m[0]});
      for (int i = 0; i < 3; ++i) {
        // A few float32 roundings of values up to full scale: 1e-6 of full scale.
        CHECK(std::fabs(y[i] - ref[i]) <= 1e-6 * full_scale);
      }
    }
  }
}

TEST_CASE("Temperature is clamped to the validity range and NaN means t_ref", "[fw][apply]") {
  const auto s = fwtest::GoodAccel();  // valid 0..50 degC, t_ref 25
  const auto cal = fwtest::CalOf(s);
  const int16_t r[3] = {1000, -2000, 16000};
  float at_max[3], beyond[3], at_ref[3], nan_t[3];
  metro_fw_apply(&cal, r, 50.0f, at_max);
  metro_fw_apply(&cal, r, 80.0f, beyond);
  metro_fw_apply(&cal, r, 25.0f, at_ref);
  metro_fw_apply(&cal, r, std::numeric_limits<float>::quiet_NaN(), nan_t);
  for (int i = 0; i < 3; ++i) {
    CHECK(beyond[i] == at_max[i]);
    CHECK(nan_t[i] == at_ref[i]);
  }
  const auto ref = Reference(s, r, 50.0);
  CHECK(at_max[2] == Approx(ref[2]).epsilon(1e-6));
}

TEST_CASE("MPU6050 temperature conversion follows the datasheet", "[fw][apply]") {
  CHECK(metro_fw_mpu6050_temp_c(0) == Approx(36.53));
  CHECK(metro_fw_mpu6050_temp_c(-3400) == Approx(26.53));
  CHECK(metro_fw_mpu6050_temp_c(340) == Approx(37.53));
}

TEST_CASE("Apply refuses NULL pointers", "[fw][apply]") {
  metro_fw_sensor_cal cal{};
  const int16_t r[3] = {0, 0, 0};
  float y[3];
  CHECK(metro_fw_apply(nullptr, r, 0.0f, y) == METRO_FW_E_ARG);
  CHECK(metro_fw_apply(&cal, nullptr, 0.0f, y) == METRO_FW_E_ARG);
  CHECK(metro_fw_apply(&cal, r, 0.0f, nullptr) == METRO_FW_E_ARG);
}
