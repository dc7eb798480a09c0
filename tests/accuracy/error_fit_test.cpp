// Weighted least-squares error curve: exact recovery, closed-form covariance, coverage of the
// stated u, and the order rule.
#include "metro/accuracy/error_fit.hpp"

#include <catch2/catch.hpp>
#include <cmath>
#include <pcg_random.hpp>
#include <random>

namespace metro {
namespace {

std::vector<FitPoint> Grid(double start, double step, int count, double u) {
  std::vector<FitPoint> p;
  for (int i = 0; i < count; ++i) p.push_back({start + step * i, 0.0, u});
  return p;
}

TEST_CASE("Error fit recovers exact harmonic parameters", "[accuracy]") {
  const double truth[6] = {0.5, 0.002, 0.3, -0.2, 0.05, -0.04};
  std::vector<FitPoint> points = Grid(0.0, 30.0, 12, 0.01);
  for (FitPoint& p : points) {
    const double t = p.theta_deg * M_PI / 180.0;
    p.value_deg = truth[0] + truth[1] * p.theta_deg + truth[2] * std::cos(t) +
                  truth[3] * std::sin(t) + truth[4] * std::cos(2 * t) + truth[5] * std::sin(2 * t);
  }
  auto fit = FitHarmonicModel(points, ErrorModelTerms(ErrorModel::kHarmonic2));
  REQUIRE(fit.ok());
  for (int j = 0; j < 6; ++j) CHECK(fit.value().params[j] == Approx(truth[j]).margin(1e-12));
  CHECK(fit.value().chi2 == Approx(0.0).margin(1e-18));
  CHECK_FALSE(fit.value().covariance_scaled);
  CHECK(fit.value().dof == 6);
}

TEST_CASE("Straight-line covariance matches the closed form", "[accuracy]") {
  // Equal weights u: var(slope) = u^2 / Sxx, var(c0) = u^2 (1/m + mean^2 / Sxx) (exact data:
  // chi2 = 0, so the covariance is not scaled).
  std::vector<FitPoint> points = Grid(0.0, 45.0, 5, 0.02);
  for (FitPoint& p : points) p.value_deg = 0.1 + 0.001 * p.theta_deg;
  auto fit = FitHarmonicModel(points, ErrorModelTerms(ErrorModel::kLinear));
  REQUIRE(fit.ok());
  const double mean = 90.0, sxx = 2 * 90.0 * 90.0 + 2 * 45.0 * 45.0;
  CHECK(fit.value().u[1] == Approx(0.02 / std::sqrt(sxx)).epsilon(1e-9));
  CHECK(fit.value().u[0] == Approx(0.02 * std::sqrt(1.0 / 5 + mean * mean / sxx)).epsilon(1e-9));
  CHECK(fit.value().covariance[0][1] == Approx(-mean * 0.02 * 0.02 / sxx).epsilon(1e-9));
  // Prediction u at the mean angle is u / sqrt(m).
  CHECK(fit.value().PredictionU(90.0) == Approx(0.02 / std::sqrt(5.0)).epsilon(1e-9));
}

TEST_CASE("Error fit u covers the truth at the stated rate", "[accuracy]") {
  // 400 replicas with N(0, u_i^2) noise, u_i varying: each parameter within 1.96 u about
  // 95 % of the time. Binomial(2400, 0.95) sd 0.45 %: accept 92.5..97.5 %.
  pcg64 rng(7);
  std::normal_distribution<double> normal;
  const double truth[4] = {-0.3, 0.001, 0.2, 0.1};
  std::vector<FitPoint> points = Grid(-90.0, 20.0, 14, 0.0);
  int within = 0, total = 0;
  for (int rep = 0; rep < 400; ++rep) {
    for (size_t i = 0; i < points.size(); ++i) {
      FitPoint& p = points[i];
      p.u_deg = 0.01 * (1.0 + static_cast<double>(i % 3));
      const double t = p.theta_deg * M_PI / 180.0;
      p.value_deg = truth[0] + truth[1] * p.theta_deg + truth[2] * std::cos(t) +
                    truth[3] * std::sin(t) + p.u_deg * normal(rng);
    }
    auto fit = FitHarmonicModel(points, ErrorModelTerms(ErrorModel::kHarmonic1));
    REQUIRE(fit.ok());
    // The covariance is scaled when chi2/nu > 1: that only widens it, so coverage >= 95 %
    // is expected; count with the unscaled u for the exact rate.
    const double scale = fit.value().covariance_scaled ? std::sqrt(fit.value().reduced_chi2) : 1.0;
    for (int j = 0; j < 4; ++j) {
      within += std::fabs(fit.value().params[j] - truth[j]) <= 1.96 * fit.value().u[j] / scale;
      ++total;
    }
  }
  const double rate = static_cast<double>(within) / total;
  CHECK(rate > 0.925);
  CHECK(rate < 0.975);
}

TEST_CASE("Error model order rule", "[accuracy]") {
  // 12 angles over 330 deg: the second harmonic; 6 over 250: the first; 4 over 90: linear.
  CHECK(ChooseErrorModel(Grid(0, 30, 12, 0.01), ErrorModel::kAuto, 0.05).value() ==
        ErrorModel::kHarmonic2);
  CHECK(ChooseErrorModel(Grid(0, 50, 6, 0.01), ErrorModel::kAuto, 0.05).value() ==
        ErrorModel::kHarmonic1);
  CHECK(ChooseErrorModel(Grid(0, 30, 4, 0.01), ErrorModel::kAuto, 0.05).value() ==
        ErrorModel::kLinear);
  // Repeated angles count once.
  std::vector<FitPoint> repeated = Grid(0, 30, 3, 0.01);
  for (const FitPoint& p : Grid(0, 30, 3, 0.01)) repeated.push_back(p);
  auto few = ChooseErrorModel(repeated, ErrorModel::kAuto, 0.05);
  REQUIRE(!few.ok());
  CHECK(few.error().message ==
        "fewer points than the linear error model needs: it has 2 parameters and needs plateaus "
        "at >= 4 distinct reference angles; found 3 angle(s) spanning 60 deg. Collect dwell "
        "plateaus at more table angles");
  auto narrow = ChooseErrorModel(Grid(0, 15, 7, 0.01), ErrorModel::kHarmonic1, 0.05);
  REQUIRE(!narrow.ok());
  CHECK(narrow.error().message ==
        "fewer points than the harmonic1 error model needs: it has 4 parameters and needs "
        "plateaus at >= 6 distinct reference angles spanning >= 180 deg; found 7 angle(s) "
        "spanning 90 deg. Collect dwell plateaus at more table angles over at least 180 deg");
  auto model = ParseErrorModel("cubic");
  REQUIRE(!model.ok());
  CHECK(model.error().message ==
        "unknown error model 'cubic' (expected auto, linear, harmonic1 or harmonic2)");
}

TEST_CASE("Error fit refuses bad points", "[accuracy]") {
  std::vector<FitPoint> points = Grid(0, 30, 5, 0.01);
  points[2].u_deg = 0.0;
  auto zero_u = FitHarmonicModel(points, ErrorModelTerms(ErrorModel::kLinear));
  REQUIRE(!zero_u.ok());
  CHECK(zero_u.error().message == "fit point 2 has a non-finite value or a u that is not > 0");
  auto too_few = FitHarmonicModel(Grid(0, 30, 3, 0.01), ErrorModelTerms(ErrorModel::kHarmonic1));
  REQUIRE(!too_few.ok());
  CHECK(too_few.error().message == "fewer points (3) than the model's 4 parameters");
  // Four points at two angles cannot separate cos from sin and the line.
  std::vector<FitPoint> two = {{0, 0, 0.01}, {0, 0, 0.01}, {90, 0, 0.01}, {90, 0, 0.01}};
  auto singular = FitHarmonicModel(two, ErrorModelTerms(ErrorModel::kHarmonic1));
  REQUIRE(!singular.ok());
  CHECK(singular.error().message.find("singular design") != std::string::npos);
}

}  // namespace
}  // namespace metro
