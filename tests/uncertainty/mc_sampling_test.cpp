// The block samplers of the Monte Carlo method (src/uncertainty/mc_sampling.hpp) against
// Boost.Math distributions, and the tail selection of the coverage intervals against a
// full sort.
//
// Kolmogorov-Smirnov checks: with n values the statistic D exceeds
// sqrt(-ln(p / 2) / (2 n)) with probability at most p (Dvoretzky-Kiefer-Wolfowitz-Massart).
// Each check uses p = 1e-6, so a correct sampler fails one check once in a million runs;
// the seeds are fixed, so a run either always passes or always fails.
#include "uncertainty/mc_sampling.hpp"

#include <algorithm>
#include <boost/math/distributions/normal.hpp>
#include <boost/math/distributions/students_t.hpp>
#include <catch2/catch.hpp>
#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include "metro/uncertainty/budget.hpp"
#include "metro/uncertainty/monte_carlo.hpp"

namespace metro {
namespace {

constexpr size_t kChunk = 1000;

double KsCritical(size_t n) { return std::sqrt(-std::log(1e-6 / 2.0) / (2.0 * n)); }

double KsStatistic(std::vector<double> x, const std::function<double(double)>& cdf) {
  std::sort(x.begin(), x.end());
  const double n = static_cast<double>(x.size());
  double d = 0.0;
  for (size_t i = 0; i < x.size(); ++i) {
    const double f = cdf(x[i]);
    d = std::max(d, std::max(f - static_cast<double>(i) / n, static_cast<double>(i + 1) / n - f));
  }
  return d;
}

// `chunks` blocks of kChunk standard t_nu variates, one WordSource per block as in the Monte
// Carlo run.
std::vector<double> TValues(double nu, size_t chunks, uint64_t seed) {
  std::vector<double> x(chunks * kChunk);
  internal::SamplerScratch scratch(kChunk);
  for (size_t c = 0; c < chunks; ++c) {
    internal::WordSource words(seed, c);
    internal::StudentTBlock(words, nu, 0.0, 1.0, kChunk, &scratch, x.data() + c * kChunk);
  }
  return x;
}

TEST_CASE("Bailey t sampler passes a KS test against Boost students_t", "[uncertainty][mc]") {
  for (double nu : {1.0, 2.5, 5.0, 18.0, 200.0}) {
    INFO("nu = " << nu);
    const std::vector<double> x = TValues(nu, 200, 17);
    const boost::math::students_t t(nu);
    const double d = KsStatistic(x, [&](double v) { return boost::math::cdf(t, v); });
    CHECK(d < KsCritical(x.size()));
  }
}

TEST_CASE("Bailey t sampler with huge dof is a standard normal", "[uncertainty][mc]") {
  // nu = 1e12: e = -2 ln(w) / nu is below 1e-10, where exp(e) - 1 would keep no digit of
  // the tail; the series keeps the full variance 1.
  const std::vector<double> x = TValues(1e12, 200, 5);
  const boost::math::normal z;
  CHECK(KsStatistic(x, [&](double v) { return boost::math::cdf(z, v); }) < KsCritical(x.size()));
  double ss = 0.0;
  for (double v : x) ss += v * v;
  // Var of s^2 for N(0, 1): 2 / n; 5 standard errors.
  CHECK(ss / x.size() == Approx(1.0).margin(5.0 * std::sqrt(2.0 / x.size())));
}

TEST_CASE("Bailey t sampler location and scale", "[uncertainty][mc]") {
  internal::SamplerScratch scratch(kChunk);
  internal::WordSource a(3, 9);
  internal::WordSource b(3, 9);
  std::vector<double> standard(kChunk), shifted(kChunk);
  internal::StudentTBlock(a, 7.0, 0.0, 1.0, kChunk, &scratch, standard.data());
  internal::StudentTBlock(b, 7.0, 50000623.0, 25.0, kChunk, &scratch, shifted.data());
  for (size_t k = 0; k < kChunk; ++k) {
    CHECK(shifted[k] == Approx(50000623.0 + 25.0 * standard[k]).epsilon(1e-15));
  }
}

TEST_CASE("Baseline and AVX2 builds of the t arithmetic agree", "[uncertainty][mc]") {
  std::vector<double> u, w;
  internal::WordSource words(11, 0);
  while (u.size() < 4096) {
    const uint64_t r = words();
    const double s = internal::S32(static_cast<uint32_t>(r >> 32));
    const double t = internal::S32(static_cast<uint32_t>(r));
    if (s * s + t * t < 1.0) {
      u.push_back(s);
      w.push_back(s * s + t * t);
    }
  }
  // Points near the centre and the rim exercise the tails and the series branch.
  u[0] = 0x1.0p-31;
  w[0] = 0x1.0p-61;
  u[1] = 0.9999999;
  w[1] = 0.9999999 * 0.9999999 + 1e-14;
  const size_t n = u.size();
  for (double nu : {0.7, 5.0, 24.0, 1e9}) {
    INFO("nu = " << nu);
    std::vector<double> e(n), base(n), best(n);
    internal::BaileyKernel(false)(u.data(), w.data(), n, nu, 0.0, 1.0, e.data(), base.data());
    internal::BaileyKernel(true)(u.data(), w.data(), n, nu, 0.0, 1.0, e.data(), best.data());
    for (size_t k = 0; k < n; ++k) {
      // Closed form in long double: u sqrt(nu expm1(-2 ln(w) / nu) / w).
      const long double exact =
          u[k] *
          std::sqrt(nu * std::expm1(-2.0L * std::log(static_cast<long double>(w[k])) / nu) / w[k]);
      REQUIRE(std::isfinite(base[k]));
      CHECK(base[k] == Approx(static_cast<double>(exact)).epsilon(1e-12));
      CHECK(best[k] == Approx(static_cast<double>(exact)).epsilon(1e-12));
    }
  }
}

TEST_CASE("Arcsine block sampler passes a KS test", "[uncertainty][mc]") {
  const size_t chunks = 200;
  std::vector<double> x(chunks * kChunk);
  internal::SamplerScratch scratch(kChunk);
  for (size_t c = 0; c < chunks; ++c) {
    internal::WordSource words(23, c);
    internal::ArcsineBlock(words, 0.0, 1.0, kChunk, &scratch, x.data() + c * kChunk);
  }
  const double pi = std::acos(-1.0);
  // JCGM 101 6.4.6.1: G(x) = 1/2 + arcsin(x)/pi on [-1, 1].
  const double d = KsStatistic(x, [&](double v) { return 0.5 + std::asin(v) / pi; });
  CHECK(d < KsCritical(x.size()));
  CHECK(*std::min_element(x.begin(), x.end()) >= -1.0);
  CHECK(*std::max_element(x.begin(), x.end()) <= 1.0);
}

TEST_CASE("Uniform block sampler passes a KS test", "[uncertainty][mc]") {
  const size_t chunks = 200;
  std::vector<double> x(chunks * kChunk);
  for (size_t c = 0; c < chunks; ++c) {
    internal::WordSource words(29, c);
    // Uneven pieces: the block sampler must continue across the word buffer's refills.
    internal::UniformBlock(words, 300, x.data() + c * kChunk);
    internal::UniformBlock(words, 700, x.data() + c * kChunk + 300);
  }
  CHECK(KsStatistic(x, [](double v) { return v; }) < KsCritical(x.size()));
  CHECK(*std::min_element(x.begin(), x.end()) >= 0.0);
  CHECK(*std::max_element(x.begin(), x.end()) < 1.0);
  // U52 values are multiples of 2^-52.
  for (size_t k = 0; k < 1000; ++k) CHECK(std::ldexp(x[k], 52) == std::floor(std::ldexp(x[k], 52)));
}

TEST_CASE("Word source depends on the seed and chunk only", "[uncertainty][mc]") {
  internal::WordSource a(1, 5), b(1, 5), c(1, 6), d(2, 5);
  int same_ab = 0, same_ac = 0, same_ad = 0;
  for (int k = 0; k < 1000; ++k) {
    const uint64_t x = a();
    same_ab += x == b() ? 1 : 0;
    same_ac += x == c() ? 1 : 0;
    same_ad += x == d() ? 1 : 0;
  }
  CHECK(same_ab == 1000);
  CHECK(same_ac == 0);
  CHECK(same_ad == 0);
}

// The k-th order statistic intervals by full sort (JCGM 101 7.7), for comparison.
void CheckIntervalsAgainstSort(const std::vector<double>& v, double p) {
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
  std::vector<double> a = v, b = v;
  const CoverageInterval sym = SymmetricInterval(&a, p);
  const CoverageInterval shortest = ShortestInterval(&b, p);
  CHECK(sym.low == sorted[r - 1]);
  CHECK(sym.high == sorted[r + q - 1]);
  CHECK(shortest.low == sorted[best - 1]);
  CHECK(shortest.high == sorted[best + q - 1]);
}

TEST_CASE("Coverage intervals by threshold selection match a full sort", "[uncertainty][mc]") {
  // 2^19 values: large enough for the threshold path (>= 2^18, L <= M/8).
  const size_t m = size_t{1} << 19;
  std::vector<double> skewed(m), ties(m), ascending(m), periodic(m);
  uint64_t s = 99;
  for (size_t i = 0; i < m; ++i) {
    s = s * 6364136223846793005ULL + 1442695040888963407ULL;
    const double x = static_cast<double>(s >> 11) * 0x1.0p-53;
    skewed[i] = x * x * x;
    ties[i] = std::floor(x * 20.0);  // 20 distinct values: thresholds fall on ties
    ascending[i] = static_cast<double>(i);
    periodic[i] = static_cast<double>(i % 64);  // the pilot (every 64th value) sees one value
  }
  for (double p : {0.9, 0.95, 0.99}) {
    INFO("p = " << p);
    CheckIntervalsAgainstSort(skewed, p);
    CheckIntervalsAgainstSort(ties, p);
    CheckIntervalsAgainstSort(ascending, p);
    CheckIntervalsAgainstSort(periodic, p);
  }
}

TEST_CASE("Monte Carlo moments and threaded intervals match the kept samples",
          "[uncertainty][mc]") {
  auto budget =
      LoadBudget(std::string(METRO_SOURCE_DIR) + "/datasets/budgets/jcgm101_9_5_gauge_block.json");
  REQUIRE(budget.ok());
  McOptions options = budget.value().monte_carlo;
  options.adaptive = false;
  options.trials = 300000;
  options.threads = 2;
  auto run = RunMonteCarlo(budget.value(), options, true);
  REQUIRE(run.ok());
  const McResult& r = run.value();
  const std::vector<double>& y = r.samples;
  REQUIRE(y.size() == 300000);
  // JCGM 101 7.6 by two passes in long double.
  long double sum = 0.0L;
  for (double v : y) sum += v;
  const long double mean = sum / y.size();
  long double ss = 0.0L;
  for (double v : y) ss += (v - mean) * (v - mean);
  CHECK(r.value == Approx(static_cast<double>(mean)).epsilon(1e-13));
  CHECK(r.u == Approx(static_cast<double>(std::sqrt(ss / (y.size() - 1)))).epsilon(1e-11));
  std::vector<double> sorted = y;
  std::sort(sorted.begin(), sorted.end());
  const size_t q = static_cast<size_t>(0.99 * 300000 + 0.5);
  size_t best = 1;
  for (size_t k = 1; k <= y.size() - q; ++k) {
    if (sorted[k + q - 1] - sorted[k - 1] < sorted[best + q - 1] - sorted[best - 1]) best = k;
  }
  // JCGM 101 7.7 as written.
  CHECK(r.shortest_discrete.low == sorted[best - 1]);
  CHECK(r.shortest_discrete.high == sorted[best + q - 1]);
  // The reported interval at the fitted minimum of the width (docs/uncertainty.md) is the
  // single-threaded one of the same values, holds p of them (to the rank interpolation) and
  // is as short as the discrete minimum to within the noise of the widths.
  std::vector<double> copy = sorted;
  const CoverageInterval fitted = ShortestIntervalFitted(&copy, 0.99);
  CHECK(r.shortest.low == fitted.low);
  CHECK(r.shortest.high == fitted.high);
  const auto inside = std::count_if(
      y.begin(), y.end(), [&](double v) { return v >= r.shortest.low && v <= r.shortest.high; });
  CHECK(std::abs(static_cast<double>(inside) - static_cast<double>(q)) <= 2.0);
  const double discrete_width = sorted[best + q - 1] - sorted[best - 1];
  CHECK(r.shortest.high - r.shortest.low >= discrete_width);
  CHECK(r.shortest.high - r.shortest.low == Approx(discrete_width).epsilon(2e-3));
}

}  // namespace
}  // namespace metro
