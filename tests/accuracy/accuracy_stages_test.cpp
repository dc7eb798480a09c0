// The accuracy stages alone (accuracy_stages.hpp) against closed forms and simulated truth,
// and the cases of issue #24 end to end on one seed each: a log with the turned axis only,
// a wrapped readout, a separate reference log with a small clock offset and a lagging tag,
// an up-only sweep.
#include "metro/accuracy/accuracy_stages.hpp"

#include <fmt/format.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <pcg_random.hpp>
#include <random>

#include "metro/core/angles.hpp"
#include "metro/io/session_io.hpp"
#include "metro/sim/table_session.hpp"
#include "support/session_text.hpp"

namespace metro {
namespace {

using testing::Into;
using testing::Load;

AccuracyPoint Point(double reference_deg, double error_deg, double u_deg, int direction = 0) {
  AccuracyPoint p;
  p.reference_deg = reference_deg;
  p.error_deg = error_deg;
  p.type_a.u_deg = u_deg;
  p.type_a.dof = 1e9;
  p.direction = direction;
  return p;
}

TEST_CASE("AR(1) variance of the mean against its closed forms", "[accuracy]") {
  CHECK(Ar1MeanVarianceFactor(10, 0.0) == Approx(0.1));
  // n = 2: Var((x1 + x2)/2) = (2 + 2 phi) / 4.
  CHECK(Ar1MeanVarianceFactor(2, 0.5) == Approx(0.75));
  // Large n: F -> (1 + phi) / ((1 - phi) n).
  CHECK(Ar1MeanVarianceFactor(100000, 0.9) == Approx(19.0 / 100000).epsilon(1e-3));
}

TEST_CASE("Pooled plateau noise recovers sigma and phi of short AR(1) plateaus", "[accuracy]") {
  // 200 plateaus of 20 observations, sigma 0.05, phi 0.9: each plateau's own r1 is biased
  // low by about (1 + 4 phi)/n = 0.23; the pooled restricted likelihood is not.
  pcg64 rng(7);
  std::normal_distribution<double> normal;
  const double phi = 0.9, sigma = 0.05;
  std::vector<double> series;
  std::vector<Plateau> plateaus;
  for (int i = 0; i < 200; ++i) {
    Plateau p;
    p.begin = series.size();
    double x = sigma * normal(rng) + 3.0 * i;  // Each plateau at its own level.
    for (int k = 0; k < 20; ++k) {
      series.push_back(x);
      x = 3.0 * i + phi * (x - 3.0 * i) + sigma * std::sqrt(1.0 - phi * phi) * normal(rng);
    }
    p.end = series.size();
    plateaus.push_back(p);
  }
  const PlateauNoise noise = PlateauNoiseOf(series, plateaus);
  CHECK(noise.plateaus == 200);
  CHECK(noise.phi == Approx(0.9).margin(0.03));
  CHECK(noise.sigma_deg == Approx(0.05).epsilon(0.1));
}

// The dof of the pooled noise: 45 plateaus of 20 observations at phi = 0.9 (a 4 s dwell at
// 5 Hz) leave phi poorly known, so u^2 = sigma^2 F(20, phi) scatters far more than the
// innovations' 855 dof say. Over 300 simulated sweeps the variance of ln u^2 must match
// 2 / dof (JCGM 100 G.4.2) within 25 % (sampling scatter of a variance from 300 draws: 8 %),
// and the stated dof must lie far below the count of observations.
TEST_CASE("Pooled plateau noise states the dof its u has", "[accuracy]") {
  pcg64 rng(11);
  std::normal_distribution<double> normal;
  const double phi = 0.9, sigma = 0.05;
  std::vector<double> log_u2;
  double sum_inv_dof = 0.0;
  for (int rep = 0; rep < 300; ++rep) {
    std::vector<double> series;
    std::vector<Plateau> plateaus;
    for (int i = 0; i < 45; ++i) {
      Plateau p;
      p.begin = series.size();
      double x = sigma * normal(rng);
      for (int k = 0; k < 20; ++k) {
        series.push_back(x + 5.0 * i);
        x = phi * x + sigma * std::sqrt(1.0 - phi * phi) * normal(rng);
      }
      p.end = series.size();
      plateaus.push_back(p);
    }
    const PlateauNoise noise = PlateauNoiseOf(series, plateaus);
    log_u2.push_back(
        std::log(noise.sigma_deg * noise.sigma_deg * Ar1MeanVarianceFactor(20, noise.phi)));
    sum_inv_dof += 1.0 / noise.dof;
  }
  double mean = 0.0;
  for (double v : log_u2) mean += v / log_u2.size();
  double var = 0.0;
  for (double v : log_u2) var += (v - mean) * (v - mean) / (log_u2.size() - 1.0);
  const double stated = 2.0 * sum_inv_dof / log_u2.size();
  CHECK(var == Approx(stated).epsilon(0.25));
  CHECK(2.0 / stated < 40.0);
  // And u^2 is unbiased in the log within its scatter: the truth's ln u^2 near the mean.
  const double truth = std::log(sigma * sigma * Ar1MeanVarianceFactor(20, phi));
  CHECK(std::fabs(mean - truth) < 0.5 * std::sqrt(var));
}

TEST_CASE("Uncorrected mixture U against closed forms", "[accuracy]") {
  // One plateau without error: the normal quantile, 1.959964 u.
  CHECK(UncorrectedMixtureU({Point(0, 0.0, 0.0)}, 1.0, 0.95) == Approx(1.959964).epsilon(1e-5));
  // Errors +-1 deg with a tiny random part: U = 1 deg plus the normal tail.
  const double u = UncorrectedMixtureU({Point(0, 1.0, 0.0), Point(90, -1.0, 0.0)}, 1e-3, 0.95);
  // P(|1 + N| <= U) = Phi((U - 1)/s) (the far tail is nil) = 0.95: U = 1 + 1.644854 s.
  CHECK(u == Approx(1.0 + 1.644854e-3).epsilon(1e-6));
}

TEST_CASE("Linearity deviation and its u against the straight-line closed form", "[accuracy]") {
  // Angle means (0, 1, 0) at -10, 0, 10 deg with u = 0.1: line 1/3, deviations (-1/3, 2/3,
  // -1/3); u(d_mid) = u sqrt(1 - h_mid), h_mid = 1/3.
  const Linearity lin =
      LinearityOf({Point(-10, 0.0, 0.1), Point(0, 1.0, 0.1), Point(10, 0.0, 0.1)}, 0.05);
  CHECK(lin.line_offset_deg == Approx(1.0 / 3.0));
  CHECK(lin.line_slope == Approx(0.0).margin(1e-12));
  CHECK(lin.max_abs_deviation_deg == Approx(2.0 / 3.0));
  CHECK(lin.at_reference_deg == Approx(0.0));
  CHECK(lin.u_max_abs_deviation_deg == Approx(0.1 * std::sqrt(2.0 / 3.0)));
}

TEST_CASE("Repeatability and hysteresis stages against hand-computed groups", "[accuracy]") {
  // Angle 30 up twice (0.1, 0.3) and down twice (0.0, 0.2): s_r^2 = (0.02 + 0.02) / 2.
  const std::vector<AccuracyPoint> pts = {Point(30, 0.1, 0.01, 1), Point(30, 0.0, 0.01, -1),
                                          Point(30, 0.3, 0.01, 1), Point(30, 0.2, 0.01, -1)};
  const Repeatability r = RepeatabilityOf(pts, 0.05);
  REQUIRE(r.available);
  CHECK(r.s_r_deg == Approx(std::sqrt(0.02)));
  CHECK(r.dof == 2.0);
  CHECK(r.u_s_r_deg == Approx(std::sqrt(0.02) / 2.0));
  const Hysteresis h = HysteresisOf(pts, 0.05);
  REQUIRE(h.pairs.size() == 1);
  CHECK(h.pairs[0].hysteresis_deg == Approx(0.1));
  // Each side's u from its plateaus' u: 0.01 / sqrt(2); u(h) = sqrt(2) 0.01 / sqrt(2).
  CHECK(h.pairs[0].u_deg == Approx(0.01));
}

TEST_CASE("The hysteresis term leaves the curve's parameters unbiased", "[accuracy]") {
  // Noise-free errors c0 + s theta +- h/2, turning points visited one way only (0 first, 90
  // up): the fit returns c0, s and h exactly.
  std::vector<AccuracyPoint> pts;
  const double angles[] = {0, 30, 60, 90, 60, 30, 0};
  const int dirs[] = {0, 1, 1, 1, -1, -1, -1};
  for (int i = 0; i < 7; ++i) {
    pts.push_back(Point(angles[i], 0.5 + 0.002 * angles[i] + 0.5 * dirs[i] * 0.15, 0.01, dirs[i]));
  }
  auto curve = FitErrorCurve(pts, ErrorModel::kLinear, 0.05);
  REQUIRE(curve.ok());
  REQUIRE(curve.value().hysteresis_term);
  CHECK(curve.value().fit.params[0] == Approx(0.5).margin(1e-9));
  CHECK(curve.value().fit.params[1] == Approx(0.002).margin(1e-12));
  CHECK(curve.value().fit.params[2] == Approx(0.15).margin(1e-9));
}

TEST_CASE("A log with the turned axis only is evaluated without cross-axis", "[accuracy]") {
  TableSimulationOptions o;
  o.seed = 21;
  o.sweeps = 1;
  std::string text;
  REQUIRE(SimulateTableSession(o, SessionFormat::kCsv, Into(&text)).ok());
  const Session full = Load(text);
  const Tag& tag = full.tags.at(0);
  std::string yaw_only = "t_s,table_angle_deg,yaw_deg\n";
  for (size_t k = 0; k < tag.size(); ++k) {
    yaw_only += fmt::format("{:.6f},{:.6f},{:.4f}\n", tag.t_s[k],
                            tag.Find("table_angle_deg")->values[k], tag.Find("yaw_deg")->values[k]);
  }
  auto r = EvaluateAccuracy(Load(yaw_only), nullptr, {});
  REQUIRE(r.ok());
  auto ref = EvaluateAccuracy(full, nullptr, {});
  REQUIRE(ref.ok());
  CHECK_FALSE(r.value().cross_axis_available);
  CHECK(r.value().points.size() == ref.value().points.size());
  CHECK(r.value().fit.params[0] == Approx(ref.value().fit.params[0]).margin(1e-3));
  bool said = false;
  for (const std::string& w : r.value().warnings) {
    said = said || w == "the session has the tag's yaw_deg only: cross-axis coupling (pitch_deg "
                        "and roll_deg) is not evaluated";
  }
  CHECK(said);
}

TEST_CASE("A wrapped readout gets the directions and sweeps of the unwrapped table", "[accuracy]") {
  TableSimulationOptions o;
  o.seed = 22;
  o.readout_wrap_180 = true;
  std::string text;
  TableTruth truth;
  REQUIRE(SimulateTableSession(o, SessionFormat::kCsv, Into(&text), nullptr, &truth).ok());
  auto r = EvaluateAccuracy(Load(text), nullptr, {});
  REQUIRE(r.ok());
  REQUIRE(r.value().points.size() == truth.plateaus.size());
  CHECK(r.value().reference_unwrapped);
  for (size_t i = 0; i < truth.plateaus.size(); ++i) {
    CHECK(r.value().points[i].direction == truth.plateaus[i].direction);
    CHECK(r.value().points[i].reference_deg == Approx(truth.plateaus[i].reference_deg));
  }
  CHECK(r.value().repeatability.sweeps == 2);
  CHECK(r.value().hysteresis.pairs.size() == 10);
}

TEST_CASE("A reference log 0.1 s ahead of a lagging tag: offset and lag apart", "[accuracy]") {
  TableSimulationOptions o;
  o.seed = 23;
  o.sweeps = 1;
  o.reference_clock_offset_s = 0.1;
  o.lag_tau_s = 0.5;
  std::string text, ref_text;
  REQUIRE(SimulateTableSession(o, SessionFormat::kCsv, Into(&text), Into(&ref_text)).ok());
  const Session reference = Load(ref_text);
  auto r = EvaluateAccuracy(Load(text), &reference, {});
  REQUIRE(r.ok());
  REQUIRE(r.value().alignment.has_value());
  const Alignment& a = *r.value().alignment;
  CHECK(a.lag_modelled);
  CHECK(a.offset_s == Approx(0.1).margin(0.03));
  CHECK(a.lag_tau_s == Approx(0.5).margin(0.05));
  // The pure delay alone lands early by most of the lag (the whole lag on a long ramp).
  CHECK(a.delay_s < 0.1 - 0.2);
  CHECK(r.value().lag_tau_s == a.lag_tau_s);
}

// A reference offset given 0.3 s wrong (the reference seems to stop and start 0.3 s late):
// the tag is already moving for the last 0.3 s of every plateau by the reference's clock.
// The departing ends are trimmed and said so; the plateau errors and the hysteresis then match
// the simulation's truth within their u, and the noise and U are those of the right offset.
// Kept, they inflate the pooled reading noise and every u built on it.
TEST_CASE("A tag moving before the reference stops has its plateau ends trimmed", "[accuracy]") {
  TableSimulationOptions o;
  o.seed = 27;
  o.sweeps = 1;
  o.reference_clock_offset_s = 0.1;
  std::string text, ref_text;
  TableTruth truth;
  REQUIRE(SimulateTableSession(o, SessionFormat::kCsv, Into(&text), Into(&ref_text), &truth).ok());
  const Session session = Load(text), reference = Load(ref_text);
  auto evaluate = [&](bool trim) {
    AccuracyOptions a;
    a.alignment.offset_s = 0.1 - 0.3;
    a.plateaus.trim_departures = trim;
    auto r = EvaluateAccuracy(session, &reference, a);
    REQUIRE(r.ok());
    return std::move(r).value();
  };
  // Plateau errors more than 3 u from the truth, and the hysteresis's z.
  auto misses = [&](const AccuracyResult& r) {
    REQUIRE(r.points.size() == truth.plateaus.size());
    int n = 0;
    for (size_t i = 0; i < r.points.size(); ++i) {
      const double z =
          (r.points[i].error_deg - truth.plateaus[i].error_deg) / r.points[i].type_a.u_deg;
      if (std::fabs(z) > 3.0) ++n;
    }
    return n;
  };
  const AccuracyResult trimmed = evaluate(true);
  CHECK(trimmed.segmentation.departure_trimmed_plateaus >= 20);
  CHECK(trimmed.segmentation.max_end_trimmed_s > 0.2);
  CHECK(trimmed.segmentation.max_end_trimmed_s < 0.6);
  CHECK(misses(trimmed) <= 2);
  CHECK(std::fabs(trimmed.hysteresis.mean_deg - o.hysteresis_deg) <
        3.0 * trimmed.hysteresis.u_mean_deg);
  bool said = false;
  for (const std::string& w : trimmed.warnings) {
    said = said || w.find("the tag moved while the reference was still") == 0;
  }
  CHECK(said);
  // As with the right offset: the same reading noise and corrected U.
  AccuracyOptions right;
  right.alignment.offset_s = 0.1;
  auto reference_case = EvaluateAccuracy(session, &reference, right);
  REQUIRE(reference_case.ok());
  const AccuracyResult& good = reference_case.value();
  CHECK(good.segmentation.departure_trimmed_plateaus == 0);
  CHECK(trimmed.noise.sigma_deg == Approx(good.noise.sigma_deg).epsilon(0.03));
  CHECK(trimmed.corrected.gum.expanded == Approx(good.corrected.gum.expanded).epsilon(0.03));
  // Kept, the moving ends make the pooled reading noise (and every u built on it) many times
  // too large: measured sigma 2.4 deg instead of 0.049, U 6.1 deg instead of 0.17.
  const AccuracyResult kept = evaluate(false);
  CHECK(kept.noise.sigma_deg > 10.0 * good.noise.sigma_deg);
  CHECK(kept.corrected.gum.expanded > 10.0 * good.corrected.gum.expanded);
}

TEST_CASE("An up-only sweep says hysteresis was not measured and widens U", "[accuracy]") {
  TableSimulationOptions o;
  o.seed = 24;
  o.sweeps = 1;
  o.up_only = true;
  std::string text;
  REQUIRE(SimulateTableSession(o, SessionFormat::kCsv, Into(&text)).ok());
  auto r = EvaluateAccuracy(Load(text), nullptr, {});
  REQUIRE(r.ok());
  CHECK_FALSE(r.value().hysteresis.available);
  CHECK_FALSE(r.value().fit_hysteresis_term);
  bool input = false;
  for (const BudgetLine& line : r.value().corrected.gum.budget) {
    if (line.name == "hysteresis_not_measured") {
      input = true;
      CHECK(line.u == Approx(0.2 / std::sqrt(3.0)));
    }
  }
  CHECK(input);
  bool said = false;
  for (const std::string& w : r.value().warnings) {
    said = said || w.find("hysteresis was not measured") == 0;
  }
  CHECK(said);
}

TEST_CASE("A tag lagging 1 s settles by its modelled lag and says so", "[accuracy]") {
  TableSimulationOptions o;
  o.seed = 25;
  o.lag_tau_s = 1.0;
  std::string text;
  TableTruth truth;
  REQUIRE(SimulateTableSession(o, SessionFormat::kCsv, Into(&text), nullptr, &truth).ok());
  auto r = EvaluateAccuracy(Load(text), nullptr, {});
  REQUIRE(r.ok());
  CHECK(r.value().lag_tau_s == Approx(1.0).margin(0.1));
  CHECK(r.value().lag_settled_plateaus > 40);
  CHECK(std::fabs(r.value().hysteresis.mean_deg - 0.15) < 3.0 * r.value().hysteresis.u_mean_deg);
  bool said = false;
  for (const std::string& w : r.value().warnings) said = said || w.find("the tag lags") == 0;
  CHECK(said);
}

}  // namespace
}  // namespace metro
