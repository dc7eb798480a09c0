// Sensor sections v2.0 (issue #25, docs/calibration-blob.md 2.4, 3.1, 3.2): a declared nominal
// sensitivity s_nom and raw input encoding instead of an MPU6050 FS_SEL. The expected decisions
// and outputs are derived here from the spec (the real-number rule, the model in double on the
// unsigned counts as the calibrator sees them), not taken from the library.
#include <catch2/catch.hpp>
#include <cmath>
#include <cstring>
#include <random>

#include "metro_fw/blob.h"
#include "metro_fw/fixed.h"
#include "test_support.hpp"

namespace {

using fwtest::Blob;
using fwtest::Build;
using fwtest::Sensor;

constexpr double kDegToRad = fwtest::kPi / 180.0;

// A v2.0 body: the v1.0 body with byte 3 = input and the f32 at 172 = s_nom (SI per LSB).
std::vector<uint8_t> V2Body(const Sensor& s, float s_nom, uint8_t input) {
  std::vector<uint8_t> b = fwtest::SensorBody(s);
  b[3] = input;
  fwtest::PutF32(b, 172, s_nom);
  return b;
}

// imu_tk's Xsens gyroscope as its calibration describes it (datasets/external/imu_tk_xsens,
// SOURCE.md): 83.2 counts per deg/s, unsigned 16-bit counts with biases near 32768, no
// temperature term. M is a small rotation of diag(s) with 0.5 % scale differences; b0 is
// relative to the input's zero (32768).
Sensor XsensLikeGyro(double counts_per_dps) {
  Sensor s;
  const double k = kDegToRad / counts_per_dps;
  const double m[9] = {1.004 * k, 0.006 * k, -0.003 * k, -0.005 * k, 0.998 * k,
                       0.004 * k, 0.002 * k, -0.007 * k, 1.002 * k};
  for (int i = 0; i < 9; ++i) s.m[i] = static_cast<float>(m[i]);
  s.model_bits = METRO_FW_MODEL_BIAS | METRO_FW_MODEL_FULL_M;
  s.b0 = {-268.25f, -101.5f, 31.75f};
  s.b1 = {0.0f, 0.0f, 0.0f};
  s.b2 = {0.0f, 0.0f, 0.0f};
  s.t_valid_min_c = -40.0f;
  s.t_valid_max_c = 85.0f;
  s.fs_sel = 1;
  return s;
}

Blob OneSensorBlob(uint16_t type, uint16_t version, std::vector<uint8_t> body) {
  Blob b;
  b.seq = 5;
  std::vector<uint8_t> meta(128, 0);
  b.sections.push_back({METRO_FW_SEC_META, 0x0100, meta});
  b.sections.push_back({type, version, std::move(body)});
  b.flags = (type == METRO_FW_SEC_ACCEL ? METRO_FW_FLAG_ACCEL : METRO_FW_FLAG_GYRO) |
            ((b.sections[1].body[2] & 0x0Cu) != 0u ? METRO_FW_FLAG_TEMP_MODEL : 0u);
  return b;
}

// The decoder's status for a section on a tag configured with input `input` (and the section's
// own fs_sel, dlpf_cfg 3), and the validator's result.
struct Decoded {
  int validate = 0;
  metro_fw_sensor_cal cal{};
};
Decoded Decode(const std::vector<uint8_t>& bytes, metro_fw_sensor_kind kind, uint8_t fs_sel,
               uint8_t input) {
  Decoded d;
  metro_fw_blob_info info{};
  d.validate = fwtest::Validate(bytes, &info);
  metro_fw_config cfg = fwtest::Config();
  cfg.accel_fs_sel = kind == METRO_FW_ACCEL ? fs_sel : 0;
  cfg.gyro_fs_sel = kind == METRO_FW_GYRO ? fs_sel : 0;
  cfg.accel_input = kind == METRO_FW_ACCEL ? input : 0;
  cfg.gyro_input = kind == METRO_FW_GYRO ? input : 0;
  metro_fw_buffer buf{bytes.data(), static_cast<uint32_t>(bytes.size())};
  REQUIRE(metro_fw_sensor_decode(metro_fw_buffer_read, &buf, &info, kind, &cfg, &d.cal) ==
          METRO_FW_OK);
  return d;
}

// Section 3.2's bound for one output (SI), evaluated on the double model's terms.
double FixedBound(const metro_fw_sensor_cal& c, int i, const double r[3], const double bias[3],
                  double dt) {
  double bound = std::ldexp(1.0, -21);
  for (int j = 0; j < 3; ++j) {
    bound += std::ldexp(std::fabs(r[j]) + std::fabs(bias[j]) + 1.0, -37);
    bound +=
        std::fabs(c.m[3 * i + j]) *
        (std::ldexp(1.0, -11) + std::ldexp(1.0 + std::fabs(dt), -16) + std::ldexp(dt * dt, -25) +
         std::ldexp(std::fabs(c.b1[j]) + 2.0 * std::fabs(c.b2[j]) * (std::fabs(dt) + 1.0 / 4096),
                    -12));
  }
  return bound;
}

}  // namespace

TEST_CASE("v2.0: an Xsens-like gyroscope with unsigned counts is accepted and applied",
          "[fw][blob][v2]") {
  const Sensor s = XsensLikeGyro(83.2);
  const float s_nom = static_cast<float>(kDegToRad / 83.2);
  const auto bytes = Build(OneSensorBlob(METRO_FW_SEC_GYRO, METRO_FW_SEC_VERSION_2_0,
                                         V2Body(s, s_nom, METRO_FW_INPUT_OFFSET_BINARY)));
  Decoded d = Decode(bytes, METRO_FW_GYRO, 1, METRO_FW_INPUT_OFFSET_BINARY);
  CHECK(d.validate == METRO_FW_OK);
  REQUIRE(d.cal.status == METRO_FW_SENSOR_OK);
  CHECK(d.cal.input == METRO_FW_INPUT_OFFSET_BINARY);
  CHECK(d.cal.b0[0] == -268.25f);
  // The same constants as v1.0 at fs_sel 1: 83.2 / 65.536 = +27 % from its s_nom, refused.
  const auto v1 = Build(OneSensorBlob(METRO_FW_SEC_GYRO, 0x0100, fwtest::SensorBody(s)));
  CHECK(fwtest::Validate(v1) == METRO_FW_E_SENSOR);
  // A tag whose gyroscope driver delivers int16 does not use it.
  CHECK(Decode(bytes, METRO_FW_GYRO, 1, METRO_FW_INPUT_INT16).cal.status ==
        METRO_FW_SENSOR_CONFIG_MISMATCH);
  // Nor a v1.0 section on a tag whose driver is offset binary.
  CHECK(Decode(Build(fwtest::StandardBlob(3)), METRO_FW_GYRO, 0, METRO_FW_INPUT_OFFSET_BINARY)
            .cal.status == METRO_FW_SENSOR_CONFIG_MISMATCH);

  // Apply to unsigned counts u: the model in double on u and the absolute bias 32768 + b0 (the
  // calibrator's view), against the fixed apply of u - 32768.
  metro_fw_sensor_fixed fx;
  REQUIRE(metro_fw_fixed_from_cal(&d.cal, &fx) == METRO_FW_OK);
  std::mt19937 rng(25);
  std::uniform_int_distribution<int> word(0, 65535);
  const uint16_t corners[] = {0, 1, 32767, 32768, 32769, 65534, 65535};
  double worst_lsb = 0.0;
  for (int n = 0; n < 20000 + 343; ++n) {
    uint16_t u[3];
    if (n < 343) {
      u[0] = corners[n % 7];
      u[1] = corners[(n / 7) % 7];
      u[2] = corners[n / 49];
    } else {
      for (auto& x : u) x = static_cast<uint16_t>(word(rng));
    }
    const int16_t r[3] = {METRO_FW_OFFSET_BINARY_TO_INT16(u[0]),
                          METRO_FW_OFFSET_BINARY_TO_INT16(u[1]),
                          METRO_FW_OFFSET_BINARY_TO_INT16(u[2])};
    for (int j = 0; j < 3; ++j) REQUIRE(r[j] == static_cast<int>(u[j]) - 32768);
    int32_t y_q20[3];
    REQUIRE(metro_fw_apply_fixed(&fx, r, 30 * 4096, y_q20) == METRO_FW_OK);
    double e[3], rr[3], bias[3];
    for (int j = 0; j < 3; ++j) {
      e[j] = u[j] - (32768.0 + s.b0[j]);
      rr[j] = r[j];
      bias[j] = s.b0[j];
    }
    for (int i = 0; i < 3; ++i) {
      double exact = 0.0;
      for (int j = 0; j < 3; ++j) exact += double{s.m[3 * i + j]} * e[j];
      const double y = std::ldexp(static_cast<double>(y_q20[i]), -20);
      const double bound = FixedBound(d.cal, i, rr, bias, 0.0);
      REQUIRE(std::fabs(y - exact) <= bound);
      worst_lsb = std::max(worst_lsb, std::fabs(y - exact) / s_nom);
    }
  }
  CHECK(worst_lsb < 0.01);
}

TEST_CASE("v2.0: the row norms are checked against the declared s_nom", "[fw][blob][v2]") {
  for (const double counts_per_unit : {83.2, 20.0, 250.0}) {
    for (const double scale : {0.9 * 1.0001, 0.9 * 0.9999, 1.1 * 0.9999, 1.1 * 1.0001}) {
      Sensor s = XsensLikeGyro(counts_per_unit);
      const float s_nom = static_cast<float>(kDegToRad / counts_per_unit);
      // every row norm = scale * s_nom: a rotation about z scaled
      const double a = 0.3, k = scale * s_nom;
      const double m[9] = {
          k * std::cos(a), -k * std::sin(a), 0, k * std::sin(a), k * std::cos(a), 0, 0, 0, k};
      for (int i = 0; i < 9; ++i) s.m[i] = static_cast<float>(m[i]);
      const bool inside = scale > 0.9 && scale < 1.1;
      const auto bytes = Build(OneSensorBlob(METRO_FW_SEC_GYRO, METRO_FW_SEC_VERSION_2_0,
                                             V2Body(s, s_nom, METRO_FW_INPUT_INT16)));
      INFO(counts_per_unit << " " << scale);
      CHECK((fwtest::Validate(bytes) == METRO_FW_OK) == inside);
      CHECK((Decode(bytes, METRO_FW_GYRO, 1, 0).cal.status == METRO_FW_SENSOR_OK) == inside);
    }
  }
}

TEST_CASE("v2.0: s_nom outside 2^-14 .. 2^-7 SI per LSB, NaN, 0 or negative is refused",
          "[fw][blob][v2]") {
  const float lo = std::ldexp(1.0f, -14), hi = std::ldexp(1.0f, -7);
  const float below_hi = std::nextafter(hi, 0.0f);
  struct Case {
    float s_nom;
    bool ok;
  };
  for (const Case c : {Case{lo, true}, Case{below_hi, true}, Case{std::nextafter(lo, 0.0f), false},
                       Case{hi, false}, Case{std::nanf(""), false}, Case{0.0f, false},
                       Case{-lo, false}, Case{INFINITY, false}}) {
    Sensor s = XsensLikeGyro(83.2);
    s.model_bits = METRO_FW_MODEL_BIAS;  // diagonal M = s_nom
    for (float& m : s.m) m = 0.0f;
    s.m[0] = s.m[4] = s.m[8] = std::isfinite(c.s_nom) && c.s_nom > 0 ? c.s_nom : 1e-3f;
    INFO(c.s_nom);
    const auto bytes = Build(OneSensorBlob(METRO_FW_SEC_ACCEL, METRO_FW_SEC_VERSION_2_0,
                                           V2Body(s, c.s_nom, METRO_FW_INPUT_INT16)));
    CHECK(fwtest::Validate(bytes) == (c.ok ? METRO_FW_OK : METRO_FW_E_SENSOR));
    const Decoded d = Decode(bytes, METRO_FW_ACCEL, 1, 0);
    CHECK(d.cal.status == (c.ok ? METRO_FW_SENSOR_OK : METRO_FW_SENSOR_LIMITS));
    if (c.ok) {
      // The fixed apply's formats hold M and the output at the int16 corners (3.2).
      metro_fw_sensor_fixed fx;
      REQUIRE(metro_fw_fixed_from_cal(&d.cal, &fx) == METRO_FW_OK);
      const int16_t r[3] = {-32768, 32767, -32768};
      int32_t y[3];
      REQUIRE(metro_fw_apply_fixed(&fx, r, 0, y) == METRO_FW_OK);
      CHECK(std::fabs(std::ldexp(static_cast<double>(y[1]), -20) -
                      double{d.cal.m[4]} * (32767.0 - d.cal.b0[1])) < 1e-3);
    }
  }
}

TEST_CASE("v2.0: bias and temperature coefficient limits are fs_sel 0's, in counts",
          "[fw][blob][v2]") {
  // Bias: |b0| + |b1| D + |b2| D^2 <= 4096 (accel) / 7864 (gyro) counts whatever s_nom and
  // fs_sel; temperature coefficient |b1| + 2 |b2| D <= 80 / 88 LSB/degC.
  for (const bool accel : {true, false}) {
    const double limit = accel ? 4096.0 : 7864.0, tempco = accel ? 80.0 : 88.0;
    for (const double b0 : {limit - 0.01, limit + 0.01}) {
      for (const double b1 : {0.0, tempco - 0.01, tempco + 0.01}) {
        Sensor s = XsensLikeGyro(83.2);
        s.fs_sel = 3;  // the limits do not shift with it in v2.0
        s.model_bits |= METRO_FW_MODEL_LINEAR_T;
        s.t_ref_c = 25.0f;
        s.t_valid_min_c = 24.0f;
        s.t_valid_max_c = 26.0f;  // D = 1 degC
        s.b0 = {0.0f, static_cast<float>(-(b0 - b1)), 0.0f};
        s.b1 = {0.0f, static_cast<float>(b1), 0.0f};
        const bool ok = b0 <= limit && b1 <= tempco;
        const auto bytes = Build(OneSensorBlob(accel ? METRO_FW_SEC_ACCEL : METRO_FW_SEC_GYRO,
                                               METRO_FW_SEC_VERSION_2_0,
                                               V2Body(s, static_cast<float>(kDegToRad / 83.2), 1)));
        INFO(accel << " " << b0 << " " << b1);
        CHECK((fwtest::Validate(bytes) == METRO_FW_OK) == ok);
      }
    }
  }
}

TEST_CASE("v2.0: an unknown input code is BAD_MODEL; v2.0 is exactly 176 bytes", "[fw][blob][v2]") {
  const Sensor s = XsensLikeGyro(83.2);
  const float s_nom = static_cast<float>(kDegToRad / 83.2);
  auto blob = OneSensorBlob(METRO_FW_SEC_GYRO, METRO_FW_SEC_VERSION_2_0, V2Body(s, s_nom, 2));
  CHECK(fwtest::Validate(Build(blob)) == METRO_FW_E_SENSOR);
  CHECK(Decode(Build(blob), METRO_FW_GYRO, 1, 2).cal.status == METRO_FW_SENSOR_BAD_MODEL);
  blob.sections[1].body = V2Body(s, s_nom, 1);
  blob.sections[1].body.resize(180, 0);
  CHECK(fwtest::Validate(Build(blob)) == METRO_FW_E_SECTION);
  blob.sections[1].body.resize(172);
  CHECK(fwtest::Validate(Build(blob)) == METRO_FW_E_SECTION);
  // v2.1 may append fields: read, the tail ignored.
  blob.sections[1].version = 0x0201;
  blob.sections[1].body = V2Body(s, s_nom, 1);
  blob.sections[1].body.resize(192, 0xA5);
  CHECK(fwtest::Validate(Build(blob)) == METRO_FW_OK);
  // META has no major 2: such a META is skipped, as any unknown major.
  Blob meta2 = fwtest::StandardBlob(3);
  meta2.sections[0].version = 0x0200;
  meta2.sections[0].body.resize(4);
  CHECK(fwtest::Validate(Build(meta2)) == METRO_FW_OK);
}

TEST_CASE("v2.0: the fixed apply stays within 0.1 LSB for every s_nom and section 3.1 admits",
          "[fw][fixed][v2]") {
  // Worst case of the 3.2 bound over a v2.0 section, divided by one LSB (0.9 s_nom, the
  // smallest row norm): |r| <= 32768, |bias| <= the bias limit, |dT| <= 125 degC, the
  // temperature coefficient at its limit, |b2| < 2^7, sum_j |M_ij| <= sqrt(3) 1.1 s_nom.
  for (const bool accel : {true, false}) {
    const double limit = accel ? 4096 : 7864, tempco = accel ? 80 : 88;
    for (int q = METRO_FW_S_NOM_MIN_Q; q <= METRO_FW_S_NOM_MAX_Q; ++q) {
      const double s_nom = std::ldexp(1.0, 14 - q);  // the smallest s_nom of that Q
      const double sum_m = std::sqrt(3.0) * 1.1 * s_nom;
      const double bound =
          std::ldexp(1.0, -21) + 3.0 * std::ldexp(32768.0 + limit + 1.0, -37) +
          sum_m * (std::ldexp(1.0, -11) + std::ldexp(126.0, -16) + std::ldexp(125.0 * 125.0, -25) +
                   std::ldexp(tempco + 2.0 * 128.0 / 4096.0, -12));
      INFO(accel << " Q" << q);
      CHECK(bound / (0.9 * s_nom) < 0.1);
      // and the output fits Q20: |y| <= sum_m (32768 + limit) < 2^11 at the largest s_nom
      CHECK(sum_m * 2.0 * (32768.0 + limit) < 2048.0);
    }
  }
  // Random v2.0 sections at the edges, decoded and accepted by the firmware, applied.
  std::mt19937 rng(2525);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::uniform_int_distribution<int> raw(-32768, 32767);
  int accepted = 0;
  double worst = 0.0;
  for (int n = 0; n < 300; ++n) {
    const bool accel = n % 2 == 0;
    const double s_nom = std::ldexp(1.0, -14 + static_cast<int>(7 * (unit(rng) + 1) / 2));
    const double k = s_nom * (1.0 + 0.099 * unit(rng));
    const double a = fwtest::kPi * unit(rng);
    Sensor s;
    s.model_bits = 0x0F;
    const double m[9] = {
        k * std::cos(a), -k * std::sin(a), 0, k * std::sin(a), k * std::cos(a), 0, 0, 0, k};
    for (int i = 0; i < 9; ++i) s.m[i] = static_cast<float>(m[i]);
    const double limit = accel ? 4096 : 7864, tempco = accel ? 80 : 88;
    s.t_ref_c = static_cast<float>(22.5 + 60 * unit(rng));
    s.t_valid_min_c = -40.0f;
    s.t_valid_max_c = 85.0f;
    const double dmax = std::max(85.0 - s.t_ref_c, s.t_ref_c + 40.0);
    for (int j = 0; j < 3; ++j) {
      // each term at most half its limit (tempco) or a quarter of the bias limit
      s.b1[j] = static_cast<float>(std::min(0.5 * tempco, 0.25 * limit / dmax) * unit(rng) * 0.99);
      s.b2[j] = static_cast<float>(std::min(0.25 * tempco / dmax, 0.25 * limit / (dmax * dmax)) *
                                   unit(rng) * 0.99);
      const double rest = limit - std::fabs(s.b1[j]) * dmax - std::fabs(s.b2[j]) * dmax * dmax;
      s.b0[j] = static_cast<float>(std::max(0.0, rest) * 0.99 * unit(rng));
    }
    const auto bytes =
        Build(OneSensorBlob(accel ? METRO_FW_SEC_ACCEL : METRO_FW_SEC_GYRO,
                            METRO_FW_SEC_VERSION_2_0, V2Body(s, static_cast<float>(s_nom), 0)));
    const Decoded d = Decode(bytes, accel ? METRO_FW_ACCEL : METRO_FW_GYRO, 0, 0);
    INFO(n << " s_nom " << s_nom << " status " << int{d.cal.status});
    CHECK(d.validate == (d.cal.status == METRO_FW_SENSOR_OK ? METRO_FW_OK : METRO_FW_E_SENSOR));
    if (d.cal.status != METRO_FW_SENSOR_OK) continue;
    ++accepted;
    metro_fw_sensor_fixed fx;
    REQUIRE(metro_fw_fixed_from_cal(&d.cal, &fx) == METRO_FW_OK);
    for (int t = -60; t <= 100; t += 40) {
      for (int rep = 0; rep < 50; ++rep) {
        const int16_t r[3] = {static_cast<int16_t>(raw(rng)), static_cast<int16_t>(raw(rng)),
                              static_cast<int16_t>(raw(rng))};
        int32_t y_q20[3];
        REQUIRE(metro_fw_apply_fixed(&fx, r, t * 4096, y_q20) == METRO_FW_OK);
        const double tc = std::min<double>(std::max<double>(t, s.t_valid_min_c), s.t_valid_max_c);
        const double dt = tc - double{d.cal.t_ref_c};
        double e[3], rr[3], bias[3];
        for (int j = 0; j < 3; ++j) {
          bias[j] = d.cal.b0[j] + (double{d.cal.b1[j]} + double{d.cal.b2[j]} * dt) * dt;
          e[j] = r[j] - bias[j];
          rr[j] = r[j];
        }
        for (int i = 0; i < 3; ++i) {
          double exact = 0.0;
          for (int j = 0; j < 3; ++j) exact += double{d.cal.m[3 * i + j]} * e[j];
          const double y = std::ldexp(static_cast<double>(y_q20[i]), -20);
          REQUIRE(std::fabs(y - exact) <= FixedBound(d.cal, i, rr, bias, dt));
          worst = std::max(worst, std::fabs(y - exact) / (0.9 * s_nom));
        }
      }
    }
  }
  CHECK(accepted > 250);  // all but the few at s_nom = 2^-7 (outside)
  CHECK(worst < 0.1);
}
