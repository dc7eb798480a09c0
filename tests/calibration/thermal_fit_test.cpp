// FitThermalBias over simulated thermal sessions with known truth (issue #42, docs/thermal.md).
// Per axis case: the held-out-temperature bias error within 2u, the chosen order equal to the
// truth's, and the residual RMS against a fixed order-3 offset-only least-squares fit on the
// samples (PX4 / ArduPilot's method), computed here from the samples.
#include "metro/calibration/thermal_fit.hpp"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <boost/math/distributions/binomial.hpp>
#include <catch2/catch.hpp>
#include <cmath>
#include <map>
#include <random>

#include "metro/sim/thermal_session.hpp"

namespace metro {
namespace {

struct Tally {
  int cases = 0;
  int within_2u = 0;
  int order_right = 0;
  int rms_cases = 0;
  int rms_at_or_below_px4 = 0;
  double worst_rms_ratio = 0;
  int truth_error_at_or_below_px4 = 0;  // RMS of (fit - truth) over the bins.
};

// Order-3 least squares on every sample (time-weighted, PX4's TemperatureCalibration and
// ArduPilot's), as a function of T.
struct Px4Fit {
  Eigen::Vector4d c;  // Of z = (T - t_ref_c) / 20.
  double t_ref_c = 0;
  double At(double temp_c) const {
    const double z = (temp_c - t_ref_c) / 20.0;
    return c[0] + z * (c[1] + z * (c[2] + z * c[3]));
  }
};

Px4Fit FitPx4(const ThermalSamples& s, int axis, double t_ref_c) {
  Eigen::MatrixXd x(static_cast<Eigen::Index>(s.temp_c.size()), 4);
  for (Eigen::Index i = 0; i < x.rows(); ++i) {
    for (int j = 0; j < 4; ++j)
      x(i, j) = std::pow((s.temp_c[static_cast<size_t>(i)] - t_ref_c) / 20.0, j);
  }
  Px4Fit f;
  f.t_ref_c = t_ref_c;
  f.c = x.colPivHouseholderQr().solve(
      Eigen::Map<const Eigen::VectorXd>(s.values[axis].data(), x.rows()));
  return f;
}

// The bin means the fit uses, recomputed here the plain way (one leg; bins of 0.5 degC with
// >= 10 samples), for the PX4 comparison.
void BinMeansForTest(const ThermalSamples& s, const std::vector<bool>& use, int axis,
                     std::vector<double>* bt, std::vector<double>* bm) {
  std::map<long, std::array<double, 3>> sums;
  for (size_t i = 0; i < s.temp_c.size(); ++i) {
    if (!use[i]) continue;
    auto& a = sums[std::lround(std::floor(s.temp_c[i] / 0.5))];
    a[0] += s.temp_c[i];
    a[1] += s.values[axis][i];
    a[2] += 1;
  }
  for (const auto& [k, a] : sums) {
    if (a[2] < 10) continue;
    bt->push_back(a[0] / a[2]);
    bm->push_back(a[1] / a[2]);
  }
}

void RunCase(const ThermalSimulationOptions& o, Tally* tally) {
  auto sim = SimulateThermalSession(o);
  REQUIRE(sim.ok());
  const Tag& tag = sim.value().session.tags.front();
  const ThermalTruth& truth = sim.value().truth;
  std::mt19937_64 rng(o.seed * 7919u + 17u);
  const double span = o.temp_high_c - o.temp_low_c;
  const double held_c = std::uniform_real_distribution<double>(o.temp_low_c + 0.25 * span,
                                                               o.temp_high_c - 0.25 * span)(rng);
  for (ImuSensor sensor : {ImuSensor::kAccel, ImuSensor::kGyro}) {
    auto all = ThermalSamplesFromTag(tag, sensor, "sim.csv");
    REQUIRE(all.ok());
    // Hold out 2 degC about held_c: the fit never sees that temperature.
    ThermalSamples s = all.value();
    std::vector<bool> use(s.temp_c.size());
    for (size_t i = 0; i < use.size(); ++i) use[i] = std::abs(s.temp_c[i] - held_c) > 1.0;
    ThermalSamples fit_in;
    fit_in.what = s.what;
    for (size_t i = 0; i < use.size(); ++i) {
      if (!use[i]) continue;
      fit_in.temp_c.push_back(s.temp_c[i]);
      fit_in.lines.push_back(s.lines[i]);
      for (int a = 0; a < 3; ++a) fit_in.values[a].push_back(s.values[a][i]);
    }
    auto fit = FitThermalBias(fit_in, ThermalFitOptions{}, truth.t_ref_c);
    REQUIRE(fit.ok());
    const ThermalSensorTruth& st = sensor == ImuSensor::kAccel ? truth.accel : truth.gyro;
    for (int a = 0; a < 3; ++a) {
      const ThermalAxisFit& f = fit.value().axes[a];
      const double err = f.BiasAt(held_c, truth.t_ref_c) - st.BiasAt(a, held_c, truth.t_ref_c, 0);
      ++tally->cases;
      tally->within_2u += std::abs(err) <= 2.0 * f.UBiasAt(held_c, truth.t_ref_c) ? 1 : 0;
      tally->order_right += f.order == truth.order ? 1 : 0;
      if (!fit.value().legs) {
        std::vector<double> bt, bm;
        BinMeansForTest(fit_in, std::vector<bool>(fit_in.temp_c.size(), true), a, &bt, &bm);
        const Px4Fit px4 = FitPx4(fit_in, a, truth.t_ref_c);
        double ss_px4 = 0, ss_err = 0, ss_err_px4 = 0;
        for (size_t k = 0; k < bt.size(); ++k) {
          ss_px4 += std::pow(bm[k] - px4.At(bt[k]), 2);
          const double b_true = st.BiasAt(a, bt[k], truth.t_ref_c, 0);
          ss_err += std::pow(f.BiasAt(bt[k], truth.t_ref_c) - b_true, 2);
          ss_err_px4 += std::pow(px4.At(bt[k]) - b_true, 2);
        }
        const double px4_rms = std::sqrt(ss_px4 / static_cast<double>(bt.size()));
        ++tally->rms_cases;
        tally->rms_at_or_below_px4 += f.residual_rms <= px4_rms ? 1 : 0;
        tally->worst_rms_ratio = std::max(tally->worst_rms_ratio, f.residual_rms / px4_rms);
        tally->truth_error_at_or_below_px4 += ss_err <= ss_err_px4 ? 1 : 0;
      }
    }
  }
}

Tally RunCases(ThermalSimulationOptions o, int tags, uint64_t first_seed) {
  Tally t;
  for (int k = 0; k < tags; ++k) {
    o.seed = first_seed + static_cast<uint64_t>(k);
    RunCase(o, &t);
  }
  return t;
}

// k of n successes is consistent with probability p: inside the central 99.8 % of Binomial(n, p).
bool Consistent(int k, int n, double p) {
  const boost::math::binomial_distribution<double> b(n, p);
  return k >= boost::math::quantile(b, 0.001) && k <= boost::math::quantile(b, 0.999);
}

void Report(const std::string& name, const Tally& t) {
  WARN(fmt::format(
      "{}: {} axis cases; within 2u {:.1f} %, order right {:.1f} %; of {} one-leg "
      "cases residual RMS <= order-3 (PX4) in {} (worst ratio {:.3f}), error "
      "against the truth <= order-3's in {}",
      name, t.cases, 100.0 * t.within_2u / t.cases, 100.0 * t.order_right / t.cases, t.rms_cases,
      t.rms_at_or_below_px4, t.worst_rms_ratio, t.truth_error_at_or_below_px4));
}

ThermalSimulationOptions Case(int order, ThermalProfile profile, bool cooling, bool hysteresis) {
  ThermalSimulationOptions o;
  o.bias_order = order;
  o.profile = profile;
  o.cooling_leg = cooling;
  if (hysteresis) {
    o.accel_hysteresis_g = 0.005;
    o.gyro_hysteresis_dps = 0.2;
  }
  return o;
}

// About 95 % within 2u (k = 2, JCGM 100:2008 6.3.3) and >= 90 % right orders. CI-sized runs:
// the count inside the central 99.8 % of Binomial(n, 0.9545). 100-tag runs: the issue's
// acceptance, 95 +- 3 % (the binomial band of 600 cases is +-2.6 points, and the uniform bin
// weighting under-covers by 1-3 points where bin counts differ most, docs/thermal.md).
void CheckCoverage(const Tally& t, bool issue_band = false) {
  if (issue_band) {
    CHECK(t.within_2u >= 0.92 * t.cases);
    CHECK(t.within_2u <= 0.98 * t.cases);
  } else {
    CHECK(Consistent(t.within_2u, t.cases, 0.9545));
  }
  const boost::math::binomial_distribution<double> b(t.cases, 0.90);
  CHECK(t.order_right >= boost::math::quantile(b, 0.001));
}

TEST_CASE("thermal fit: orders 1..4 on a ramp, CI-sized, binomial bounds", "[thermal]") {
  for (int order = 1; order <= 4; ++order) {
    const Tally t = RunCases(Case(order, ThermalProfile::kRamp, false, false), 10, 100 * order);
    Report(fmt::format("ramp order {}", order), t);
    CheckCoverage(t);
    if (order == 4) {
      // A fourth-order term far above the noise: a fixed order-3 fit (PX4, ArduPilot) leaves it
      // in its residuals and its error; the chosen order does not.
      CHECK(t.rms_at_or_below_px4 == t.rms_cases);
      CHECK(t.truth_error_at_or_below_px4 == t.rms_cases);
    }
  }
}

TEST_CASE("thermal fit: 100 tags per case, ramp and steps, with and without hysteresis",
          "[thermal][slow]") {
  for (ThermalProfile profile : {ThermalProfile::kRamp, ThermalProfile::kSteps}) {
    for (int h = 0; h < 3; ++h) {
      for (int order = 1; order <= 4; ++order) {
        const Tally t = RunCases(Case(order, profile, h > 0, h == 2), 100, 1000 * order + 7);
        Report(fmt::format("{} order {} {}", ThermalProfileName(profile), order,
                           h == 0   ? "heating only"
                           : h == 1 ? "heating+cooling, no hysteresis"
                                    : "heating+cooling, hysteresis"),
               t);
        CheckCoverage(t, true);
      }
    }
  }
}

// A power-on warm-up of 23 degC: with the 2 degC held out, the span still allows order 4
// (5 degC per order).
ThermalSimulationOptions Warmup(int order) {
  ThermalSimulationOptions o = Case(order, ThermalProfile::kWarmup, false, false);
  o.temp_low_c = 25.0;
  o.temp_high_c = 48.0;
  o.warmup_tau_s = 600.0;
  o.warmup_s = 3600.0;
  return o;
}

TEST_CASE("thermal fit: a power-on warm-up 25 -> 48 degC (CI-sized with binomial bounds)",
          "[thermal]") {
  for (int order = 1; order <= 4; ++order) {
    const Tally t = RunCases(Warmup(order), 10, 500 + 100 * order);
    Report(fmt::format("warm-up order {}", order), t);
    CheckCoverage(t);
  }
}

TEST_CASE("thermal fit: a power-on warm-up with 100 tags per order", "[thermal][slow]") {
  for (int order = 1; order <= 4; ++order) {
    const Tally t = RunCases(Warmup(order), 100, 5000 + 1000 * order);
    Report(fmt::format("warm-up order {}", order), t);
    CheckCoverage(t, true);
  }
}

TEST_CASE("thermal fit: hysteresis estimated within 2u of the truth", "[thermal]") {
  ThermalSimulationOptions o = Case(2, ThermalProfile::kRamp, true, true);
  o.seed = 42;
  auto sim = SimulateThermalSession(o);
  REQUIRE(sim.ok());
  auto s = ThermalSamplesFromTag(sim.value().session.tags.front(), ImuSensor::kGyro, "sim.csv");
  REQUIRE(s.ok());
  auto fit = FitThermalBias(s.value(), ThermalFitOptions{}, sim.value().truth.t_ref_c);
  REQUIRE(fit.ok());
  REQUIRE(fit.value().legs);
  for (int a = 0; a < 3; ++a) {
    const ThermalAxisFit& f = fit.value().axes[a];
    CHECK(std::abs(f.hysteresis - sim.value().truth.gyro.hysteresis_lsb[a]) <=
          2.0 * f.u_hysteresis);
  }
}

TEST_CASE("thermal fit: a span too small for the order is refused with its figures", "[thermal]") {
  ThermalSimulationOptions o;
  o.temp_low_c = 25.0;
  o.temp_high_c = 28.0;  // 3 degC: order 1 needs 5.
  o.bias_order = 1;
  o.ramp_s = 600;
  auto sim = SimulateThermalSession(o);
  REQUIRE(sim.ok());
  auto s = ThermalSamplesFromTag(sim.value().session.tags.front(), ImuSensor::kGyro, "sim.csv");
  REQUIRE(s.ok());
  auto fit = FitThermalBias(s.value(), ThermalFitOptions{}, std::nan(""));
  REQUIRE_FALSE(fit.ok());
  const std::string m = fit.error().message;
  CHECK(m.find("sim.csv: sensor 1 gyro: the temperature spans ") != std::string::npos);
  CHECK(m.find("order 1 needs at least 5.0 degC") != std::string::npos);
  ThermalFitOptions fixed;
  fixed.order = 3;
  o.temp_high_c = 37.0;  // 12 degC: order 3 needs 15.
  auto sim2 = SimulateThermalSession(o);
  auto s2 = ThermalSamplesFromTag(sim2.value().session.tags.front(), ImuSensor::kGyro, "sim.csv");
  auto fit2 = FitThermalBias(s2.value(), fixed, std::nan(""));
  REQUIRE_FALSE(fit2.ok());
  CHECK(fit2.error().message.find("order 3 needs at least 15.0 degC") != std::string::npos);
}

TEST_CASE("thermal fit: temperature read errors are found and left out with their lines",
          "[thermal]") {
  ThermalSimulationOptions o;
  o.seed = 3;
  o.temp_glitches = 5;
  auto sim = SimulateThermalSession(o);
  REQUIRE(sim.ok());
  REQUIRE(sim.value().truth.glitch_lines.size() == 5);
  auto s = ThermalSamplesFromTag(sim.value().session.tags.front(), ImuSensor::kAccel, "sim.csv");
  REQUIRE(s.ok());
  auto fit = FitThermalBias(s.value(), ThermalFitOptions{}, sim.value().truth.t_ref_c);
  REQUIRE(fit.ok());
  CHECK(fit.value().excluded_lines == sim.value().truth.glitch_lines);
  // The span is the true one, not widened by the +40 degC reads.
  CHECK(fit.value().t_max_c <= o.temp_high_c + 0.5);
}

TEST_CASE("thermal fit: no temp_c column is named", "[thermal]") {
  Tag tag;
  tag.sensor = 2;
  for (const char* name : {"gx_lsb", "gy_lsb", "gz_lsb"}) {
    Quantity q;
    q.name = name;
    tag.quantities.push_back(q);
  }
  auto s = ThermalSamplesFromTag(tag, ImuSensor::kGyro, "s.csv");
  REQUIRE_FALSE(s.ok());
  CHECK(s.error().message.find("s.csv: sensor 2 gyro: no temp_c column") != std::string::npos);
}

}  // namespace
}  // namespace metro
