// metro_fw_apply_fixed against the model evaluated in double on the float32 constants, with
// the worst-case bound of docs/calibration-blob.md section 3.2 (written out here, not taken
// from the library), and against the float32 apply; the library's private 64 x 32 multiply
// against the product taken modulo 2^64.
#include "metro_fw/fixed.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <cstring>
#include <random>

#include "metro_fw/blob.h"
#include "test_support.hpp"
extern "C" {
#include "../src/le.h"  // metro_fw_mul, the library's private 64 x 32 multiply
}

namespace {

// Checks one sample: |fixed - exact| <= the section 3.2 bound, and the bound is small
// (below 2 % of an LSB-equivalent, so the check means something).
void CheckSample(const metro_fw_sensor_cal& c, const metro_fw_sensor_fixed& fx, const int16_t r[3],
                 int32_t temp_q12) {
  const double t_c = temp_q12 / 4096.0;
  const double t = std::min<double>(std::max<double>(t_c, c.t_valid_min_c), c.t_valid_max_c);
  const double dt = t - c.t_ref_c;
  double e[3], bias[3];
  for (int j = 0; j < 3; ++j) {
    bias[j] = c.b0[j] + (double{c.b1[j]} + double{c.b2[j]} * dt) * dt;
    e[j] = r[j] - bias[j];
  }
  int32_t y_q20[3];
  REQUIRE(metro_fw_apply_fixed(&fx, r, temp_q12, y_q20) == METRO_FW_OK);
  float y_f[3];
  REQUIRE(metro_fw_apply(&c, r, static_cast<float>(t_c), y_f) == METRO_FW_OK);
  const double lsb_si = std::sqrt(double{c.m[0]} * c.m[0] + double{c.m[1]} * c.m[1] +
                                  double{c.m[2]} * c.m[2]);  // row norm ~ s_nom
  for (int i = 0; i < 3; ++i) {
    double exact = 0.0, bound = std::ldexp(1.0, -21);
    for (int j = 0; j < 3; ++j) {
      const double m = c.m[3 * i + j];
      exact += m * e[j];
      bound += std::ldexp(std::fabs(r[j]) + std::fabs(bias[j]) + 1.0, -37);
      bound +=
          std::fabs(m) *
          (std::ldexp(1.0, -11) + std::ldexp(1.0 + std::fabs(dt), -16) + std::ldexp(dt * dt, -25) +
           std::ldexp(std::fabs(c.b1[j]) + 2.0 * std::fabs(c.b2[j]) * (std::fabs(dt) + 1.0 / 4096),
                      -12));
    }
    const double y = std::ldexp(static_cast<double>(y_q20[i]), -20);
    REQUIRE(bound < 0.02 * lsb_si);
    CHECK(std::fabs(y - exact) <= bound);
    // float32 apply: a few roundings of values up to full scale (see apply_test.cpp).
    CHECK(std::fabs(y - y_f[i]) <= bound + 1e-6 * 32768.0 * 1.1 * lsb_si);
  }
}

std::vector<metro_fw_sensor_cal> Sensors() {
  std::vector<metro_fw_sensor_cal> out = {fwtest::CalOf(fwtest::GoodAccel()),
                                          fwtest::CalOf(fwtest::GoodGyro())};
  for (uint8_t fs = 0; fs < 4; ++fs) {
    metro_fw_sensor_cal d;
    REQUIRE(metro_fw_sensor_defaults(METRO_FW_ACCEL, fs, &d) == METRO_FW_OK);
    out.push_back(d);
    REQUIRE(metro_fw_sensor_defaults(METRO_FW_GYRO, fs, &d) == METRO_FW_OK);
    out.push_back(d);
  }
  // Extremes section 3.1 admits: a 45 degree rotation at +10 % scale on the accelerometer
  // at fs_sel 3, bias at the limit over -40..85 degC around t_ref -40 (D = 125 degC).
  metro_fw_sensor_cal x;
  REQUIRE(metro_fw_sensor_defaults(METRO_FW_ACCEL, 3, &x) == METRO_FW_OK);
  const float k = 1.1f * x.m[0] * 0.70710678f;
  const float m[9] = {k, -k, 0.0f, k, k, 0.0f, 0.0f, 0.0f, 1.1f * x.m[0]};
  std::memcpy(x.m, m, sizeof(m));
  x.t_ref_c = -40.0f;
  x.t_valid_min_c = -40.0f;
  x.t_valid_max_c = 85.0f;
  for (int i = 0; i < 3; ++i) {
    x.b0[i] = i == 1 ? -200.0f : 200.0f;
    x.b1[i] = -2.0f;
    x.b2[i] = 0.0125f;
  }
  out.push_back(x);
  return out;
}

}  // namespace

TEST_CASE("Fixed apply is within the stated bound at the int16 corners", "[fw][fixed]") {
  const int16_t corners[] = {-32768, -32767, -1, 0, 1, 32766, 32767};
  for (const auto& c : Sensors()) {
    metro_fw_sensor_fixed fx;
    REQUIRE(metro_fw_fixed_from_cal(&c, &fx) == METRO_FW_OK);
    const int32_t temps_q12[] = {
        static_cast<int32_t>(std::lround(c.t_valid_min_c * 4096.0)) - 40960,
        static_cast<int32_t>(std::lround(c.t_valid_min_c * 4096.0)),
        static_cast<int32_t>(std::lround(c.t_ref_c * 4096.0)) + 1237,
        static_cast<int32_t>(std::lround(c.t_valid_max_c * 4096.0)),
        static_cast<int32_t>(std::lround(c.t_valid_max_c * 4096.0)) + 40960};
    for (int16_t a : corners) {
      for (int16_t b : corners) {
        for (int16_t d : corners) {
          const int16_t r[3] = {a, b, d};
          for (int32_t t : temps_q12) CheckSample(c, fx, r, t);
        }
      }
    }
  }
}

TEST_CASE("Fixed apply is within the stated bound on random samples", "[fw][fixed]") {
  std::mt19937 rng(11);
  std::uniform_int_distribution<int> raw(-32768, 32767);
  std::uniform_int_distribution<int32_t> temp_q12(-60 * 4096, 100 * 4096);
  for (const auto& c : Sensors()) {
    metro_fw_sensor_fixed fx;
    REQUIRE(metro_fw_fixed_from_cal(&c, &fx) == METRO_FW_OK);
    for (int n = 0; n < 5000; ++n) {
      const int16_t r[3] = {static_cast<int16_t>(raw(rng)), static_cast<int16_t>(raw(rng)),
                            static_cast<int16_t>(raw(rng))};
      CheckSample(c, fx, r, temp_q12(rng));
    }
  }
}

TEST_CASE("Fixed conversion rounds float32 constants to nearest", "[fw][fixed]") {
  metro_fw_sensor_cal c;
  REQUIRE(metro_fw_sensor_defaults(METRO_FW_GYRO, 0, &c) == METRO_FW_OK);
  c.b0[0] = 1.5f;                       // exact in Q16
  c.b0[1] = -3.0f / 65536.0f * 0.5f;    // -1.5 units of Q16: rounds away from zero to -2
  c.b1[2] = 1.0f / 131072.0f * 0.999f;  // just under half a unit: rounds to 0
  c.b2[0] = -100.0f;                    // exact in Q24
  c.t_ref_c = 25.5f;
  metro_fw_sensor_fixed fx;
  REQUIRE(metro_fw_fixed_from_cal(&c, &fx) == METRO_FW_OK);
  CHECK(fx.b0_q16[0] == 98304);
  CHECK(fx.b0_q16[1] == -2);
  CHECK(fx.b1_q16[2] == 0);
  CHECK(fx.b2_q24[0] == -100 * 16777216);
  CHECK(fx.t_ref_q12 == 104448);
  CHECK(fx.t_valid_min_q12 == -40 * 4096);
  CHECK(fx.m_q36[0] == std::lround(std::ldexp(double{c.m[0]}, 36)));
  CHECK(fx.m_q36[1] == 0);
}

TEST_CASE("Fixed conversion refuses constants outside their formats", "[fw][fixed]") {
  metro_fw_sensor_cal c;
  REQUIRE(metro_fw_sensor_defaults(METRO_FW_ACCEL, 0, &c) == METRO_FW_OK);
  metro_fw_sensor_fixed fx;
  auto bad = c;
  bad.b1[1] = 32768.0f;  // 2^15 LSB/degC: does not fit Q16 in int32
  CHECK(metro_fw_fixed_from_cal(&bad, &fx) == METRO_FW_E_ARG);
  CHECK(fx.m_q36[0] == 0);
  bad = c;
  bad.b2[0] = -128.0f;  // 2^7 LSB/degC^2
  CHECK(metro_fw_fixed_from_cal(&bad, &fx) == METRO_FW_E_ARG);
  bad = c;
  bad.m[4] = 1.0f / 32.0f;  // 2^-5 SI/LSB
  CHECK(metro_fw_fixed_from_cal(&bad, &fx) == METRO_FW_E_ARG);
  bad = c;
  bad.t_ref_c = std::nanf("");
  CHECK(metro_fw_fixed_from_cal(&bad, &fx) == METRO_FW_E_ARG);
  bad = c;
  bad.b1[1] = 32767.5f;  // largest that fits
  CHECK(metro_fw_fixed_from_cal(&bad, &fx) == METRO_FW_OK);
  CHECK(fx.b1_q16[1] == 2147450880);
  CHECK(metro_fw_fixed_from_cal(nullptr, &fx) == METRO_FW_E_ARG);
  CHECK(metro_fw_fixed_from_cal(&c, nullptr) == METRO_FW_E_ARG);
  const int16_t r[3] = {0, 0, 0};
  int32_t y[3];
  CHECK(metro_fw_apply_fixed(nullptr, r, 0, y) == METRO_FW_E_ARG);
  CHECK(metro_fw_apply_fixed(&fx, nullptr, 0, y) == METRO_FW_E_ARG);
  CHECK(metro_fw_apply_fixed(&fx, r, 0, nullptr) == METRO_FW_E_ARG);
}

TEST_CASE("Fixed MPU6050 temperature is within three Q12 units for every raw value",
          "[fw][fixed]") {
  for (int raw = -32768; raw <= 32767; ++raw) {
    const double exact_q12 = 4096.0 * (raw / 340.0 + 36.53);  // PS-MPU-6000A rev 3.4 sec. 6.4
    const int32_t q12 = metro_fw_mpu6050_temp_q12(static_cast<int16_t>(raw));
    REQUIRE(std::fabs(q12 - exact_q12) <= 3.0);
  }
}

TEST_CASE("The 64 x 32 multiply equals the product modulo 2^64", "[fw][fixed]") {
  // The product taken in unsigned 64-bit arithmetic (defined wrap-around), as two's complement.
  const auto expected = [](int64_t a, int32_t b) {
    return static_cast<uint64_t>(a) * static_cast<uint64_t>(static_cast<int64_t>(b));
  };
  const int64_t edge_a[] = {0,
                            1,
                            -1,
                            65535,
                            65536,
                            -65536,
                            INT32_MAX,
                            INT32_MIN,
                            0xFFFFFFFFll,
                            0x100000000ll,
                            -(1ll << 44),
                            (1ll << 44) - 1,
                            INT64_MAX,
                            INT64_MIN,
                            0x7FFF0000FFFF0000ll};
  const int32_t edge_b[] = {0, 1, -1, 65535, 65536, -65536, INT32_MAX, INT32_MIN, 512000, -512000};
  for (int64_t a : edge_a) {
    for (int32_t b : edge_b) {
      INFO("a " << a << " b " << b);
      CHECK(static_cast<uint64_t>(metro_fw_mul(a, b)) == expected(a, b));
    }
  }
  std::mt19937_64 rng(6);
  for (int i = 0; i < 1000000; ++i) {
    // Random magnitudes: a of 0 ... 63 bits, b of 0 ... 31 bits, either sign.
    const int64_t a = static_cast<int64_t>(rng() >> (rng() % 64));
    const int32_t b = static_cast<int32_t>(static_cast<uint32_t>(rng() >> (32 + rng() % 32)));
    const int64_t sa = (rng() & 1) ? -a : a;
    const int32_t sb = (rng() & 1) && b != INT32_MIN ? -b : b;
    REQUIRE(static_cast<uint64_t>(metro_fw_mul(sa, sb)) == expected(sa, sb));
  }
}
