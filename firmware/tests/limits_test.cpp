// The integer-only section 3.1 limit checks (metro_fw_sensor_decode) against the float
// evaluation they replace: the same accept/reject decision on constructed values (NaN, +-Inf,
// +-0, subnormals, FLT_MAX, every limit +-1 and a few ulp) and random sections.
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "metro_fw/blob.h"
#include "test_support.hpp"

namespace {

// The float decision as metro_fw_sensor_decode computed it before issue #6 (binary32 steps).
bool FloatWithinLimits(const fwtest::Sensor& in, metro_fw_sensor_kind kind, int fs_sel) {
  const uint8_t bits = in.model_bits;
  float m[9], b0[3], b1[3], b2[3];
  for (int i = 0; i < 9; ++i) m[i] = (i % 4 == 0 || (bits & 0x02)) ? in.m[i] : 0.0f;
  for (int i = 0; i < 3; ++i) {
    b0[i] = (bits & 0x01) ? in.b0[i] : 0.0f;
    b1[i] = (bits & 0x04) ? in.b1[i] : 0.0f;
    b2[i] = (bits & 0x08) ? in.b2[i] : 0.0f;
  }
  const float s =
      (kind == METRO_FW_ACCEL ? 5.98550415e-4f : 1.33158055e-4f) * static_cast<float>(1 << fs_sel);
  const float bias_limit = static_cast<float>((kind == METRO_FW_ACCEL ? 4096 : 7864) >> fs_sel);
  auto in_range = [](float x, float lo, float hi) { return x >= lo && x <= hi; };
  if (!in_range(in.t_ref_c, -40.0f, 85.0f) || !in_range(in.t_valid_min_c, -40.0f, 85.0f) ||
      !in_range(in.t_valid_max_c, -40.0f, 85.0f) || !(in.t_valid_min_c < in.t_valid_max_c)) {
    return false;
  }
  float d_max = std::fabs(in.t_valid_min_c - in.t_ref_c);
  const float d_hi = std::fabs(in.t_valid_max_c - in.t_ref_c);
  if (d_hi > d_max) d_max = d_hi;
  float det = 0.0f;
  for (int i = 0; i < 3; ++i) {
    const int k1 = (i + 1) % 3, k2 = (i + 2) % 3;
    float n2 = 0.0f;
    for (int j = 0; j < 3; ++j) n2 += m[3 * i + j] * m[3 * i + j];
    const float lo = 0.81f * s * s, hi = 1.21f * s * s;
    if (!in_range(n2, lo, hi)) return false;
    det += m[i] * (m[3 + k1] * m[6 + k2] - m[3 + k2] * m[6 + k1]);
    if (!(std::fabs(b0[i]) + (std::fabs(b1[i]) + std::fabs(b2[i]) * d_max) * d_max <= bias_limit)) {
      return false;
    }
  }
  return det > 0.0f;
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
  REQUIRE(metro_fw_sensor_decode(metro_fw_buffer_read, &buf, 4, 176, METRO_FW_SEC_VERSION_1_0, kind,
                                 &cfg, &out) == METRO_FW_OK);
  return out.status;
}

float Ulps(float x, int n) {
  const float dir =
      n > 0 ? std::numeric_limits<float>::infinity() : -std::numeric_limits<float>::infinity();
  for (int k = 0; k < std::abs(n); ++k) x = std::nextafter(x, dir);
  return x;
}

}  // namespace

TEST_CASE("Integer limit checks decide as the float evaluation did", "[fw][blob][limits]") {
  std::mt19937 rng(20240611u);
  auto pick = [&](int n) { return static_cast<int>(rng() % static_cast<uint32_t>(n)); };
  auto ulp = [&]() { return pick(9) - 4; };
  const float inf = std::numeric_limits<float>::infinity();
  const std::vector<float> special = {std::numeric_limits<float>::quiet_NaN(),
                                      inf,
                                      -inf,
                                      0.0f,
                                      -0.0f,
                                      std::numeric_limits<float>::denorm_min(),
                                      -std::numeric_limits<float>::denorm_min(),
                                      Ulps(std::numeric_limits<float>::min(), -1),
                                      std::numeric_limits<float>::min(),
                                      1e-30f,
                                      std::numeric_limits<float>::max(),
                                      -std::numeric_limits<float>::max(),
                                      3e19f,
                                      1e10f};
  int accepted = 0, limits = 0, nonfinite = 0, near_accept = 0, near_reject = 0;
  for (int iter = 0; iter < 60000; ++iter) {
    const metro_fw_sensor_kind kind = pick(2) == 0 ? METRO_FW_ACCEL : METRO_FW_GYRO;
    const int fs_sel = pick(4);
    fwtest::Sensor s = kind == METRO_FW_ACCEL ? fwtest::GoodAccel() : fwtest::GoodGyro();
    s.fs_sel = static_cast<uint8_t>(fs_sel);
    const uint8_t model[] = {0x0F, 0x01, 0x03, 0x07, 0x0D, 0x8F, 0x00};
    s.model_bits = model[pick(7)];
    const float sn = (kind == METRO_FW_ACCEL ? 5.98550415e-4f : 1.33158055e-4f) *
                     static_cast<float>(1 << fs_sel);
    for (float& v : s.m) v *= static_cast<float>(1 << fs_sel);
    const float limit = static_cast<float>((kind == METRO_FW_ACCEL ? 4096 : 7864) >> fs_sel);
    const int row = pick(3);
    bool near = false;
    switch (pick(9)) {
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
      case 1: {  // temperatures at the limits +- ulps
        const float ends[] = {-40.0f, 85.0f};
        float* t[] = {&s.t_ref_c, &s.t_valid_min_c, &s.t_valid_max_c};
        *t[pick(3)] = Ulps(ends[pick(2)], ulp());
        if (pick(2) == 0) s.t_valid_max_c = Ulps(s.t_valid_min_c, pick(3) - 1);
        near = true;
        break;
      }
      case 2:    // a diagonal row at 0.9 or 1.1 s_nom +- ulps
      case 3: {  // or a rotated row with the same norm
        const float k = pick(2) == 0 ? std::sqrt(0.81f) : std::sqrt(1.21f);
        for (int j = 0; j < 3; ++j) s.m[3 * row + j] = 0.0f;
        if (pick(2) == 0) {
          s.m[4 * row] = Ulps(k * sn, ulp());
        } else {
          s.m[3 * row + (row + 1) % 3] = Ulps(k * sn * 0.6f, ulp());
          s.m[4 * row] = Ulps(k * sn * 0.8f, ulp());
        }
        s.model_bits |= 0x02;
        near = true;
        break;
      }
      case 4: {  // bias bound at the limit +- ulps
        const float d = std::max(std::fabs(s.t_valid_min_c - s.t_ref_c),
                                 std::fabs(s.t_valid_max_c - s.t_ref_c));
        s.b1[row] = (pick(2) ? -1.0f : 1.0f) * static_cast<float>(pick(40)) / 8.0f;
        s.b2[row] = (pick(2) ? -1.0f : 1.0f) * static_cast<float>(pick(5)) / 64.0f;
        const float rest = (std::fabs(s.b1[row]) + std::fabs(s.b2[row]) * d) * d;
        s.b0[row] = (pick(2) ? -1.0f : 1.0f) * Ulps(limit - rest, ulp());
        s.model_bits = 0x0F;
        near = true;
        break;
      }
      case 5:  // subnormal and tiny entries of M, reflections
        s.m[pick(9)] = special[5 + pick(5)];
        if (pick(2) == 0)
          for (int j = 0; j < 3; ++j) s.m[3 * row + j] = -s.m[3 * row + j];
        break;
      case 6: {  // random temperatures
        std::uniform_real_distribution<float> t(-45.0f, 90.0f);
        s.t_ref_c = t(rng);
        s.t_valid_min_c = t(rng);
        s.t_valid_max_c = t(rng);
        break;
      }
      default: {  // random scale and bias
        std::uniform_real_distribution<float> u(-1.0f, 1.0f);
        for (float& v : s.m) v *= 1.0f + 0.12f * u(rng);
        for (int i = 0; i < 3; ++i) {
          s.b0[i] = limit * u(rng);
          s.b1[i] = 50.0f * u(rng);
          s.b2[i] = u(rng);
        }
        break;
      }
    }
    int expected;
    if (!Finite(s)) {
      expected = METRO_FW_SENSOR_NONFINITE;
      ++nonfinite;
    } else if (FloatWithinLimits(s, kind, fs_sel)) {
      expected = METRO_FW_SENSOR_OK;
      ++accepted;
      near_accept += near ? 1 : 0;
    } else {
      expected = METRO_FW_SENSOR_LIMITS;
      ++limits;
      near_reject += near ? 1 : 0;
    }
    const int got = Decode(s, kind, fs_sel);
    if (got != expected) {
      INFO("iteration " << iter << " kind " << kind << " fs_sel " << fs_sel);
      CHECK(got == expected);
    }
  }
  // Both decisions occur, also among the values within a few ulp of a limit.
  CHECK(accepted > 5000);
  CHECK(limits > 5000);
  CHECK(nonfinite > 500);
  CHECK(near_accept > 2000);
  CHECK(near_reject > 2000);
}

TEST_CASE("Nominal sensitivity doubles exactly per fs_sel", "[fw][blob]") {
  for (int fs = 0; fs < 4; ++fs) {
    CHECK(metro_fw_nominal_sensitivity(METRO_FW_ACCEL, static_cast<uint8_t>(fs)) ==
          static_cast<float>(9.80665 / (16384 >> fs)));
    CHECK(metro_fw_nominal_sensitivity(METRO_FW_GYRO, static_cast<uint8_t>(fs)) ==
          static_cast<float>((250 << fs) / 32768.0 * 3.14159265358979323846 / 180.0));
  }
}
