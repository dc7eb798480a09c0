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

namespace {

// The nominal sensitivity s_nom, SI per LSB (PS-MPU-6000A rev 3.4 sections 6.1, 6.2).
double Nominal(metro_fw_sensor_kind kind, int fs_sel) {
  return kind == METRO_FW_ACCEL ? fwtest::kStandardGravity_mps2 / (16384 >> fs_sel)
                                : (250 << fs_sel) / 32768.0 * fwtest::kPi / 180.0;
}

// Decodes a section the way the validator does (its own fs_sel and dlpf_cfg).
metro_fw_sensor_cal DecodeSection(const fwtest::Sensor& s, metro_fw_sensor_kind kind) {
  std::vector<uint8_t> body(4, 0);  // body offset 0 would mean "absent"
  const std::vector<uint8_t> section = fwtest::SensorBody(s);
  body.insert(body.end(), section.begin(), section.end());
  metro_fw_buffer buf{body.data(), static_cast<uint32_t>(body.size())};
  metro_fw_blob_info info{};
  info.accel_off = info.gyro_off = 4;
  info.accel_len = info.gyro_len = 176;
  info.accel_version = info.gyro_version = METRO_FW_SEC_VERSION_1_0;
  metro_fw_sensor_cal out{};
  REQUIRE(metro_fw_sensor_decode(metro_fw_buffer_read, &buf, &info, kind, nullptr, &out) ==
          METRO_FW_OK);
  return out;
}

}  // namespace

TEST_CASE("The 3.2 bound at the worst section 3.1 admits is below 0.1 LSB", "[fw][fixed]") {
  // Every term of the bound at its largest under 3.1: row norm <= 1.1 s_nom, so
  // sum_j |M_ij| <= sqrt(3) 1.1 s_nom; |r| <= 32768; |bias| <= the bias limit; |dT| <= 125 degC;
  // |b1| + 2 |b2| |dT| <= the temperature-coefficient limit; |b2| < 2^7. An LSB-equivalent is
  // the row norm, at least 0.9 s_nom.
  for (int k = 0; k < 2; ++k) {
    const auto kind = static_cast<metro_fw_sensor_kind>(k);
    for (int fs = 0; fs < 4; ++fs) {
      const double s = Nominal(kind, fs);
      const double bias = (k == 0 ? 4096 : 7864) >> fs;
      const double tempco =
          (k == 0 ? METRO_FW_ACCEL_TEMPCO_LIMIT_LSB : METRO_FW_GYRO_TEMPCO_LIMIT_LSB) >> fs;
      const double d = 125.0;
      const double bound =
          std::ldexp(3.0 * (32768.0 + bias + 1.0), -37) +
          std::sqrt(3.0) * 1.1 * s *
              (std::ldexp(1.0, -11) + std::ldexp(1.0 + d, -16) + std::ldexp(d * d, -25) +
               std::ldexp(tempco + 2.0 * 128.0 / 4096.0, -12)) +
          std::ldexp(1.0, -21);
      const double lsb = bound / (0.9 * s);
      INFO("kind " << k << " fs_sel " << fs << " bound " << lsb << " LSB");
      CHECK(lsb < 0.1);
    }
  }
}

// issue #23: for every section the firmware accepts, its fixed-point and float applies stay
// within 0.1 LSB of the model evaluated exactly (double) on the section's constants, below,
// across and above the validity range. Sections are drawn at the edges 3.1 allows: random
// rotations at +-10 % scale, biases up to the bias limit, temperature coefficients up to the
// limit split between b1 and b2, validity ranges from 2 degC to the whole operating range
// with t_ref anywhere in -40 ... 85; those the firmware refuses are counted and skipped.
TEST_CASE("Every accepted section applies within 0.1 LSB of the exact model", "[fw][fixed]") {
  std::mt19937 rng(23);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::uniform_int_distribution<int> raw(-32768, 32767);
  const int16_t corners[] = {-32768, -32767, -1, 0, 1, 32766, 32767};
  int accepted = 0, refused = 0;
  double worst_fixed = 0.0, worst_float = 0.0;
  for (int iter = 0; iter < 600; ++iter) {
    const auto kind = static_cast<metro_fw_sensor_kind>(iter % 2);
    const int fs = (iter / 2) % 4;
    const double sn = Nominal(kind, fs);
    const double bias_limit = (kind == METRO_FW_ACCEL ? 4096 : 7864) >> fs;
    const double tempco = (kind == METRO_FW_ACCEL ? METRO_FW_ACCEL_TEMPCO_LIMIT_LSB
                                                  : METRO_FW_GYRO_TEMPCO_LIMIT_LSB) >>
                          fs;
    fwtest::Sensor s = kind == METRO_FW_ACCEL ? fwtest::GoodAccel() : fwtest::GoodGyro();
    s.fs_sel = static_cast<uint8_t>(fs);
    s.model_bits = 0x0F;
    // Temperatures: t_ref anywhere, a range 2 ... 125 degC wide inside -40 ... 85.
    const double width = 2.0 + 123.0 * std::pow(std::fabs(unit(rng)), 2.0);
    const double lo = -40.0 + (125.0 - width) * std::fabs(unit(rng));
    s.t_valid_min_c = static_cast<float>(lo);
    s.t_valid_max_c = static_cast<float>(lo + width);
    s.t_ref_c = static_cast<float>(-40.0 + 125.0 * std::fabs(unit(rng)));
    const double d = std::max(std::fabs(double{s.t_valid_min_c} - s.t_ref_c),
                              std::fabs(double{s.t_valid_max_c} - s.t_ref_c));
    // A rotation about a random axis (Rodrigues) times a scale within +-10 % per row.
    double axis[3] = {unit(rng), unit(rng), unit(rng)};
    const double n = std::sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
    for (double& a : axis) a /= n;
    const double angle = fwtest::kPi * unit(rng), c = std::cos(angle), sa = std::sin(angle);
    for (int i = 0; i < 3; ++i) {
      const double k = sn * (1.0 + 0.0999 * unit(rng));
      for (int j = 0; j < 3; ++j) {
        const double cross = i == j ? 0.0 : (((j - i + 3) % 3 == 1) ? -1.0 : 1.0) * axis[3 - i - j];
        const double r = (i == j ? c : 0.0) + (1.0 - c) * axis[i] * axis[j] + sa * cross;
        s.m[3 * i + j] = static_cast<float>(k * r);
      }
      // The temperature coefficient at up to its limit, shared between b1 and b2; the bias
      // bound at up to its limit.
      const double coef =
          std::min(tempco, 0.999 * bias_limit / d) * std::pow(std::fabs(unit(rng)), 0.1);
      const double share = std::fabs(unit(rng));
      s.b1[i] = static_cast<float>((unit(rng) < 0 ? -1 : 1) * share * coef);
      s.b2[i] = static_cast<float>((unit(rng) < 0 ? -1 : 1) * (1.0 - share) * coef / (2.0 * d));
      const double rest = (std::fabs(s.b1[i]) + std::fabs(s.b2[i]) * d) * d;
      s.b0[i] = static_cast<float>(unit(rng) * std::max(0.0, bias_limit - rest));
    }
    const metro_fw_sensor_cal cal = DecodeSection(s, kind);
    if (cal.status != METRO_FW_SENSOR_OK) {
      ++refused;
      continue;
    }
    ++accepted;
    metro_fw_sensor_fixed fx;
    REQUIRE(metro_fw_fixed_from_cal(&cal, &fx) == METRO_FW_OK);
    const auto check = [&](const int16_t r[3], int32_t temp_q12) {
      const double t = std::min<double>(std::max<double>(temp_q12 / 4096.0, cal.t_valid_min_c),
                                        cal.t_valid_max_c);
      const double dt = t - cal.t_ref_c;
      int32_t y_q20[3];
      REQUIRE(metro_fw_apply_fixed(&fx, r, temp_q12, y_q20) == METRO_FW_OK);
      float y_f[3];
      REQUIRE(metro_fw_apply(&cal, r, static_cast<float>(temp_q12 / 4096.0), y_f) == METRO_FW_OK);
      for (int i = 0; i < 3; ++i) {
        double exact = 0.0, row = 0.0;
        for (int j = 0; j < 3; ++j) {
          const double m = cal.m[3 * i + j];
          exact += m * (r[j] - cal.b0[j] - (double{cal.b1[j]} + double{cal.b2[j]} * dt) * dt);
          row += m * m;
        }
        row = std::sqrt(row);  // one LSB of the output, SI
        worst_fixed = std::max(worst_fixed, std::fabs(std::ldexp(y_q20[i], -20) - exact) / row);
        worst_float = std::max(worst_float, std::fabs(y_f[i] - exact) / row);
      }
    };
    const int32_t q_min = static_cast<int32_t>(std::lround(cal.t_valid_min_c * 4096.0));
    const int32_t q_max = static_cast<int32_t>(std::lround(cal.t_valid_max_c * 4096.0));
    const int32_t q_ref = static_cast<int32_t>(std::lround(cal.t_ref_c * 4096.0));
    const int32_t temps[] = {-60 * 4096,          q_min - 1, q_min,     q_ref,
                             (q_min + q_max) / 2, q_max,     q_max + 1, 100 * 4096};
    for (int16_t a : corners) {
      for (int16_t b : corners) {
        for (int16_t e : corners) {
          const int16_t r[3] = {a, b, e};
          for (int32_t t : temps) check(r, t);
        }
      }
    }
    std::uniform_int_distribution<int32_t> temp_q12(-60 * 4096, 100 * 4096);
    for (int k = 0; k < 300; ++k) {
      const int16_t r[3] = {static_cast<int16_t>(raw(rng)), static_cast<int16_t>(raw(rng)),
                            static_cast<int16_t>(raw(rng))};
      check(r, temp_q12(rng));
    }
  }
  INFO("accepted " << accepted << ", refused " << refused << "; worst fixed " << worst_fixed
                   << " LSB, float " << worst_float << " LSB");
  CHECK(accepted >= 500);
  CHECK(worst_fixed < 0.1);
  CHECK(worst_float < 0.1);
  WARN("fixed apply within " << worst_fixed << " LSB, float apply within " << worst_float
                             << " LSB of the exact model over " << accepted << " sections");
}

TEST_CASE("The section issue #23 found is refused and would err by LSBs", "[fw][fixed]") {
  // |b1| = 32767 LSB/degC over a 0.01 degC validity range passed the bias bound (328 LSB)
  // before the temperature-coefficient and span limits. The Q12 roundings of t_ref and the
  // clamp ends move dT by up to 2^-12 degC: 32767 * 2^-12 = 8 LSB.
  fwtest::Sensor s = fwtest::GoodAccel();
  s.t_ref_c = 25.0f + 0.3f / 4096.0f;
  s.t_valid_min_c = 25.0f - 0.4f / 4096.0f;
  s.t_valid_max_c = s.t_valid_min_c + 0.01f;
  s.b1 = {32767.0f, -32767.0f, 32767.0f};
  s.b2 = {0.0f, 0.0f, 0.0f};
  CHECK(DecodeSection(s, METRO_FW_ACCEL).status == METRO_FW_SENSOR_LIMITS);
  const metro_fw_sensor_cal cal = fwtest::CalOf(s);
  metro_fw_sensor_fixed fx;
  REQUIRE(metro_fw_fixed_from_cal(&cal, &fx) == METRO_FW_OK);
  const int16_t r[3] = {1000, -2000, 300};
  int32_t y_q20[3];
  REQUIRE(metro_fw_apply_fixed(&fx, r, 0, y_q20) == METRO_FW_OK);  // 0 degC: clamped to min
  const double dt = double{cal.t_valid_min_c} - cal.t_ref_c;
  double exact = 0.0;
  for (int j = 0; j < 3; ++j) exact += double{cal.m[j]} * (r[j] - cal.b0[j] - cal.b1[j] * dt);
  const double err_lsb = std::fabs(std::ldexp(y_q20[0], -20) - exact) / cal.m[0];
  INFO("fixed apply error " << err_lsb << " LSB");
  CHECK(err_lsb > 1.0);
}
