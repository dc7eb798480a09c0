#include "metro/stats/type_a.hpp"

#include <boost/math/distributions/students_t.hpp>
#include <catch2/catch.hpp>
#include <cmath>
#include <random>
#include <vector>

namespace metro {
namespace {

// Zhang's AR(1) test series, 40 values (../shared/design/metrology-notes.md sec. 3).
const std::vector<double> kZhang = {10.720, 9.604,  8.076,  9.778,  9.275,  11.098, 12.365, 11.155,
                                    11.885, 10.940, 11.828, 10.956, 10.438, 10.223, 9.745,  11.923,
                                    11.896, 11.593, 10.970, 10.009, 9.842,  11.801, 11.709, 12.945,
                                    12.573, 12.190, 12.354, 11.497, 10.956, 9.175,  9.629,  9.952,
                                    12.483, 11.300, 10.330, 12.609, 11.197, 10.929, 9.338,  9.421};

TEST_CASE("Type A reproduces Zhang 2006 autocorrelated example", "[stats][type_a]") {
  auto r = EvaluateTypeA(kZhang.data(), kZhang.size());
  REQUIRE(r.ok());
  const TypeAResult& a = r.value();
  CHECK(a.n == 40);
  CHECK(a.dof == 39);
  CHECK(a.mean == Approx(10.917675).margin(5e-7));
  CHECK(a.std == Approx(1.163614).margin(5e-7));
  CHECK(a.std_of_mean == Approx(0.183984).margin(5e-7));
  CHECK(a.rho1 == Approx(0.490258).margin(5e-7));
  CHECK(a.cutoff_lag == 1);
  CHECK(a.std_of_mean_autocorr == Approx(0.257314).margin(5e-7));
  CHECK(a.n_eff == Approx(20.45).margin(5e-3));
  CHECK_FALSE(a.cutoff_reached_limit);
}

TEST_CASE("Type A of 1..n matches the closed forms", "[stats][type_a]") {
  // mean (n+1)/2, variance n(n+1)/12 for the integers 1..n.
  const int n = 1001;
  std::vector<double> x(n);
  for (int i = 0; i < n; ++i) x[i] = i + 1;
  TypeAOptions no_ac;
  no_ac.autocorrelation = false;
  auto r = EvaluateTypeA(x.data(), x.size(), no_ac);
  REQUIRE(r.ok());
  CHECK(r.value().mean == Approx(501.0).epsilon(1e-15));
  CHECK(r.value().variance == Approx(n * (n + 1) / 12.0).epsilon(1e-14));
  CHECK(r.value().variance_of_mean == Approx(n * (n + 1) / 12.0 / n).epsilon(1e-14));
}

TEST_CASE("Type A is stable on a large offset", "[stats][type_a]") {
  // Values 1e9 + {0.1, 0.2, 0.3} * k pattern: a naive sum of squares loses every digit.
  std::vector<double> x;
  for (int k = 0; k < 3000; ++k) x.push_back(1e9 + 0.1 * (k % 3));
  TypeAOptions no_ac;
  no_ac.autocorrelation = false;
  auto r = EvaluateTypeA(x.data(), x.size(), no_ac);
  REQUIRE(r.ok());
  // Exact variance of the repeating {0, 0.1, 0.2}: mean 0.1, sum of squares per period
  // 0.02, so s^2 = 1000 * 0.02 / 2999.
  CHECK(r.value().variance == Approx(1000 * 0.02 / 2999.0).epsilon(1e-6));
  CHECK(r.value().mean - 1e9 == Approx(0.1).epsilon(1e-6));
}

TEST_CASE("FFT autocorrelation equals the direct sums", "[stats][type_a]") {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> normal;
  std::vector<double> x(5003);
  double prev = 0.0;
  for (double& v : x) v = prev = 0.9 * prev + normal(rng);
  std::vector<double> rho(200);
  Autocorrelation(x.data(), x.size(), 199, rho.data());
  double mean = 0.0;
  for (double v : x) mean += v;
  mean /= x.size();
  double c0 = 0.0;
  for (double v : x) c0 += (v - mean) * (v - mean);
  for (size_t k : {size_t{1}, size_t{5}, size_t{17}, size_t{100}, size_t{199}}) {
    double ck = 0.0;
    for (size_t i = 0; i + k < x.size(); ++i) ck += (x[i] - mean) * (x[i + k] - mean);
    CHECK(rho[k] == Approx(ck / c0).margin(1e-12));
  }
}

// Zhang's variance factor computed by definition: direct lag sums, Bartlett band, no FFT.
double DirectVarianceFactor(const std::vector<double>& x, double confidence, size_t* cutoff) {
  const double n = static_cast<double>(x.size());
  double mean = 0.0;
  for (double v : x) mean += v;
  mean /= n;
  double c0 = 0.0;
  for (double v : x) c0 += (v - mean) * (v - mean);
  const boost::math::students_t t_dist(n - 1.0);
  const double t_q = boost::math::quantile(boost::math::complement(t_dist, (1 - confidence) / 2));
  double factor = 1.0, sum_rho2 = 0.0;
  for (size_t k = 1; k <= x.size() / 4; ++k) {
    double ck = 0.0;
    for (size_t i = 0; i + k < x.size(); ++i) ck += (x[i] - mean) * (x[i + k] - mean);
    const double rho = ck / c0;
    if (std::abs(rho) <= t_q * std::sqrt((1.0 + 2.0 * sum_rho2) / n)) {
      *cutoff = k - 1;
      return factor;
    }
    factor += 2.0 * (1.0 - static_cast<double>(k) / n) * rho;
    sum_rho2 += rho * rho;
  }
  *cutoff = x.size() / 4;
  return factor;
}

TEST_CASE("Blocked FFT lags give the n_eff of the direct definition", "[stats][type_a]") {
  // Slowly decaying AR(1) series: cut-offs below and above the first FFT block (2048 lags),
  // so both the first block and the longer retry are exercised against direct sums.
  for (const double phi : {0.99, 0.99999}) {
    std::mt19937_64 rng(11);
    std::normal_distribution<double> normal;
    std::vector<double> x(30011);
    double prev = 0.0;
    for (double& v : x) v = prev = phi * prev + normal(rng);
    // phi near 1: add a slow drift so the correlation outlasts the first block.
    if (phi > 0.999) {
      for (size_t i = 0; i < x.size(); ++i) x[i] += 0.01 * static_cast<double>(i);
    }
    size_t cutoff = 0;
    const double factor = DirectVarianceFactor(x, 0.95, &cutoff);
    auto r = EvaluateTypeA(x.data(), x.size(), TypeAOptions{});
    REQUIRE(r.ok());
    CHECK(r.value().cutoff_lag == static_cast<int64_t>(cutoff));
    CHECK(r.value().variance_factor == Approx(factor).epsilon(1e-9));
    if (phi > 0.999) CHECK(cutoff > 2048);
    if (phi < 0.999) CHECK((cutoff > 8 && cutoff < 2048));
  }
}

TEST_CASE("n_eff of simulated AR(1) series matches theory", "[stats][type_a]") {
  // For AR(1) with coefficient phi the asymptotic variance factor is (1 + phi)/(1 - phi),
  // so n_eff = n (1 - phi)/(1 + phi). phi = 0.8 needs lags well past the direct range,
  // exercising the FFT path. Averaged over 40 series the relative error of the mean n_eff
  // is a few percent (the truncated sum slightly underestimates F).
  std::mt19937_64 rng(2024);
  std::normal_distribution<double> normal;
  const double phi = 0.8;
  const size_t n = 20000;
  double sum_ratio = 0.0;
  const int series = 40;
  for (int s = 0; s < series; ++s) {
    std::vector<double> x(n);
    double prev = normal(rng) / std::sqrt(1 - phi * phi);
    for (double& v : x) v = prev = phi * prev + normal(rng);
    auto r = EvaluateTypeA(x.data(), n);
    REQUIRE(r.ok());
    sum_ratio += r.value().n_eff / n;
    CHECK(r.value().n_eff < n / 2.0);
  }
  const double expected = (1 - phi) / (1 + phi);
  CHECK(sum_ratio / series == Approx(expected).epsilon(0.10));
}

TEST_CASE("White noise keeps n_eff near n", "[stats][type_a]") {
  std::mt19937_64 rng(99);
  std::normal_distribution<double> normal;
  std::vector<double> x(10000);
  for (double& v : x) v = normal(rng);
  auto r = EvaluateTypeA(x.data(), x.size());
  REQUIRE(r.ok());
  CHECK(r.value().n_eff > 0.9 * x.size());
  CHECK(r.value().cutoff_lag <= 2);
}

TEST_CASE("Type A rejects too few or non-finite observations", "[stats][type_a]") {
  const double one = 1.0;
  auto r1 = EvaluateTypeA(&one, 1);
  REQUIRE_FALSE(r1.ok());
  CHECK(r1.error().message == "1 observation: a Type A evaluation needs at least 2");
  const std::vector<double> bad = {1.0, NAN, 2.0};
  auto r2 = EvaluateTypeA(bad.data(), bad.size());
  REQUIRE_FALSE(r2.ok());
  CHECK(r2.error().message == "observation 2 is not finite");
  // The finiteness check goes through the sum: an infinity late in the series is still named.
  std::vector<double> inf_late(1001, 1.0);
  inf_late[997] = -INFINITY;
  auto r3 = EvaluateTypeA(inf_late.data(), inf_late.size());
  REQUIRE_FALSE(r3.ok());
  CHECK(r3.error().message == "observation 998 is not finite");
  // Finite values whose sum overflows: an error, not an infinite mean.
  const std::vector<double> huge = {1.5e308, 1.6e308, 1.0};
  auto r4 = EvaluateTypeA(huge.data(), huge.size());
  REQUIRE_FALSE(r4.ok());
  CHECK(r4.error().message == "the sum of the 3 observations overflows double precision");
}

}  // namespace
}  // namespace metro
