// The section 3.1 limit checks of metro_fw_sensor_decode (exact integer arithmetic on
// fixed-point forms of the binary32 constants) against the real-number rule evaluated in double
// precision on the same constants. docs/calibration-blob.md 3.1 states the decision band: the
// two may differ only for a quantity within its band of a limit. Every constructed section
// farther than that from every limit must get the real-number decision; sections at the limits
// +-2 bands check that "outside by more than the band" is rejected and "inside by more than the
// band" accepted.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

#include "metro_fw/blob.h"
#include "metro_fw/fixed.h"
#include "test_support.hpp"

namespace {

// Real nominal sensitivity, SI per LSB (MPU6050 PS-MPU-6000A rev 3.4 tables 6.1, 6.2).
double NominalSensitivity(metro_fw_sensor_kind kind, int fs_sel) {
  return kind == METRO_FW_ACCEL ? fwtest::kStandardGravity_mps2 / (16384 >> fs_sel)
                                : (250 << fs_sel) / 32768.0 * fwtest::kPi / 180.0;
}

double BiasLimit(metro_fw_sensor_kind kind, int fs_sel) {
  return (kind == METRO_FW_ACCEL ? 4096 : 7864) >> fs_sel;  // 0.25 g, 60 deg/s in counts
}

// The temperature coefficient limit of 3.1, LSB/degC: 4.9 mg/degC, 0.67 deg/s/degC in counts.
double TempcoLimit(metro_fw_sensor_kind kind, int fs_sel) {
  return (kind == METRO_FW_ACCEL ? 80 : 88) >> fs_sel;
}
constexpr double kMinSpan_c = 2.0;  // the narrowest validity range of 3.1

// Half-units of the formats of 3.1: M in Q(k - fs_sel), k = 25 / 27; b0, b1 in Q16, b2 in
// Q24; T in Q12.
double RowNormBand(metro_fw_sensor_kind kind, int fs_sel) {
  return std::sqrt(3.0) / 2.0 * std::ldexp(1.0, -((kind == METRO_FW_ACCEL ? 25 : 27) - fs_sel));
}
constexpr double kTempBand_c = 1.0 / 8192.0;  // 2^-13
constexpr double kTempStep_c = 1.0 / 4096.0;  // 2^-12

// The bias-bound band of 3.1: delta = 2^-17 (1 + D' + D'^2) + 2^-12 (|b1| + 2 |b2| D'),
// D' = D + 2^-12.
double BiasBand(double d, double b1, double b2) {
  const double dp = d + kTempStep_c;
  return std::ldexp(1.0 + dp + dp * dp, -17) +
         std::ldexp(std::fabs(b1) + 2 * std::fabs(b2) * dp, -12);
}

// The band of the temperature coefficient |b1| + 2 |b2| D: the Q16 rounding of b1 (2^-17), the
// Q24 rounding of b2 times 2 D' (2^-24 D'), D within 2^-12 degC times 2 |b2|, and the floor of
// |b2| D to Q28 counted twice (2^-27); D' = D + 2^-12.
double TempcoBand(double d, double b2) {
  const double dp = d + kTempStep_c;
  return std::ldexp(1.0, -17) + std::ldexp(dp, -24) + std::ldexp(std::fabs(b2), -11) +
         std::ldexp(1.0, -27);
}

enum class Real { kAccept, kReject, kNear };

// Outcome of one check: clearly passes, clearly fails, or within its band of the limit.
struct Tally {
  bool fail = false;
  bool near = false;
  // x must be <= limit; band is where the integer decision may differ.
  void AtMost(double x, double limit, double band) {
    if (x > limit + band) {
      fail = true;
    } else if (x >= limit - band) {
      near = true;
    }
  }
  void Exact(bool ok) { fail = fail || !ok; }
  Real Result() const { return fail ? Real::kReject : near ? Real::kNear : Real::kAccept; }
};

// The 3.1 rule on the real values of the (finite) binary32 constants, model bits applied.
Real RealRule(const fwtest::Sensor& in, metro_fw_sensor_kind kind, int fs_sel) {
  const uint8_t bits = in.model_bits;
  double m[9], b0[3], b1[3], b2[3];
  for (int i = 0; i < 9; ++i) m[i] = (i % 4 == 0 || (bits & 0x02)) ? in.m[i] : 0.0;
  for (int i = 0; i < 3; ++i) {
    b0[i] = (bits & 0x01) ? in.b0[i] : 0.0;
    b1[i] = (bits & 0x04) ? in.b1[i] : 0.0;
    b2[i] = (bits & 0x08) ? in.b2[i] : 0.0;
  }
  const double s = NominalSensitivity(kind, fs_sel);
  const double t_ref = in.t_ref_c, t_min = in.t_valid_min_c, t_max = in.t_valid_max_c;
  Tally t;
  for (double x : {t_ref, t_min, t_max}) {
    t.AtMost(x, 85.0, kTempBand_c);
    t.AtMost(-x, 40.0, kTempBand_c);
  }
  // t_max - t_min >= 2 degC: the difference of two Q12 roundings is within 2^-12 degC of it.
  t.AtMost(kMinSpan_c - (t_max - t_min), 0.0, kTempStep_c);
  const double d = std::max(std::fabs(t_min - t_ref), std::fabs(t_max - t_ref));
  const double band_n = RowNormBand(kind, fs_sel);
  double r_max = 1.1 * s;
  for (int i = 0; i < 3; ++i) {
    const double n =
        std::sqrt(m[3 * i] * m[3 * i] + m[3 * i + 1] * m[3 * i + 1] + m[3 * i + 2] * m[3 * i + 2]);
    r_max = std::max(r_max, n);
    t.AtMost(n, 1.1 * s, band_n);
    t.AtMost(-n, -0.9 * s, band_n);
    t.Exact(std::fabs(b1[i]) < 32768.0 && std::fabs(b2[i]) < 128.0);  // fixed-apply ranges
    t.AtMost(std::fabs(b0[i]) + std::fabs(b1[i]) * d + std::fabs(b2[i]) * d * d,
             BiasLimit(kind, fs_sel), BiasBand(d, b1[i], b2[i]));
    t.AtMost(std::fabs(b1[i]) + 2.0 * std::fabs(b2[i]) * d, TempcoLimit(kind, fs_sel),
             TempcoBand(d, b2[i]));
  }
  const double det = m[0] * (m[4] * m[8] - m[5] * m[7]) - m[1] * (m[3] * m[8] - m[5] * m[6]) +
                     m[2] * (m[3] * m[7] - m[4] * m[6]);
  // Hadamard: rows moved by at most band_n change det by at most (R + band)^3 - R^3.
  const double band_det = std::pow(r_max + band_n, 3) - std::pow(r_max, 3);
  t.AtMost(-det, 0.0, band_det);  // det > 0; det = 0 lies within the band
  return t.Result();
}

bool Finite(const fwtest::Sensor& s) {
  bool ok =
      std::isfinite(s.t_ref_c) && std::isfinite(s.t_valid_min_c) && std::isfinite(s.t_valid_max_c);
  for (float v : s.m) ok = ok && std::isfinite(v);
  for (int i = 0; i < 3; ++i)
    ok = ok && std::isfinite(s.b0[i]) && std::isfinite(s.b1[i]) && std::isfinite(s.b2[i]);
  return ok;
}

int Decode(const fwtest::Sensor& s, metro_fw_sensor_kind kind, int fs_sel) {
  std::vector<uint8_t> body(4, 0);  // body_off 0 would mean "absent"
  const std::vector<uint8_t> section = fwtest::SensorBody(s);
  body.insert(body.end(), section.begin(), section.end());
  metro_fw_buffer buf{body.data(), static_cast<uint32_t>(body.size())};
  metro_fw_config cfg = fwtest::Config();
  cfg.accel_fs_sel = static_cast<uint8_t>(fs_sel);
  cfg.gyro_fs_sel = static_cast<uint8_t>(fs_sel);
  metro_fw_sensor_cal out{};
  metro_fw_blob_info info{};  // the section at offset 4 for either kind
  info.accel_off = info.gyro_off = 4;
  info.accel_len = info.gyro_len = 176;
  info.accel_version = info.gyro_version = METRO_FW_SEC_VERSION_1_0;
  REQUIRE(metro_fw_sensor_decode(metro_fw_buffer_read, &buf, &info, kind, &cfg, &out) ==
          METRO_FW_OK);
  // Whatever the status, the constants loaded (the section's or the defaults) convert to the
  // fixed-point formats of 3.2: 3.1 bounds |b1| < 2^15 and |b2| < 2^7.
  metro_fw_sensor_fixed fx;
  if (metro_fw_fixed_from_cal(&out, &fx) != METRO_FW_OK) {
    FAIL_CHECK("a loaded section does not convert to fixed point");
  }
  return out.status;
}

fwtest::Sensor Base(metro_fw_sensor_kind kind, int fs_sel) {
  fwtest::Sensor s = kind == METRO_FW_ACCEL ? fwtest::GoodAccel() : fwtest::GoodGyro();
  s.fs_sel = static_cast<uint8_t>(fs_sel);
  for (float& v : s.m) v *= static_cast<float>(1 << fs_sel);
  return s;
}

}  // namespace

TEST_CASE("Integer limit checks decide as the real-number rule outside the band",
          "[fw][blob][limits]") {
  std::mt19937 rng(20240611u);
  auto pick = [&](int n) { return static_cast<int>(rng() % static_cast<uint32_t>(n)); };
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  auto bands = [&]() { return 2.0 * unit(rng); };  // a position within +-2 bands of a limit
  const float inf = std::numeric_limits<float>::infinity();
  const std::vector<float> special = {std::numeric_limits<float>::quiet_NaN(),
                                      inf,
                                      -inf,
                                      0.0f,
                                      -0.0f,
                                      std::numeric_limits<float>::denorm_min(),
                                      -std::numeric_limits<float>::denorm_min(),
                                      std::nextafter(std::numeric_limits<float>::min(), 0.0f),
                                      std::numeric_limits<float>::min(),
                                      1e-30f,
                                      std::numeric_limits<float>::max(),
                                      -std::numeric_limits<float>::max(),
                                      3e19f,
                                      -1e10f,
                                      32768.0f,
                                      128.0f};
  int accepted = 0, rejected = 0, nonfinite = 0, skipped = 0;
  int outside_rejected[5] = {}, inside_accepted[5] = {};
  for (int iter = 0; iter < 60000; ++iter) {
    const metro_fw_sensor_kind kind = pick(2) == 0 ? METRO_FW_ACCEL : METRO_FW_GYRO;
    const int fs_sel = pick(4);
    fwtest::Sensor s = Base(kind, fs_sel);
    const uint8_t model[] = {0x0F, 0x01, 0x03, 0x07, 0x0D, 0x8F, 0x00};
    s.model_bits = model[pick(7)];
    const double sn = NominalSensitivity(kind, fs_sel);
    const double limit = BiasLimit(kind, fs_sel);
    const int row = pick(3);
    int family = -1;  // which limit the +-2 band construction targets
    switch (pick(10)) {
      case 0:  // a special value anywhere
        switch (pick(6)) {
          case 0:
            s.m[pick(9)] = special[pick(special.size())];
            break;
          case 1:
            s.b0[pick(3)] = special[pick(special.size())];
            break;
          case 2:
            s.b1[pick(3)] = special[pick(special.size())];
            break;
          case 3:
            s.b2[pick(3)] = special[pick(special.size())];
            break;
          case 4:
            s.t_ref_c = special[pick(special.size())];
            break;
          default:
            s.t_valid_min_c = special[pick(special.size())];
            break;
        }
        break;
      case 1: {  // a temperature limit +- 2 bands
        family = 0;
        const double ends[] = {-40.0, 85.0};
        float* t[] = {&s.t_ref_c, &s.t_valid_min_c, &s.t_valid_max_c};
        if (pick(3) == 0) {  // the narrowest range, 2 degC +- 2 bands
          s.t_valid_min_c = static_cast<float>(10.0 + 40.0 * unit(rng));
          s.t_valid_max_c =
              static_cast<float>(s.t_valid_min_c + kMinSpan_c + bands() * kTempStep_c);
        } else {
          const int e = pick(2);
          *t[pick(3)] = static_cast<float>(ends[e] + (e == 0 ? -1 : 1) * bands() * kTempBand_c);
        }
        break;
      }
      case 2:    // a row norm at 0.9 or 1.1 s_nom +- 2 bands, along an axis,
      case 3: {  // or in a random direction
        family = 1;
        const double n = (pick(2) == 0 ? 0.9 : 1.1) * sn + bands() * RowNormBand(kind, fs_sel);
        double v[3] = {0.0, 0.0, 0.0};
        v[row] = 1.0;
        if (pick(2) == 0) {
          for (double& x : v) x += 0.4 * unit(rng);
        }
        const double len = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
        for (int j = 0; j < 3; ++j) s.m[3 * row + j] = static_cast<float>(n * v[j] / len);
        s.model_bits |= 0x02;
        break;
      }
      case 4: {  // bias bound at the limit +- 2 bands
        family = 2;
        s.t_ref_c = static_cast<float>(25.0 + 20.0 * unit(rng));
        s.t_valid_min_c = static_cast<float>(-40.0 + 60.0 * std::fabs(unit(rng)));
        s.t_valid_max_c = static_cast<float>(85.0 - 60.0 * std::fabs(unit(rng)));
        const double d = std::max(std::fabs(double{s.t_valid_min_c} - s.t_ref_c),
                                  std::fabs(double{s.t_valid_max_c} - s.t_ref_c));
        s.b0 = {0.0f, 0.0f, 0.0f};
        s.b1 = {0.0f, 0.0f, 0.0f};
        s.b2 = {0.0f, 0.0f, 0.0f};
        // The temperature coefficient well inside its limit (at most 0.9 of it) and the
        // temperature terms at most 0.63 of the bias limit.
        const double tempco = std::min(TempcoLimit(kind, fs_sel), 0.9 * limit / d);
        s.b1[row] = static_cast<float>(unit(rng) * 0.5 * tempco);
        s.b2[row] = static_cast<float>(unit(rng) * 0.2 * tempco / d);
        const double rest = (std::fabs(s.b1[row]) + std::fabs(s.b2[row]) * d) * d;
        const double b0 = limit - rest + bands() * BiasBand(d, s.b1[row], s.b2[row]);
        s.b0[row] = static_cast<float>(pick(2) ? -b0 : b0);
        s.model_bits = 0x0F;
        break;
      }
      case 5: {  // det(M) near 0 with every row norm s_nom: rows x, y and (0, cos a, sin a)
        family = 3;
        const double r = 1.1 * sn + RowNormBand(kind, fs_sel);
        const double band_det = std::pow(r + RowNormBand(kind, fs_sel), 3) - std::pow(r, 3);
        const double z = bands() * band_det / (sn * sn * sn);
        s.m = {
            static_cast<float>(sn),    0.0f, 0.0f, 0.0f,
            static_cast<float>(sn),    0.0f, 0.0f, static_cast<float>(sn * std::sqrt(1.0 - z * z)),
            static_cast<float>(sn * z)};
        s.model_bits |= 0x02;
        break;
      }
      case 6: {  // the temperature coefficient |b1| + 2 |b2| D at its limit +- 2 bands
        family = 4;
        const double t_ref = 45.0 * std::fabs(unit(rng));
        const double below = 1.0 + 39.0 * std::fabs(unit(rng));
        const double above = 1.0 + 39.0 * std::fabs(unit(rng));
        s.t_ref_c = static_cast<float>(t_ref);
        s.t_valid_min_c = static_cast<float>(t_ref - below);
        s.t_valid_max_c = static_cast<float>(t_ref + above);
        const double d = std::max(std::fabs(double{s.t_valid_min_c} - s.t_ref_c),
                                  std::fabs(double{s.t_valid_max_c} - s.t_ref_c));
        // D <= 40 degC keeps the bias bound (<= 40 x limit x 2^-fs_sel) below the bias limit.
        const double share = std::fabs(unit(rng));  // of the coefficient carried by b1
        const double b2_mag = (1.0 - share) * TempcoLimit(kind, fs_sel) / (2.0 * d);
        s.b0 = {0.0f, 0.0f, 0.0f};
        s.b1 = {0.0f, 0.0f, 0.0f};
        s.b2 = {0.0f, 0.0f, 0.0f};
        s.b2[row] = static_cast<float>(pick(2) ? -b2_mag : b2_mag);
        const double b1_mag = TempcoLimit(kind, fs_sel) - 2.0 * std::fabs(s.b2[row]) * d +
                              bands() * TempcoBand(d, s.b2[row]);
        s.b1[row] = static_cast<float>(pick(2) ? -b1_mag : b1_mag);
        s.model_bits = 0x0F;
        break;
      }
      case 7: {  // subnormal, tiny or huge entries of M; negative scale; reflections
        switch (pick(4)) {
          case 0:
            s.m[pick(9)] = special[3 + pick(special.size() - 3)];
            break;
          case 1:
            for (float& v : s.m) v = -v;  // negative scale: det < 0
            break;
          case 2:
            for (int j = 0; j < 3; ++j) s.m[3 * row + j] = -s.m[3 * row + j];  // reflection
            break;
          default:  // two flipped rows: a rotation by pi, det > 0
            for (int j = 0; j < 6; ++j) s.m[(3 * row + j) % 9] = -s.m[(3 * row + j) % 9];
            break;
        }
        s.model_bits |= 0x02;
        break;
      }
      case 8: {  // random temperatures
        std::uniform_real_distribution<float> t(-45.0f, 90.0f);
        s.t_ref_c = t(rng);
        s.t_valid_min_c = t(rng);
        s.t_valid_max_c = t(rng);
        break;
      }
      default: {  // random sections: a random rotation, scale within +-12 %, random biases
        const double a = fwtest::kPi * unit(rng), b = fwtest::kPi * unit(rng);
        const double rot[9] = {std::cos(a),
                               -std::sin(a) * std::cos(b),
                               std::sin(a) * std::sin(b),
                               std::sin(a),
                               std::cos(a) * std::cos(b),
                               -std::cos(a) * std::sin(b),
                               0.0,
                               std::sin(b),
                               std::cos(b)};
        for (int i = 0; i < 3; ++i) {
          const double k = sn * (1.0 + 0.12 * unit(rng));
          for (int j = 0; j < 3; ++j) s.m[3 * i + j] = static_cast<float>(k * rot[3 * i + j]);
          s.b0[i] = static_cast<float>(limit * unit(rng));
          s.b1[i] = static_cast<float>(40.0 * unit(rng) / (1 << fs_sel));
          s.b2[i] = static_cast<float>(0.5 * unit(rng) / (1 << fs_sel));
        }
        s.model_bits |= 0x02;
        break;
      }
    }
    const int got = Decode(s, kind, fs_sel);
    if (!Finite(s)) {
      ++nonfinite;
      CHECK(got == METRO_FW_SENSOR_NONFINITE);
      continue;
    }
    const Real want = RealRule(s, kind, fs_sel);
    if (want == Real::kNear) {
      ++skipped;
      CHECK((got == METRO_FW_SENSOR_OK || got == METRO_FW_SENSOR_LIMITS));
      continue;
    }
    const int expected = want == Real::kAccept ? METRO_FW_SENSOR_OK : METRO_FW_SENSOR_LIMITS;
    if (want == Real::kAccept) ++accepted;
    if (want == Real::kReject) ++rejected;
    if (family >= 0 && got == expected) {
      (want == Real::kAccept ? inside_accepted : outside_rejected)[family] += 1;
    }
    if (got != expected) {
      INFO("iteration " << iter << " kind " << kind << " fs_sel " << fs_sel << " family "
                        << family);
      CHECK(got == expected);
    }
  }
  CHECK(accepted > 10000);
  CHECK(rejected > 10000);
  CHECK(nonfinite > 500);
  // Between 1 and 2 bands from each limit, both sides are decided as the real-number rule
  // (the loop checked each one), and each side occurs often.
  for (int f = 0; f < 5; ++f) {
    INFO("family " << f);
    CHECK(inside_accepted[f] > 300);
    CHECK(outside_rejected[f] > 300);
  }
  // The band is not vacuous: a few sections were within it.
  CHECK(skipped > 100);
}

TEST_CASE("Limit checks accept and reject just beyond the stated band", "[fw][blob][limits]") {
  for (int k = 0; k < 2; ++k) {
    const metro_fw_sensor_kind kind = k == 0 ? METRO_FW_ACCEL : METRO_FW_GYRO;
    for (int fs_sel = 0; fs_sel < 4; ++fs_sel) {
      const double sn = NominalSensitivity(kind, fs_sel);
      const double band_n = RowNormBand(kind, fs_sel);
      for (double side : {-1.0, 1.0}) {
        // Row 1 along y at 0.9 s_nom / 1.1 s_nom, moved 1.05 bands inwards or outwards.
        for (double end : {0.9, 1.1}) {
          fwtest::Sensor s = Base(kind, fs_sel);
          s.m = {static_cast<float>(sn), 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f,
                 static_cast<float>(sn)};
          const double out_dir = end > 1.0 ? 1.0 : -1.0;
          s.m[4] = static_cast<float>(end * sn + side * out_dir * 1.05 * band_n);
          s.model_bits = 0x0F;
          INFO("kind " << k << " fs_sel " << fs_sel << " row norm end " << end << " side " << side);
          CHECK(Decode(s, kind, fs_sel) ==
                (side > 0 ? METRO_FW_SENSOR_LIMITS : METRO_FW_SENSOR_OK));
        }
        // Bias bound: b0 = limit - (|b1| + |b2| D) D -+ 1.05 bands.
        {
          fwtest::Sensor s = Base(kind, fs_sel);
          const double d = 25.0;  // t_ref 25, valid 0 ... 50
          const double band = BiasBand(d, s.b1[2], s.b2[2]);
          const double rest = (std::fabs(s.b1[2]) + std::fabs(s.b2[2]) * d) * d;
          s.b0[2] = static_cast<float>(BiasLimit(kind, fs_sel) - rest + side * 1.05 * band);
          INFO("kind " << k << " fs_sel " << fs_sel << " bias side " << side);
          CHECK(Decode(s, kind, fs_sel) ==
                (side > 0 ? METRO_FW_SENSOR_LIMITS : METRO_FW_SENSOR_OK));
        }
        // Temperatures: t_valid_max_c at 85 +- 1.05 bands, t_valid_min_c at -40 -+ 1.05 bands.
        {
          fwtest::Sensor s = Base(kind, fs_sel);
          s.t_valid_max_c = static_cast<float>(85.0 + side * 1.05 * kTempBand_c);
          s.t_valid_min_c = static_cast<float>(-40.0 - side * 1.05 * kTempBand_c);
          s.b1 = {0.0f, 0.0f, 0.0f};
          s.b2 = {0.0f, 0.0f, 0.0f};
          INFO("kind " << k << " fs_sel " << fs_sel << " temperature side " << side);
          CHECK(Decode(s, kind, fs_sel) ==
                (side > 0 ? METRO_FW_SENSOR_LIMITS : METRO_FW_SENSOR_OK));
        }
        // The narrowest validity range: 2 degC -+ 1.05 bands (2^-12 degC).
        {
          fwtest::Sensor s = Base(kind, fs_sel);
          s.t_valid_min_c = 24.0f;
          s.t_valid_max_c = static_cast<float>(24.0 + kMinSpan_c - side * 1.05 * kTempStep_c);
          INFO("kind " << k << " fs_sel " << fs_sel << " span side " << side);
          CHECK(Decode(s, kind, fs_sel) ==
                (side > 0 ? METRO_FW_SENSOR_LIMITS : METRO_FW_SENSOR_OK));
        }
        // Temperature coefficient: |b1| + 2 |b2| D at the limit +- 1.05 bands, D = 25 degC.
        for (double b2 : {0.0, 0.03125}) {
          fwtest::Sensor s = Base(kind, fs_sel);
          const double d = 25.0;  // t_ref 25, valid 0 ... 50
          s.b2 = {0.0f, static_cast<float>(-b2), 0.0f};
          s.b1 = {0.0f,
                  static_cast<float>(TempcoLimit(kind, fs_sel) - 2.0 * b2 * d +
                                     side * 1.05 * TempcoBand(d, b2)),
                  0.0f};
          s.b0 = {0.0f, 0.0f, 0.0f};
          INFO("kind " << k << " fs_sel " << fs_sel << " tempco side " << side << " b2 " << b2);
          CHECK(Decode(s, kind, fs_sel) ==
                (side > 0 ? METRO_FW_SENSOR_LIMITS : METRO_FW_SENSOR_OK));
        }
      }
    }
  }
}

TEST_CASE("The defaults' nominal sensitivity doubles exactly per fs_sel", "[fw][blob]") {
  for (int fs = 0; fs < 4; ++fs) {
    const double s[2] = {9.80665 / (16384 >> fs),
                         (250 << fs) / 32768.0 * 3.14159265358979323846 / 180.0};
    for (int k = 0; k < 2; ++k) {
      metro_fw_sensor_cal d{};
      REQUIRE(metro_fw_sensor_defaults(static_cast<metro_fw_sensor_kind>(k),
                                       static_cast<uint8_t>(fs), &d) == METRO_FW_OK);
      for (int i = 0; i < 9; ++i) CHECK(d.m[i] == (i % 4 == 0 ? static_cast<float>(s[k]) : 0.0f));
    }
  }
}
