// Monte Carlo method against JCGM 101:2008 clause 9 and closed forms.
//
// Tolerances come from the trial count M. For a sample of M values:
//   se(mean) = sigma / sqrt(M);
//   se(s) ~= sigma sqrt((kurtosis - 1) / (4 M))   (kurtosis 3 for a normal);
//   se(y_p) ~= sqrt(p (1 - p) / M) / g(y_p)       (g the density at the quantile).
// Each check allows 5 standard errors (a false alarm once in ~3.5 million runs for a
// normal statistic), unless a published rounding is wider.
#include "metro/uncertainty/monte_carlo.hpp"

#include <algorithm>
#include <atomic>
#include <boost/math/distributions/normal.hpp>
#include <boost/math/distributions/students_t.hpp>
#include <boost/math/quadrature/gauss.hpp>
#include <catch2/catch.hpp>
#include <cmath>
#include <functional>
#include <stdexcept>
#include <string>

#include "metro/uncertainty/budget.hpp"
#include "metro/uncertainty/gum.hpp"

namespace metro {
namespace {

Budget Parse(const std::string& text) {
  auto b = ParseBudget(text, "test.json");
  if (!b.ok()) FAIL(b.error().ToString());
  return b.value();
}

Budget Load(const std::string& name) {
  auto b = LoadBudget(std::string(METRO_SOURCE_DIR) + "/datasets/budgets/" + name);
  if (!b.ok()) FAIL(b.error().ToString());
  return b.value();
}

McResult Run(const Budget& budget, int64_t trials, bool keep = false) {
  McOptions options = budget.monte_carlo;
  options.adaptive = false;
  options.trials = trials;
  auto r = RunMonteCarlo(budget, options, keep);
  if (!r.ok()) FAIL(r.error().ToString());
  return r.value();
}

double Phi(double z) { return boost::math::cdf(boost::math::normal(), z); }
double PhiDensity(double z) { return boost::math::pdf(boost::math::normal(), z); }

// Solves F(x) = p by bisection on [lo, hi].
double Quantile(const std::function<double(double)>& cdf, double p, double lo, double hi) {
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (cdf(mid) < p ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

// CDF of N(0, sigma^2) + R(-a, a): (sigma / 2a) [G((y + a)/sigma) - G((y - a)/sigma)],
// G(z) = z Phi(z) + phi(z) (the integral of Phi).
double NormalPlusRectCdf(double y, double sigma, double a) {
  const auto g = [](double z) { return z * Phi(z) + PhiDensity(z); };
  return sigma / (2 * a) * (g((y + a) / sigma) - g((y - a) / sigma));
}

// Irwin-Hall CDF of the sum of n U(0, 1).
double IrwinHallCdf(double x, int n) {
  double sum = 0.0;
  double binom = 1.0;
  double factorial = 1.0;
  for (int k = 1; k <= n; ++k) factorial *= k;
  for (int k = 0; k <= n && k <= x; ++k) {
    sum += (k % 2 ? -1.0 : 1.0) * binom * std::pow(x - k, n);
    binom = binom * (n - k) / (k + 1);
  }
  return sum / factorial;
}

const std::string kAdditive = R"({"measurand": {"name": "Y", "model": "X1 + X2 + X3 + X4"},
  "inputs": [)";

TEST_CASE("JCGM 101 9.2.2 additive model with normal inputs", "[uncertainty][mc]") {
  const Budget b = Parse(kAdditive + R"(
    {"name": "X1", "value": 0, "u": 1}, {"name": "X2", "value": 0, "u": 1},
    {"name": "X3", "value": 0, "u": 1}, {"name": "X4", "value": 0, "u": 1}],
    "monte_carlo": {"trials": 1000000, "seed": 7}})");
  const int64_t m = 1000000;
  const McResult r = Run(b, m);
  // Y ~ N(0, 4): u = 2, 95 % interval +-1.959964 * 2 = +-3.919928 (9.2.2: [-3.92, 3.92]).
  CHECK(r.value == Approx(0.0).margin(5 * 2.0 / std::sqrt(m)));
  CHECK(r.u == Approx(2.0).margin(5 * 2.0 * std::sqrt(2.0 / (4.0 * m))));
  const double se_q = std::sqrt(0.975 * 0.025 / m) / (PhiDensity(1.959964) / 2.0);
  CHECK(r.symmetric.low == Approx(-3.919928).margin(5 * se_q));
  CHECK(r.symmetric.high == Approx(3.919928).margin(5 * se_q));
  // The shortest interval of a symmetric unimodal pdf is the symmetric one; its end points
  // move by at most ~ the quantile error.
  CHECK(r.shortest.low == Approx(-3.919928).margin(10 * se_q));
  CHECK(r.shortest.high == Approx(3.919928).margin(10 * se_q));
  // GUF validated (9.2.2): delta = 0.05 for u = 2.0 at ndig = 2.
  auto gum = EvaluateGum(b);
  REQUIRE(gum.ok());
  const GufValidation v = ValidateGuf(gum.value(), r, 2);
  CHECK(v.delta == Approx(0.05));
  CHECK(v.validated);
}

TEST_CASE("JCGM 101 9.2.3 additive model with rectangular inputs", "[uncertainty][mc]") {
  const Budget b = Parse(kAdditive + R"(
    {"name": "X1", "value": 0, "distribution": "rectangular", "half_width": 1.7320508075688772},
    {"name": "X2", "value": 0, "distribution": "rectangular", "half_width": 1.7320508075688772},
    {"name": "X3", "value": 0, "distribution": "rectangular", "half_width": 1.7320508075688772},
    {"name": "X4", "value": 0, "distribution": "rectangular", "half_width": 1.7320508075688772}],
    "monte_carlo": {"trials": 1000000, "seed": 3}})");
  const int64_t m = 1000000;
  const McResult r = Run(b, m);
  // Exact: Y = sqrt(3) (2 S - 4), S Irwin-Hall(4); kurtosis of Y is 3 - 1.2/4 = 2.7.
  const double a = std::sqrt(3.0);
  const double s975 = Quantile([](double x) { return IrwinHallCdf(x, 4); }, 0.975, 0.0, 4.0);
  const double y975 = a * (2 * s975 - 4);
  CHECK(y975 == Approx(3.88).margin(0.005));                       // The published MCM end point.
  const double density = (std::pow(4 - s975, 3) / 6.0) / (2 * a);  // g at the upper tail
  const double se_q = std::sqrt(0.975 * 0.025 / m) / density;
  CHECK(r.u == Approx(2.0).margin(5 * 2.0 * std::sqrt(1.7 / (4.0 * m))));
  CHECK(r.symmetric.high == Approx(y975).margin(5 * se_q));
  CHECK(r.symmetric.low == Approx(-y975).margin(5 * se_q));
  // GUF [-3.92, 3.92] differs by ~0.04 from [-3.88, 3.88]: not validated at ndig = 3
  // (delta = 0.005 >> 5 se_q).
  auto gum = EvaluateGum(b);
  REQUIRE(gum.ok());
  CHECK(gum.value().u == Approx(2.0));
  const GufValidation v = ValidateGuf(gum.value(), r, 3);
  CHECK(v.delta == Approx(0.0005 * 10));
  CHECK_FALSE(v.validated);
  CHECK(v.d_high > v.delta);
}

TEST_CASE("JCGM 101 9.2.4 additive model with a dominant rectangular input", "[uncertainty][mc]") {
  const Budget b = Parse(kAdditive + R"(
    {"name": "X1", "value": 0, "u": 1}, {"name": "X2", "value": 0, "u": 1},
    {"name": "X3", "value": 0, "u": 1},
    {"name": "X4", "value": 0, "distribution": "rectangular", "half_width": 17.320508075688775}],
    "monte_carlo": {"trials": 1000000, "seed": 11}})");
  const int64_t m = 1000000;
  const McResult r = Run(b, m);
  const double sigma = std::sqrt(3.0);
  const double a = 10 * std::sqrt(3.0);
  const auto cdf = [&](double y) { return NormalPlusRectCdf(y, sigma, a); };
  const double y975 = Quantile(cdf, 0.975, 0.0, 40.0);
  CHECK(y975 == Approx(17.0).margin(0.05));  // Published MCM interval [-17.0, 17.0].
  const double density = (cdf(y975 + 1e-4) - cdf(y975 - 1e-4)) / 2e-4;
  const double se_q = std::sqrt(0.975 * 0.025 / m) / density;
  CHECK(r.symmetric.high == Approx(y975).margin(5 * se_q));
  CHECK(r.symmetric.low == Approx(-y975).margin(5 * se_q));
  // u = sqrt(103) = 10.149 (kurtosis below 3: 5 se with kurtosis 3 is conservative).
  CHECK(r.u == Approx(std::sqrt(103.0)).margin(5 * std::sqrt(103.0) * std::sqrt(2.0 / (4.0 * m))));
  auto gum = EvaluateGum(b);
  REQUIRE(gum.ok());
  CHECK(gum.value().expanded == Approx(19.9).margin(0.05));  // GUF [-19.9, 19.9]
  CHECK_FALSE(ValidateGuf(gum.value(), r, 2).validated);
}

TEST_CASE("JCGM 101 9.3 mass calibration", "[uncertainty][mc]") {
  const Budget b = Load("jcgm101_9_3_mass.json");
  const int64_t m = 1000000;
  const McResult r = Run(b, m);
  // Published MCM: 1.2341 mg, u = 0.0754 mg (0.0755 in the issue's rounding), shortest 95 %
  // [1.0834, 1.3825] mg. se(u) ~ 0.0755 sqrt(2/(4M)) = 5e-5 mg at M = 1e6 (the pdf is close
  // to normal); published values carry +-5e-5 rounding, so the margin is 5e-5 + 5 se.
  CHECK(r.value == Approx(1.2341).margin(5e-5 + 5 * 0.0755 / std::sqrt(m)));
  CHECK(r.u == Approx(0.07545).margin(1e-4 + 5 * 5.3e-5));
  // Width: each end point has se ~ sqrt(0.025 0.975 / M) / g = 1.1e-4 mg (g ~ 1.4 / mg in
  // the tails), the width ~ sqrt(2) times that.
  CHECK(r.shortest.high - r.shortest.low == Approx(1.3825 - 1.0834).margin(1e-4 + 5 * 1.6e-4));
  // The location of the shortest interval of a nearly symmetric pdf is poorly determined
  // (widths change only at second order in the shift; end points converge like M^(-1/3),
  // see docs/uncertainty.md): at M = 1e6 seeds spread by ~1e-3 mg, hence 2.5e-3.
  CHECK(r.shortest.low == Approx(1.0834).margin(2.5e-3));
  CHECK(r.shortest.high == Approx(1.3825).margin(2.5e-3));
  auto gum = EvaluateGum(b);
  REQUIRE(gum.ok());
  // GUF first order: u = sqrt(0.05^2 + 0.02^2) = 0.0539 mg (both density sensitivities are
  // zero at rho_W = rho_R and rho_a = rho_a0); not validated (9.3: d ~ 0.045 mg >> 0.0005).
  CHECK(gum.value().u == Approx(std::sqrt(0.05 * 0.05 + 0.02 * 0.02)).epsilon(1e-6));
  CHECK_FALSE(ValidateGuf(gum.value(), r, 2).validated);
  // Second order (9.3.2.3, Table 9): u = 0.0750 mg.
  GumOptions second = b.gum;
  second.second_order = true;
  auto g2 = EvaluateGum(b, second);
  REQUIRE(g2.ok());
  CHECK(g2.value().u == Approx(0.0750).margin(2e-4));
}

TEST_CASE("JCGM 101 9.4 comparison loss where the first-order GUF gives u = 0",
          "[uncertainty][mc]") {
  const Budget b = Parse(R"({"measurand": {"name": "Y", "model": "X1^2 + X2^2"},
    "inputs": [{"name": "X1", "value": 0, "u": 0.005}, {"name": "X2", "value": 0, "u": 0.005}],
    "monte_carlo": {"trials": 1000000, "seed": 5}})");
  const int64_t m = 1000000;
  const McResult r = Run(b, m);
  // Y = u^2 chi^2_2: exponential with mean theta = 2 u^2 = 5e-5 and sd theta; shortest 95 %
  // interval [0, theta ln 20], symmetric [-theta ln 0.975, theta ln 40]. Kurtosis 9.
  const double theta = 5e-5;
  CHECK(r.value == Approx(theta).margin(5 * theta / std::sqrt(m)));
  CHECK(r.u == Approx(theta).margin(5 * theta * std::sqrt(8.0 / (4.0 * m))));
  const double q95 = theta * std::log(20.0);
  const double se_q95 = theta * std::sqrt(0.95 * 0.05 / m) / 0.05;
  CHECK(r.shortest.low == Approx(0.0).margin(theta * 1e-4));
  CHECK(r.shortest.high == Approx(q95).margin(5 * se_q95));
  CHECK(r.symmetric.high ==
        Approx(theta * std::log(40.0)).margin(5 * theta * std::sqrt(0.975 * 0.025 / m) / 0.025));
  auto gum = EvaluateGum(b);
  REQUIRE(gum.ok());
  CHECK(gum.value().u == 0.0);  // The GUF's answer at x = 0 (9.4.2.2).
  CHECK_FALSE(ValidateGuf(gum.value(), r, 2).validated);
  // Second-order GUF: u^2 = sum_i (1/2)(d2f/dxi2)^2 u^4 = 2 * 2 u^4 -> u = 2 u^2 = theta.
  GumOptions second = b.gum;
  second.second_order = true;
  auto g2 = EvaluateGum(b, second);
  REQUIRE(g2.ok());
  CHECK(g2.value().u == Approx(theta).epsilon(1e-9));
}

TEST_CASE("JCGM 101 9.5 gauge block", "[uncertainty][mc]") {
  const Budget b = Load("jcgm101_9_5_gauge_block.json");
  const int64_t m = 1000000;
  const McResult r = Run(b, m);
  // Exact variance (inputs independent; da, dth, th0 + dlt have mean 0 or enter products
  // whose cross moments vanish):
  //   Var = sum s^2 nu/(nu - 2) over the four t inputs
  //       + E[ls^2] E[da^2] E[theta^2] + E[ls^2] E[als^2] E[dth^2]
  // with E[da^2] = a^2/3 + d^2/9 (ctrap), E[theta^2] = 0.1^2 + 0.2^2 + 0.5^2/2.
  const auto tv = [](double s, double nu) { return s * s * nu / (nu - 2); };
  const double ls2 = 50000623.0 * 50000623.0 + tv(25, 18);
  const double da2 = 1e-12 / 3 + 0.01e-12 / 9;
  const double theta2 = 0.01 + 0.04 + 0.125;
  const double als2 = 11.5e-6 * 11.5e-6 + 4e-12 / 3;
  const double dth2 = 0.0025 / 3 + 0.025 * 0.025 / 9;
  const double var =
      tv(25, 18) + tv(5.8, 24) + tv(3.9, 5) + tv(6.7, 8) + ls2 * da2 * theta2 + ls2 * als2 * dth2;
  const double u_exact = std::sqrt(var);  // 35.68 nm
  CHECK(std::round(u_exact) == 36.0);     // Published MCM u = 36 nm.
  // The t_5 input has an infinite fourth moment, so se(u) is not the normal one; a 1 %
  // margin is ~10x the spread seen over 20 seeds at M = 1e6.
  CHECK(r.u == Approx(u_exact).epsilon(0.01));
  CHECK(r.value == Approx(838.0 - 0.0).margin(5 * u_exact / std::sqrt(m) + 0.5));
  // Published shortest 99 % interval [745, 932] nm, rounded to 1 nm; se of a 99 % end point
  // ~ sqrt(0.01 0.99 / 1e6) / (0.0007 / nm) ~ 0.15 nm.
  CHECK(r.shortest.low == Approx(745.0).margin(0.5 + 5 * 0.15));
  CHECK(r.shortest.high == Approx(932.0).margin(0.5 + 5 * 0.15));
  auto gum = EvaluateGum(b);
  REQUIRE(gum.ok());
  CHECK(std::round(gum.value().u) == 32.0);  // GUF u = 32 nm.
}

TEST_CASE("Adaptive Monte Carlo stops by its rule", "[uncertainty][mc]") {
  Budget b = Load("jcgm101_9_3_mass.json");
  McOptions options = b.monte_carlo;
  REQUIRE(options.adaptive);
  auto run = RunMonteCarlo(b, options, true);
  REQUIRE(run.ok());
  const McResult& r = run.value();
  REQUIRE(r.converged);
  REQUIRE(r.ok);
  const int64_t h = r.blocks;
  CHECK(h >= 10);
  CHECK(h % 10 == 0);  // stage 2 is tested on multiples of G = 10 blocks
  CHECK(r.trials == h * 10000);
  REQUIRE(r.samples.size() == static_cast<size_t>(r.trials));
  const auto mean_sd = [](const std::vector<double>& z) {
    double m = 0;
    for (double v : z) m += v;
    m /= static_cast<double>(z.size());
    double s = 0;
    for (double v : z) s += (v - m) * (v - m);
    return std::pair{m, std::sqrt(s / static_cast<double>(z.size() - 1))};
  };
  // Both stages recomputed from the pooled values (docs/uncertainty.md).
  std::vector<double> means, us, lows, highs;
  for (int64_t k = 0; k < h; ++k) {
    std::vector<double> block(r.samples.begin() + k * 10000, r.samples.begin() + (k + 1) * 10000);
    const auto [mean, sd] = mean_sd(block);
    std::sort(block.begin(), block.end());
    means.push_back(mean);
    us.push_back(sd);
    lows.push_back(block[250 - 1]);  // r = (M - q)/2 = 250, y_(r)
    highs.push_back(block[250 + 9500 - 1]);
  }
  const double delta = NumericalTolerance(mean_sd(r.samples).second, 2);
  CHECK(r.delta == Approx(delta));
  const double t =
      boost::math::quantile(boost::math::students_t(static_cast<double>(h - 1)), 0.975);
  for (const auto* z : {&means, &us, &lows, &highs}) {
    CHECK(t * mean_sd(*z).second / std::sqrt(static_cast<double>(h)) <= delta);
  }
  std::vector<double> g_low, g_high;
  const size_t group = static_cast<size_t>(r.trials / 10);
  for (size_t g = 0; g < 10; ++g) {
    std::vector<double> part(r.samples.begin() + static_cast<std::ptrdiff_t>(g * group),
                             r.samples.begin() + static_cast<std::ptrdiff_t>((g + 1) * group));
    const CoverageInterval iv = ShortestIntervalFitted(&part, 0.95);
    g_low.push_back(iv.low);
    g_high.push_back(iv.high);
  }
  const double t9 = boost::math::quantile(boost::math::students_t(9.0), 0.975);
  const double half_low = t9 * mean_sd(g_low).second * std::pow(10.0, -0.4);
  const double half_high = t9 * mean_sd(g_high).second * std::pow(10.0, -0.4);
  CHECK(half_low <= delta);
  CHECK(half_high <= delta);
  CHECK(r.stability.shortest_low == Approx(half_low).epsilon(1e-9));
  CHECK(r.stability.shortest_high == Approx(half_high).epsilon(1e-9));
  CHECK(r.stability.groups == 10);
  // And the pooled result agrees with the published 9.3 values at its own tolerance.
  CHECK(r.u == Approx(0.07545).margin(2 * r.delta + 1e-4));
}

TEST_CASE("Numerical tolerance of JCGM 101 7.9.2", "[uncertainty][mc]") {
  CHECK(NumericalTolerance(0.0996, 2) == Approx(0.005));  // rounds to 0.10 first
  CHECK(NumericalTolerance(2.0, 2) == Approx(0.05));
  CHECK(NumericalTolerance(0.0539, 2) == Approx(0.0005));
  CHECK(NumericalTolerance(35.7, 1) == Approx(5.0));  // 36 -> 4 x 10^1, delta = 5
  CHECK(NumericalTolerance(1.0, 3) == Approx(0.005));
}

TEST_CASE("Coverage intervals by partial selection match a full sort", "[uncertainty][mc]") {
  std::vector<double> v;
  uint64_t s = 12345;
  for (int i = 0; i < 20001; ++i) {
    s = s * 6364136223846793005ULL + 1442695040888963407ULL;
    const double x = static_cast<double>(s >> 11) * 0x1.0p-53;
    v.push_back(x * x * x);  // skewed
  }
  for (double p : {0.5, 0.9, 0.95, 0.99}) {
    std::vector<double> sorted = v;
    std::sort(sorted.begin(), sorted.end());
    const size_t m = v.size();
    const double pm = p * static_cast<double>(m);
    const size_t q = pm == std::floor(pm) ? static_cast<size_t>(pm) : static_cast<size_t>(pm + 0.5);
    const size_t r = (m - q) % 2 == 0 ? (m - q) / 2 : (m - q + 1) / 2;
    size_t best = 1;
    for (size_t k = 1; k <= m - q; ++k) {
      if (sorted[k + q - 1] - sorted[k - 1] < sorted[best + q - 1] - sorted[best - 1]) best = k;
    }
    std::vector<double> a = v;
    std::vector<double> b = v;
    const CoverageInterval sym = SymmetricInterval(&a, p);
    const CoverageInterval shortest = ShortestInterval(&b, p);
    CHECK(sym.low == sorted[r - 1]);
    CHECK(sym.high == sorted[r + q - 1]);
    CHECK(shortest.low == sorted[best - 1]);
    CHECK(shortest.high == sorted[best + q - 1]);
  }
}

TEST_CASE("Samplers reproduce the JCGM 101 6.4 moments", "[uncertainty][mc]") {
  // Each input alone through y = x: mean and standard deviation against JCGM 100 4.3 /
  // JCGM 101 6.4 (se(u)/u <= sqrt((kurtosis - 1)/(4M)); kurtosis <= 9 here except t).
  struct Case {
    const char* input;
    double mean;
    double u;
  };
  const double a = 2.0;
  const Case cases[] = {
      {R"({"name": "x", "value": 1, "u": 0.5})", 1, 0.5},
      {R"({"name": "x", "value": 1, "distribution": "rectangular", "half_width": 2})", 1,
       a / std::sqrt(3.0)},
      {R"({"name": "x", "value": 1, "distribution": "triangular", "half_width": 2})", 1,
       a / std::sqrt(6.0)},
      {R"({"name": "x", "value": 1, "distribution": "arcsine", "half_width": 2})", 1,
       a / std::sqrt(2.0)},
      {R"({"name": "x", "value": 1, "distribution": "trapezoidal", "half_width": 2, "beta": 0.5})",
       1, a * std::sqrt(1.25 / 6.0)},
      {R"({"name": "x", "value": 1, "distribution": "ctrap", "half_width": 2, "d": 0.5})", 1,
       std::sqrt(4.0 / 3.0 + 0.25 / 9.0)},
      // t_nu(mu, s^2): sd = s sqrt(nu / (nu - 2)); nu = 10 keeps the fourth moment finite.
      {R"({"name": "x", "value": 1, "distribution": "t", "scale": 0.5, "dof": 10})", 1,
       0.5 * std::sqrt(10.0 / 8.0)},
      {R"({"name": "x", "type_a": {"mean": 1, "std": 1.5, "n": 9}})", 1,
       0.5 * std::sqrt(8.0 / 6.0)},
  };
  const int64_t m = 400000;
  for (const Case& c : cases) {
    INFO(c.input);
    const Budget b =
        Parse(std::string(R"({"measurand": {"name": "y", "model": "x"}, "inputs": [)") + c.input +
              R"(], "monte_carlo": {"trials": 400000, "seed": 2}})");
    const McResult r = Run(b, m);
    CHECK(r.value == Approx(c.mean).margin(5 * c.u / std::sqrt(m)));
    // Kurtosis of t_10 is 3 + 6/(10 - 4) = 4, of the rest <= 3.
    CHECK(r.u == Approx(c.u).margin(5 * c.u * std::sqrt(3.0 / (4.0 * m))));
  }
}

TEST_CASE("An input without a variance is named and u(y) is undefined, never converged noise",
          "[uncertainty][mc]") {
  // issue #22: a Type A input of 3 readings is t_2(x, s^2/3) (JCGM 101 6.4.9), which has no
  // variance; metro reported u = 330 as converged. Now: the input is named, u is NaN, and
  // the intervals (quantiles, defined) match t_2's: x +- t_0.975(2) s / sqrt(3).
  const Budget b = Parse(R"({"measurand": {"name": "y", "model": "x"},
    "inputs": [{"name": "x", "type_a": {"mean": 10, "std": 0.3, "n": 3}}],
    "monte_carlo": {"trials": 1000000, "seed": 5}})");
  REQUIRE(InputsWithoutVariance(b) == std::vector<std::string>{"x (nu = 2)"});
  const boost::math::students_t t2(2.0);
  const double scale = 0.3 / std::sqrt(3.0);
  const double half = boost::math::quantile(t2, 0.975) * scale;  // 4.3027 s / sqrt(3)
  const int64_t m = 1000000;
  // se of the 0.975 quantile: sqrt(p (1 - p) / M) / g(y_p), g the t_2 density scaled.
  const double se = std::sqrt(0.975 * 0.025 / m) /
                    (boost::math::pdf(t2, boost::math::quantile(t2, 0.975)) / scale);
  const McResult r = Run(b, m);
  CHECK(r.inputs_without_variance == std::vector<std::string>{"x (nu = 2)"});
  CHECK_FALSE(r.u_defined);
  CHECK(r.mean_defined);
  CHECK(std::isnan(r.u));
  CHECK(r.value == Approx(10.0).margin(0.05));  // the mean exists (nu > 1), slowly converging
  CHECK(r.symmetric.low == Approx(10.0 - half).margin(5 * se));
  CHECK(r.symmetric.high == Approx(10.0 + half).margin(5 * se));
  CHECK_THAT(r.message, Catch::Contains("u(y) is undefined: input x (nu = 2) is drawn from a t"));

  // Adaptive: settles on the interval alone, well before the cap, to its own delta.
  McOptions options = b.monte_carlo;
  options.adaptive = true;
  options.max_trials = 20000000;
  auto adaptive = RunMonteCarlo(b, options);
  REQUIRE(adaptive.ok());
  CHECK(adaptive.value().converged);
  CHECK(adaptive.value().trials < options.max_trials);
  CHECK(std::isnan(adaptive.value().u));
  CHECK(std::isnan(adaptive.value().stability.u));
  CHECK(adaptive.value().symmetric.high == Approx(10.0 + half).margin(2 * adaptive.value().delta));

  // Two readings: t_1 (Cauchy) has no mean either.
  const Budget cauchy = Parse(R"({"measurand": {"name": "y", "model": "2 * x"},
    "inputs": [{"name": "x", "type_a": {"values": [1.0, 1.2]}}],
    "monte_carlo": {"trials": 200000, "seed": 1}})");
  const McResult c = Run(cauchy, 200000);
  CHECK_FALSE(c.mean_defined);
  CHECK(std::isnan(c.value));
  CHECK_THAT(c.message, Catch::Contains("and so is the mean (nu <= 1)"));
  // y = 2x: the 95 % interval of 2 (1.1 + t_1 s / sqrt(2)), s = 0.1414, t_0.975(1) = 12.706.
  const double half1 = 2.0 * boost::math::quantile(boost::math::students_t(1.0), 0.975) *
                       (std::sqrt(0.02) / std::sqrt(2.0));
  CHECK(c.symmetric.high - c.symmetric.low == Approx(2 * half1).epsilon(0.05));
}

TEST_CASE("Correlated normal inputs by Cholesky", "[uncertainty][mc]") {
  // y = a - b with r(a, b) = 0.8, u = 1 and 2: Var = 1 + 4 - 2 * 0.8 * 2 = 1.8.
  const Budget b = Parse(R"({"measurand": {"name": "y", "model": "a - b"},
    "inputs": [{"name": "a", "value": 0, "u": 1}, {"name": "b", "value": 0, "u": 2}],
    "correlations": [{"a": "a", "b": "b", "r": 0.8}], "monte_carlo": {"trials": 400000}})");
  const McResult r = Run(b, 400000);
  CHECK(r.u == Approx(std::sqrt(1.8)).margin(5 * std::sqrt(1.8) * std::sqrt(2.0 / (4.0 * 400000))));
  auto g = EvaluateGum(b);
  REQUIRE(g.ok());
  CHECK(g.value().u == Approx(std::sqrt(1.8)));
}

TEST_CASE("Monte Carlo is deterministic for a seed whatever the thread count",
          "[uncertainty][mc]") {
  const Budget b = Load("jcgm101_9_5_gauge_block.json");
  McOptions options = b.monte_carlo;
  options.adaptive = false;
  options.trials = 54321;  // not a multiple of the chunk size
  options.threads = 1;
  auto one = RunMonteCarlo(b, options, true);
  options.threads = 3;
  auto three = RunMonteCarlo(b, options, true);
  options.seed = 2;
  auto other = RunMonteCarlo(b, options, true);
  REQUIRE(one.ok());
  REQUIRE(three.ok());
  REQUIRE(other.ok());
  CHECK(one.value().samples == three.value().samples);
  CHECK(one.value().samples != other.value().samples);
  CHECK(one.value().generator.find("pcg64") != std::string::npos);
  CHECK(one.value().seed == 1);
}

TEST_CASE("Monte Carlo progress counts every trial once and changes nothing", "[uncertainty][mc]") {
  const Budget b = Load("jcgm101_9_5_gauge_block.json");
  for (const bool adaptive : {false, true}) {
    McOptions options = b.monte_carlo;
    options.adaptive = adaptive;
    options.trials = 654321;  // Fixed run: ~10 reports per worker, the last one short.
    options.threads = 2;
    auto quiet = RunMonteCarlo(b, options, true);
    std::atomic<int64_t> trials{0};
    std::atomic<int64_t> calls{0};
    options.on_trials_done = [&](int64_t n) {
      trials += n;
      ++calls;
    };
    auto heard = RunMonteCarlo(b, options, true);
    REQUIRE(quiet.ok());
    REQUIRE(heard.ok());
    CHECK(trials.load() == heard.value().trials);
    CHECK(calls.load() >= 2);
    CHECK(quiet.value().samples == heard.value().samples);
    if (!adaptive) CHECK(heard.value().trials == 654321);
  }
}

TEST_CASE("Monte Carlo reports a model that is NaN for some trials", "[uncertainty][mc]") {
  const Budget b = Parse(R"j({"measurand": {"name": "y", "model": "sqrt(x)"},
    "inputs": [{"name": "x", "value": 1, "u": 1}], "monte_carlo": {"trials": 10000}})j");
  auto r = RunMonteCarlo(b);
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().message.find("model 'sqrt(x)' is NaN or infinite in") != std::string::npos);
  CHECK(r.error().message.find("x = -") != std::string::npos);
}

TEST_CASE("JCGM 101 9.5 gauge block at 1e7 trials", "[uncertainty][mc][slow]") {
  const Budget b = Load("jcgm101_9_5_gauge_block.json");
  const McResult r = Run(b, 10000000);
  CHECK(r.u == Approx(35.68).epsilon(0.005));
  CHECK(r.shortest.low == Approx(745.0).margin(0.5 + 5 * 0.05));
  CHECK(r.shortest.high == Approx(932.0).margin(0.5 + 5 * 0.05));
}

TEST_CASE("An exception in a Monte Carlo worker reaches the caller", "[uncertainty][mc]") {
  // issue #21 part 8: the chunks run on core/parallel, which rethrows a worker's exception
  // in the calling thread (a bare std::thread would call std::terminate). on_trials_done is
  // called from the workers, so a throwing one is an exception inside a worker.
  const Budget b = Load("jcgm101_9_3_mass.json");
  for (const bool adaptive : {false, true}) {
    for (const int threads : {1, 2, 3}) {
      INFO("adaptive " << adaptive << ", threads " << threads);
      McOptions options = b.monte_carlo;
      options.adaptive = adaptive;
      options.trials = 300000;
      options.threads = threads;
      std::atomic<int64_t> heard{0};
      options.on_trials_done = [&](int64_t n) {
        if ((heard += n) > 64000) throw std::runtime_error("worker stopped by the test");
      };
      CHECK_THROWS_WITH(RunMonteCarlo(b, options), "worker stopped by the test");
    }
  }
  // The same options without the throw still run (nothing left behind by the failure).
  McOptions options = b.monte_carlo;
  options.adaptive = false;
  options.trials = 100000;
  options.threads = 2;
  auto r = RunMonteCarlo(b, options);
  REQUIRE(r.ok());
  CHECK(r.value().trials == 100000);
}

TEST_CASE("The fitted shortest interval is closer to the exact one than the discrete",
          "[uncertainty][mc]") {
  // JCGM 101 7.7's discrete minimiser converges like M^(-1/3); the fitted minimum of the
  // width (docs/uncertainty.md) faster. Y = exp(X), X ~ N(0, 0.25^2), is lognormal and
  // skewed; its shortest 95 % interval minimises exp(0.25 z(s + 0.95)) - exp(0.25 z(s)),
  // z the normal quantile: [0.566982, 1.556482] (golden section, Python, separately), where
  // the pdf phi(ln y / 0.25) / (0.25 y) is equal at both ends.
  const Budget b = Parse(R"j({"measurand": {"name": "Y", "model": "exp(X)"},
    "inputs": [{"name": "X", "value": 0, "u": 0.25}],
    "monte_carlo": {"trials": 1000000, "seed": 1}})j");
  const CoverageInterval exact = {0.566982, 1.556482};
  const auto pdf = [](double y) { return PhiDensity(std::log(y) / 0.25) / (0.25 * y); };
  CHECK(pdf(exact.low) == Approx(pdf(exact.high)).epsilon(1e-4));
  CHECK(Phi(std::log(exact.high) / 0.25) - Phi(std::log(exact.low) / 0.25) ==
        Approx(0.95).margin(1e-6));
  double ss_fitted = 0.0;
  double ss_discrete = 0.0;
  for (uint64_t seed = 1; seed <= 12; ++seed) {
    McOptions options = b.monte_carlo;
    options.adaptive = false;
    options.trials = 1000000;
    options.seed = seed;
    auto r = RunMonteCarlo(b, options);
    REQUIRE(r.ok());
    const McResult& m = r.value();
    const auto sq = [](double x) { return x * x; };
    ss_fitted += sq(m.shortest.low - exact.low) + sq(m.shortest.high - exact.high);
    ss_discrete +=
        sq(m.shortest_discrete.low - exact.low) + sq(m.shortest_discrete.high - exact.high);
  }
  WARN("lognormal, 12 seeds at M = 1e6: rms error of the end points, fitted "
       << std::sqrt(ss_fitted / 24) << ", discrete " << std::sqrt(ss_discrete / 24));
  CHECK(ss_fitted < ss_discrete);
}

// JCGM 101 9.3 by quadrature, independent of any sampling. With S = mrc + dmrc ~ N(mu_S,
// sigma_S^2), mu_S = 100001.234 mg, sigma_S^2 = 0.05^2 + 0.02^2, A = rhoa - 1.2 ~ R(-0.1, 0.1)
// and B = 1/rhow - 1/rhor, the model is Y = S (1 + A B) - 100000. Given B, Y is the sum of
// N(1.234, sigma_S^2) and a rectangular of half-width 0.1 mu_S |B| (the sd of the normal part
// is sigma_S |1 + A B|, which differs from sigma_S by at most 3.2e-6 relative, moving the
// end points by < 1e-6 mg), whose CDF is NormalPlusRectCdf; F_Y is its mean over rhow ~
// R(7000, 9000) and rhor ~ R(7950, 8050) kg/m^3 by Gauss-Legendre quadrature with N nodes.
template <int N>
double MassCdf(double y) {
  const double mu = 1.234;
  const double sigma = std::sqrt(0.05 * 0.05 + 0.02 * 0.02);
  const double mu_s = 100001.234;
  // Nodes of the product rule, once: half-width a_k and weight (w_i/2)(w_j/2) of the mean
  // over the two rectangular densities (N even: nodes +-x_i on [-1, 1]).
  static const std::vector<std::pair<double, double>> nodes = [&] {
    using Gauss = boost::math::quadrature::gauss<double, N>;
    std::vector<std::pair<double, double>> t;  // (x on [-1, 1], weight on the mean)
    for (size_t i = 0; i < Gauss::abscissa().size(); ++i) {
      t.emplace_back(Gauss::abscissa()[i], Gauss::weights()[i] / 2);
      t.emplace_back(-Gauss::abscissa()[i], Gauss::weights()[i] / 2);
    }
    std::vector<std::pair<double, double>> out;
    for (const auto& [xw, ww] : t) {
      for (const auto& [xr, wr] : t) {
        const double rhow = 8000.0 + 1000.0 * xw;
        const double rhor = 8000.0 + 50.0 * xr;
        out.emplace_back(0.1 * mu_s * std::fabs(1 / rhow - 1 / rhor), ww * wr);
      }
    }
    return out;
  }();
  double f = 0.0;
  for (const auto& [a, w] : nodes) {
    f += w * (a < 1e-9 ? Phi((y - mu) / sigma) : NormalPlusRectCdf(y - mu, sigma, a));
  }
  return f;
}

struct Reference {
  CoverageInterval symmetric;
  CoverageInterval shortest;
};

// 95 % intervals of a CDF: symmetric [G^-1(0.025), G^-1(0.975)]; shortest by golden-section
// search of the width G^-1(s + 0.95) - G^-1(s) over s in (0, 0.05).
Reference Intervals95(const std::function<double(double)>& cdf, double lo, double hi) {
  const auto q = [&](double p) {
    double a = lo;
    double b = hi;
    for (int i = 0; i < 64; ++i) {
      const double mid = 0.5 * (a + b);
      (cdf(mid) < p ? a : b) = mid;
    }
    return 0.5 * (a + b);
  };
  Reference r;
  r.symmetric = {q(0.025), q(0.975)};
  const auto width = [&](double s) { return q(s + 0.95) - q(s); };
  double a = 1e-4;
  double b = 0.05 - 1e-4;
  const double g = (std::sqrt(5.0) - 1) / 2;
  for (int i = 0; i < 40; ++i) {
    const double c = b - g * (b - a);
    const double d = a + g * (b - a);
    if (width(c) < width(d)) {
      b = d;
    } else {
      a = c;
    }
  }
  const double s = 0.5 * (a + b);
  r.shortest = {q(s), q(s + 0.95)};
  return r;
}

// The share of adaptive runs, over seeds 1..n, whose intervals both lie within delta of the
// reference at every end point; the trial counts for docs/uncertainty.md.
struct SeedSweep {
  int hits = 0;
  int shortest_hits = 0;
  int symmetric_hits = 0;
  int discrete_hits = 0;  // JCGM 101 7.7's discrete shortest interval of the same runs
  int converged = 0;
  std::vector<int64_t> trials;
};

SeedSweep Sweep(const Budget& b, const Reference& ref, double delta, int n) {
  SeedSweep out;
  for (int seed = 1; seed <= n; ++seed) {
    McOptions options = b.monte_carlo;
    REQUIRE(options.adaptive);
    options.seed = static_cast<uint64_t>(seed);
    auto run = RunMonteCarlo(b, options);
    REQUIRE(run.ok());
    const McResult& m = run.value();
    out.converged += m.converged ? 1 : 0;
    out.trials.push_back(m.trials);
    const auto near = [&](const CoverageInterval& x, const CoverageInterval& y) {
      return std::fabs(x.low - y.low) <= delta && std::fabs(x.high - y.high) <= delta;
    };
    const bool shortest = near(m.shortest, ref.shortest);
    const bool symmetric = near(m.symmetric, ref.symmetric);
    UNSCOPED_INFO("seed " << seed << ": M = " << m.trials << ", shortest [" << m.shortest.low
                          << ", " << m.shortest.high << "], symmetric [" << m.symmetric.low << ", "
                          << m.symmetric.high << "]");
    out.shortest_hits += shortest ? 1 : 0;
    out.symmetric_hits += symmetric ? 1 : 0;
    out.discrete_hits += near(m.shortest_discrete, ref.shortest) ? 1 : 0;
    out.hits += shortest && symmetric ? 1 : 0;
  }
  std::sort(out.trials.begin(), out.trials.end());
  return out;
}

std::string Summary(const char* name, const SeedSweep& s) {
  const size_t n = s.trials.size();
  const double median = n % 2 ? static_cast<double>(s.trials[n / 2])
                              : 0.5 * static_cast<double>(s.trials[n / 2 - 1] + s.trials[n / 2]);
  return std::string(name) + ": both intervals within delta in " + std::to_string(s.hits) + " of " +
         std::to_string(n) + " seeds (shortest " + std::to_string(s.shortest_hits) +
         ", symmetric " + std::to_string(s.symmetric_hits) + "; discrete 7.7 shortest " +
         std::to_string(s.discrete_hits) + "); trials median " +
         std::to_string(static_cast<int64_t>(median)) + ", range " +
         std::to_string(s.trials.front()) + " - " + std::to_string(s.trials.back());
}

TEST_CASE("JCGM 101 9.3 reference intervals by quadrature", "[uncertainty][mc][slow]") {
  // Quadrature of order 24 and 32 agree to 2e-6 mg. The issue's references from 2 x 1e8
  // draws: symmetric [1.0844, 1.3836] mg, reproduced to their rounding; shortest [1.0843,
  // 1.3834] mg, a discrete JCGM 101 7.7 minimiser, which at 2e8 trials still wanders by
  // ~1e-3 (2e8/1e6)^(-1/3) = 1.7e-4 mg (docs/uncertainty.md): within 2.5e-4 of the exact
  // [1.08443, 1.38357] mg.
  const Reference r32 = Intervals95(MassCdf<32>, 0.5, 2.0);
  const Reference r24 = Intervals95(MassCdf<24>, 0.5, 2.0);
  CHECK(r32.shortest.low == Approx(r24.shortest.low).margin(2e-6));
  CHECK(r32.shortest.high == Approx(r24.shortest.high).margin(2e-6));
  CHECK(r32.symmetric.low == Approx(r24.symmetric.low).margin(2e-6));
  // Every component N(1.234, sigma_S^2) + R(-a, a) is symmetric about 1.234 mg, so is the
  // mixture, and the shortest interval of a symmetric unimodal pdf is the symmetric one.
  CHECK(r32.shortest.low == Approx(r32.symmetric.low).margin(1e-6));
  CHECK(r32.shortest.high == Approx(r32.symmetric.high).margin(1e-6));
  CHECK(r32.symmetric.low + r32.symmetric.high == Approx(2 * 1.234).margin(1e-6));
  CHECK(r32.symmetric.low == Approx(1.0844).margin(1e-4));
  CHECK(r32.symmetric.high == Approx(1.3836).margin(1e-4));
  CHECK(r32.shortest.low == Approx(1.0843).margin(2.5e-4));
  CHECK(r32.shortest.high == Approx(1.3834).margin(2.5e-4));
  // The published JCGM 101 9.3 result (10^6 trials): shortest [1.0834, 1.3825] mg, width
  // 0.2991 mg; the width is the well-determined part.
  CHECK(r32.shortest.high - r32.shortest.low == Approx(0.2991).margin(2e-4));
  WARN("JCGM 101 9.3 by quadrature: symmetric [" << r32.symmetric.low << ", " << r32.symmetric.high
                                                 << "], shortest [" << r32.shortest.low << ", "
                                                 << r32.shortest.high << "] mg");
}

TEST_CASE("Adaptive Monte Carlo keeps its tolerance over 40 seeds (JCGM 101 9.3, 9.2.2)",
          "[uncertainty][mc][slow]") {
  // issue #21 part 6: with n_dig = 2, both 95 % intervals within delta of the exact ones at
  // every end point in at least 36 of 40 seeds (the rule aims at 95 %).
  SECTION("9.3 mass calibration, delta = 0.0005 mg") {
    const Budget b = Load("jcgm101_9_3_mass.json");
    const Reference ref = Intervals95(MassCdf<32>, 0.5, 2.0);
    const SeedSweep s = Sweep(b, ref, 0.0005, 40);
    WARN(Summary("JCGM 101 9.3", s));
    CHECK(s.converged == 40);
    CHECK(s.hits >= 36);
  }
  SECTION("9.2.2 additive normal, delta = 0.05") {
    const Budget b = Load("jcgm101_9_2_2_additive.json");
    // Y ~ N(0, 4): both intervals are +-1.959964 * 2 (closed form).
    const double z = boost::math::quantile(boost::math::normal(), 0.975);
    const Reference ref{{-2 * z, 2 * z}, {-2 * z, 2 * z}};
    const SeedSweep s = Sweep(b, ref, 0.05, 40);
    WARN(Summary("JCGM 101 9.2.2", s));
    CHECK(s.converged == 40);
    CHECK(s.hits >= 36);
  }
}

}  // namespace
}  // namespace metro
