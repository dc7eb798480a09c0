// EvaluateSessionTypeA: settle per quantity or per tag, temperature never cuts the others,
// and the gimbal-lock warnings of yaw and roll.
#include "metro/stats/session_type_a.hpp"

#include <fmt/format.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "metro/core/angles.hpp"
#include "metro/io/session_io.hpp"
#include "support/temp_file.hpp"

namespace metro {
namespace {

bool AnyContains(const std::vector<std::string>& lines, const std::string& text) {
  for (const std::string& l : lines) {
    if (l.find(text) != std::string::npos) return true;
  }
  return false;
}

const QuantityTypeA& Find(const TagTypeA& t, const std::string& name) {
  for (const QuantityTypeA& q : t.quantities) {
    if (q.name == name) return q;
  }
  FAIL("no quantity " << name);
  return t.quantities.front();
}

// One tag at 10 Hz for 600 s (n = 6000): gx_dps with a transient of 20 sigma and tau 5 s,
// ax_g stationary, temp_c warming by 5 degC with a 600 s time constant (the simulator's),
// all with white noise of sigma 1 (temp 0.01).
Session WarmUpSession() {
  Session s;
  s.path = "warm_up";
  Tag tag;
  tag.sensor = 4;
  const size_t n = 6000;
  std::mt19937_64 rng(7);
  std::normal_distribution<double> w(0.0, 1.0);
  Quantity gx{"gx_dps", "deg/s", QuantityOrigin::kFile, {}};
  Quantity ax{"ax_g", "g", QuantityOrigin::kFile, {}};
  Quantity temp{"temp_c", "degC", QuantityOrigin::kFile, {}};
  for (size_t i = 0; i < n; ++i) {
    const double t_s = 0.1 * static_cast<double>(i);
    tag.t_s.push_back(t_s);
    tag.line.push_back(static_cast<uint32_t>(i + 2));
    gx.values.push_back(20.0 * std::exp(-t_s / 5.0) + w(rng));
    ax.values.push_back(w(rng));
    temp.values.push_back(30.0 - 5.0 * std::exp(-t_s / 600.0) + 0.01 * w(rng));
  }
  tag.quantities = {gx, ax, temp};
  s.tags.push_back(std::move(tag));
  return s;
}

TEST_CASE("Settle per quantity: each from its own cut, temperature cuts no other",
          "[stats][settle]") {
  const Session session = WarmUpSession();
  SessionTypeAOptions o;
  o.window.settle_auto = true;
  auto r = EvaluateSessionTypeA(session, o);
  REQUIRE(r.ok());
  const TagTypeA& t = r.value().tags.at(0);
  const QuantityTypeA& gx = Find(t, "gx_dps");
  const QuantityTypeA& ax = Find(t, "ax_g");
  const QuantityTypeA& temp = Find(t, "temp_c");
  // gx: b(d) = 0.1 u(d) with A = 20, tau = 50 samples, u(d) = 1 / sqrt(6000 - d) at about
  // d = 50 ln(20 * 50 / (0.1 sqrt(6000 - d))) = 50 ln(130) = 243 samples (fitted: +-15 %).
  CHECK(double(gx.settle_samples) == Approx(243).epsilon(0.15));
  CHECK(gx.window_begin == gx.settle_samples);
  CHECK(gx.type_a.n == int64_t(6000 - gx.settle_samples));
  // ax: stationary, nothing dropped.
  CHECK(ax.settle_samples == 0);
  CHECK(ax.type_a.n == 6000);
  // temp: a warm-up of tau 600 s in a 600 s record cannot settle: cut at the half-window
  // limit, with a warning naming temp_c.
  CHECK(temp.settle.at_limit);
  CHECK(temp.settle_samples == 3000);
  CHECK(AnyContains(temp.warnings, "--settle auto: temp_c: start-up transient"));
  CHECK(AnyContains(temp.warnings, "did not decay within the first half"));
  // The tag window takes the largest non-temperature cut: gx's, named.
  CHECK(t.window.settle_samples == gx.settle_samples);
  CHECK(t.window.settle_driver == "gx_dps");
  CHECK_FALSE(t.window.settle_at_limit);
  CHECK_FALSE(AnyContains(t.warnings, "temp_c"));
}

TEST_CASE("Settle tag-wide on request: every quantity from the driver's cut", "[stats][settle]") {
  const Session session = WarmUpSession();
  SessionTypeAOptions o;
  o.window.settle_auto = true;
  o.window.settle_tag_wide = true;
  auto r = EvaluateSessionTypeA(session, o);
  REQUIRE(r.ok());
  const TagTypeA& t = r.value().tags.at(0);
  const size_t cut = Find(t, "gx_dps").settle_samples;
  for (const QuantityTypeA& q : t.quantities) {
    CHECK(q.window_begin == cut);
    CHECK(q.type_a.n == int64_t(6000 - cut));
  }
  CHECK(AnyContains(t.warnings, "--settle-scope tag: every quantity of the tag cut at " +
                                    std::to_string(cut) + " samples, the cut of gx_dps"));
  SessionTypeAOptions bad;
  bad.window.settle_tag_wide = true;
  std::string why;
  CHECK_FALSE(bad.IsValid(&why));
  CHECK(why == "a tag-wide settle cut (--settle-scope tag) needs --settle auto");
}

TEST_CASE("Yaw and roll near gimbal lock carry their own warning", "[stats]") {
  // Pitch 89.9 deg: yaw and roll alone are ill-defined (only yaw - roll is); the warning
  // must reach both, not only pitch.
  Session s;
  s.path = "gimbal";
  Tag tag;
  tag.sensor = 1;
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> any(-180.0, 180.0);
  std::normal_distribution<double> noise;
  Quantity yaw{"yaw_deg", "deg", QuantityOrigin::kDerived, {}};
  Quantity pitch{"pitch_deg", "deg", QuantityOrigin::kDerived, {}};
  Quantity roll{"roll_deg", "deg", QuantityOrigin::kDerived, {}};
  Quantity gx{"gx_dps", "deg/s", QuantityOrigin::kFile, {}};
  for (int i = 0; i < 200; ++i) {
    tag.t_s.push_back(0.1 * i);
    tag.line.push_back(static_cast<uint32_t>(i + 2));
    const double a = any(rng);
    yaw.values.push_back(a);
    roll.values.push_back(a - 30.0 > -180.0 ? a - 30.0 : a + 330.0);
    pitch.values.push_back(89.9);
    gx.values.push_back(0.01 * noise(rng));  // white noise: no warning of its own
  }
  tag.quantities = {yaw, pitch, roll, gx};
  s.tags.push_back(std::move(tag));
  auto r = EvaluateSessionTypeA(s, {});
  REQUIRE(r.ok());
  const TagTypeA& t = r.value().tags.at(0);
  CHECK(AnyContains(Find(t, "yaw_deg").warnings,
                    "yaw_deg (derived from the quaternion): |pitch_deg| reaches 89.90 deg"));
  CHECK(AnyContains(Find(t, "roll_deg").warnings,
                    "roll_deg (derived from the quaternion): |pitch_deg| reaches 89.90 deg"));
  CHECK(AnyContains(Find(t, "pitch_deg").warnings, "|pitch| reaches 89.90 deg"));
  CHECK(Find(t, "gx_dps").warnings.empty());
}

TEST_CASE("Quaternions at pitch 89.9 deg: derived yaw and roll are warned about", "[stats]") {
  // A tag at pitch 89.9 deg whose attitude jitters by 0.05 deg: the derived roll and yaw
  // swing by tens of degrees (only yaw - roll is defined near the lock); each says so.
  std::mt19937_64 rng(21);
  std::normal_distribution<double> jitter(0.0, 0.05);
  std::string csv = "t_s,sensor,qw,qx,qy,qz\n";
  for (int i = 0; i < 300; ++i) {
    EulerDeg e;
    e.yaw_deg = 30.0 + jitter(rng);
    e.pitch_deg = 89.9 + jitter(rng);
    e.roll_deg = 10.0 + jitter(rng);
    const Quaternion q = QuaternionFromEuler(e);
    csv += fmt::format("{:.1f},5,{:.9f},{:.9f},{:.9f},{:.9f}\n", 0.1 * i, q.w, q.x, q.y, q.z);
  }
  testing::TempFile file(csv, ".csv");
  auto session = LoadSession(file.path());
  REQUIRE(session.ok());
  auto r = EvaluateSessionTypeA(session.value(), {});
  REQUIRE(r.ok());
  const TagTypeA& t = r.value().tags.at(0);
  for (const char* name : {"yaw_deg", "roll_deg"}) {
    INFO(name);
    CHECK(Find(t, name).origin == QuantityOrigin::kDerived);
    CHECK(AnyContains(Find(t, name).warnings,
                      std::string(name) + " (derived from the quaternion): |pitch_deg| reaches"));
  }
}

}  // namespace
}  // namespace metro

namespace metro {
namespace {

TEST_CASE("A session window that hides the noise gets Willink's digitized u",
          "[stats][type_a][digitized]") {
  // temp_c printed to 0.01 degC: noisy for the first 100 readings (the step shows on the
  // whole record), then 30.00 for 50 readings, then 30.00/30.01 alternating 3:1 for 40.
  Session s;
  s.path = "digitized";
  Tag tag;
  tag.sensor = 2;
  std::mt19937_64 rng(11);
  std::normal_distribution<double> w(0.0, 0.05);
  Quantity temp{"temp_c", "degC", QuantityOrigin::kFile, {}};
  for (size_t i = 0; i < 190; ++i) {
    tag.t_s.push_back(static_cast<double>(i));
    tag.line.push_back(static_cast<uint32_t>(i + 2));
    double v = 30.0;
    if (i < 100) v = std::round((30.0 + w(rng)) * 100.0) / 100.0;
    if (i >= 150 && i % 4 == 3) v = 30.01;
    temp.values.push_back(v);
  }
  tag.quantities = {temp};
  s.tags.push_back(std::move(tag));
  const auto evaluate = [&](double from_s, double to_s) {
    SessionTypeAOptions o;
    o.window.from_s = from_s;
    o.window.to_s = to_s;
    auto r = EvaluateSessionTypeA(s, o);
    if (!r.ok()) FAIL(r.error().ToString());
    return Find(r.value().tags[0], "temp_c");
  };
  // All equal over 50 readings: u = 0.01 / sqrt(12), 49 dof, said in a warning.
  const QuantityTypeA flat = evaluate(100.0, 149.0);
  REQUIRE(flat.ok);
  CHECK(flat.type_a.n == 50);
  CHECK(flat.type_a.u_mean_available);
  CHECK(flat.type_a.u_mean_method == std::string(kUMeanDigitized));
  CHECK(flat.type_a.u_mean == Approx(0.01 / std::sqrt(12.0)).epsilon(1e-9));
  CHECK(flat.type_a.u_mean_dof == 49.0);
  CHECK(AnyContains(flat.warnings, "Willink"));
  // Three readings: c = 1.3.
  const QuantityTypeA three = evaluate(120.0, 122.0);
  CHECK(three.type_a.u_mean == Approx(std::sqrt(1.3 / 12.0) * 0.01).epsilon(1e-9));
  // One step, 30 of 30.00 and 10 of 30.01: u >= |x_mid - mean| / sqrt(3) = 0.0025 / sqrt(3).
  const QuantityTypeA step = evaluate(150.0, 189.0);
  CHECK(step.type_a.n == 40);
  CHECK(step.type_a.u_mean >= 0.0025 / std::sqrt(3.0) * (1.0 - 1e-9));
  // The noisy part is not touched: its u is what it was without any step.
  const QuantityTypeA noisy = evaluate(0.0, 99.0);
  CHECK(noisy.type_a.u_mean_method != std::string(kUMeanDigitized));
  const std::vector<double> head(s.tags[0].quantities[0].values.begin(),
                                 s.tags[0].quantities[0].values.begin() + 100);
  auto plain = EvaluateTypeA(head.data(), head.size());
  REQUIRE(plain.ok());
  CHECK(noisy.type_a.u_mean == plain.value().u_mean);
}

}  // namespace
}  // namespace metro
