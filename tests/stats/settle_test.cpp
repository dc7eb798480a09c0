#include "metro/stats/settle.hpp"

#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <vector>

#include "metro/stats/type_a.hpp"

namespace metro {
namespace {

TEST_CASE("MSER-5 finds the end of a known exponential transient", "[stats][settle]") {
  // x_i = A exp(-i / tau) + e_i with e_i ~ N(0, sigma^2). The transient exceeds 2 sigma
  // until i = tau ln(A / 2 sigma) = 200 ln 10 = 461 and falls below 0.05 sigma at
  // i = tau ln(A / 0.05 sigma) = 200 ln 400 = 1198. A good truncation removes the former
  // and keeps most of the rest. Checked over 20 seeds.
  const double amplitude = 20.0, sigma = 1.0, tau = 200.0;
  const size_t n = 6000;
  for (int seed = 0; seed < 20; ++seed) {
    std::mt19937_64 rng(seed);
    std::normal_distribution<double> noise(0.0, sigma);
    std::vector<double> x(n);
    for (size_t i = 0; i < n; ++i) x[i] = amplitude * std::exp(-double(i) / tau) + noise(rng);
    const SettleResult r = DetectSettleMser5(x.data(), n);
    CHECK(r.samples >= 461);
    CHECK(r.samples <= 1198);
    CHECK_FALSE(r.at_limit);
  }
}

TEST_CASE("MSER-5 keeps a stationary series whole", "[stats][settle]") {
  std::mt19937_64 rng(5);
  std::normal_distribution<double> noise;
  std::vector<double> x(5000);
  for (double& v : x) v = noise(rng);
  // Without a transient the minimum sits near the start: at most a few batches go.
  CHECK(DetectSettleMser5(x.data(), x.size()).samples <= 250);
}

TEST_CASE("MSER-5 needs two batches", "[stats][settle]") {
  const double x[9] = {5, 4, 3, 2, 1, 0, 0, 0, 0};
  CHECK(DetectSettleMser5(x, 9).samples == 0);
}

// Stationary noise of marginal standard deviation sigma: white, or AR(1)
// e_k = phi e_{k-1} + sqrt(1 - phi^2) sigma w_k started in its stationary law.
std::vector<double> Noise(size_t n, double sigma, double phi, std::mt19937_64* rng) {
  std::normal_distribution<double> w(0.0, 1.0);
  std::vector<double> e(n);
  double prev = sigma * w(*rng);
  for (size_t i = 0; i < n; ++i) {
    prev = i == 0 ? prev : phi * prev + std::sqrt(1.0 - phi * phi) * sigma * w(*rng);
    e[i] = prev;
  }
  return e;
}

// Exact standard deviation of the mean of k consecutive samples of that AR(1) process:
// Var = sigma^2 / k^2 (k + 2 sum_{j=1}^{k-1} (k - j) phi^j)
//     = sigma^2 / k ((1 + phi) / (1 - phi) - 2 phi (1 - phi^k) / (k (1 - phi)^2)).
double ExactStdOfMean(size_t k, double sigma, double phi) {
  const double dk = static_cast<double>(k);
  if (phi == 0.0) return sigma / std::sqrt(dk);
  const double f = (1.0 + phi) / (1.0 - phi) -
                   2.0 * phi * (1.0 - std::pow(phi, dk)) / (dk * (1.0 - phi) * (1.0 - phi));
  return sigma * std::sqrt(f / dk);
}

double MeanFrom(const std::vector<double>& x, size_t begin) {
  double s = 0.0;
  for (size_t i = begin; i < x.size(); ++i) s += x[i];
  return s / static_cast<double>(x.size() - begin);
}

TEST_CASE("The transient rule cuts where the remaining bias is a tenth of u", "[stats][settle]") {
  // x_i = A exp(-i / tau) + e_i, white e of sigma 1, n = 6000, tau = 200, A = 20. With the
  // true parameters the bias of the mean of x_d..x_{n-1} is
  //   b(d) = A exp(-d / tau) (1 - exp(-(n - d) / tau)) / ((1 - exp(-1 / tau)) (n - d))
  // and u(d) = 1 / sqrt(n - d); b(d) = 0.1 u(d) at d = 1274 (solved below by bisection).
  const double amplitude = 20.0, tau = 200.0;
  const size_t n = 6000;
  auto ratio = [&](double d) {
    const double kept = n - d;
    return amplitude * std::exp(-d / tau) * (1.0 - std::exp(-kept / tau)) /
           ((1.0 - std::exp(-1.0 / tau)) * kept) * std::sqrt(kept);
  };
  double lo = 0.0, hi = n / 2.0;
  for (int i = 0; i < 60; ++i) (ratio(0.5 * (lo + hi)) > 0.1 ? lo : hi) = 0.5 * (lo + hi);
  const double d_true = lo;
  CHECK(d_true == Approx(1274).margin(1.0));
  for (int seed = 0; seed < 20; ++seed) {
    std::mt19937_64 rng(seed);
    std::vector<double> x = Noise(n, 1.0, 0.0, &rng);
    for (size_t i = 0; i < n; ++i) x[i] += amplitude * std::exp(-double(i) / tau);
    const SettleResult r = DetectSettleTransient(x.data(), n);
    REQUIRE(r.fitted);
    CHECK(r.significant);
    CHECK(r.tau_samples == Approx(tau).epsilon(0.15));
    CHECK(r.amplitude == Approx(amplitude).epsilon(0.1));
    // The cut follows the fitted tau: within 15 % of the true cut.
    CHECK(double(r.samples) == Approx(d_true).epsilon(0.15));
    CHECK_FALSE(r.at_limit);
    CHECK(r.bias_over_u_kept <= 0.1);
  }
}

TEST_CASE("The transient rule keeps a stationary series whole", "[stats][settle]") {
  for (double phi : {0.0, 0.9}) {
    for (int seed = 0; seed < 10; ++seed) {
      std::mt19937_64 rng(100 + seed);
      const std::vector<double> x = Noise(5000, 1.0, phi, &rng);
      const SettleResult r = DetectSettleTransient(x.data(), x.size());
      CHECK(r.samples <= 500);
    }
  }
}

TEST_CASE("The transient rule says why it has no fit", "[stats][settle]") {
  const double few[5] = {5, 4, 3, 2, 1};
  SettleResult r = DetectSettleTransient(few, 5);
  CHECK_FALSE(r.fitted);
  CHECK(r.samples == 0);
  CHECK(r.note == "5 observations: at least 20 are needed to fit a transient");
  const std::vector<double> constant(100, 3.25);
  r = DetectSettleTransient(constant.data(), constant.size());
  CHECK_FALSE(r.fitted);
  CHECK(r.note == "constant (or non-finite) series: no transient to fit");
  SettleOptions bad;
  bad.max_bias_fraction = 0.0;
  std::string why;
  CHECK_FALSE(bad.IsValid(&why));
  CHECK(why == "settle max_bias_fraction must be in (0, 1]");
}

TEST_CASE("Settle coverage: the mean after the cut lies within 2 u of the truth",
          "[stats][settle][slow]") {
  // Issue #21 part 3 acceptance. A tag at 10 Hz for 600 s (n = 6000); exponential
  // transients of tau 2, 10, 30 s (20, 100, 300 samples) and amplitude 0.5, 2, 5, 20 sigma
  // on white noise and on AR(1) noise with phi = 0.9. Truth: 0. Asserted: |mean after the
  // cut| <= 2 u in >= 90 % of the sessions, u the exact standard deviation of the mean of
  // the kept samples (closed form above). 200 sessions per case, not 30: even the true
  // mean is within 2 u with probability 0.954 only, so 27 of 30 fails by chance in 8 % of
  // cases (about 2 of these 24) whatever the cut; 180 of 200 in 0.02 %. The first 30
  // sessions of each case are also counted (printed). With u = std_of_mean_autocorr of the
  // kept samples (Zhang) the bar is 90 % on white noise and 85 % at phi = 0.9, where
  // Zhang's u itself covers about 93 %; with u = u_mean (the report's) the bar is 90 %
  // everywhere. Set METRO_PRINT_SETTLE_TABLE=1 to print the table.
  const bool print = std::getenv("METRO_PRINT_SETTLE_TABLE") != nullptr;
  const size_t n = 6000;
  const double sigma = 1.0;
  const int sessions = 200;
  if (print) {
    std::printf("%5s %6s %5s | %9s %9s %9s %9s | %9s %9s | %10s %8s\n", "phi", "tau_s", "A",
                "cut_exact", "cut_zhang", "nocut", "mser5", "cut30", "mser5_30", "mean_cut_s",
                "at_limit");
  }
  int seed = 1000;
  for (double phi : {0.0, 0.9}) {
    for (double tau_s : {2.0, 10.0, 30.0}) {
      for (double a_sigma : {0.5, 2.0, 5.0, 20.0}) {
        int in_exact = 0, in_zhang = 0, in_umean = 0, in_nocut = 0, in_mser = 0, at_limit = 0;
        int in_exact30 = 0, in_mser30 = 0;
        double cut_sum_s = 0.0;
        for (int k = 0; k < sessions; ++k) {
          std::mt19937_64 rng(seed++);
          std::vector<double> x = Noise(n, sigma, phi, &rng);
          const double tau = tau_s * 10.0;
          for (size_t i = 0; i < n; ++i) x[i] += a_sigma * sigma * std::exp(-double(i) / tau);
          const SettleResult r = DetectSettleTransient(x.data(), n);
          at_limit += r.at_limit ? 1 : 0;
          cut_sum_s += 0.1 * static_cast<double>(r.samples);
          const double m = MeanFrom(x, r.samples);
          const bool covered = std::abs(m) <= 2.0 * ExactStdOfMean(n - r.samples, sigma, phi);
          in_exact += covered ? 1 : 0;
          in_exact30 += covered && k < 30 ? 1 : 0;
          const TypeAResult ta = EvaluateTypeA(x.data() + r.samples, n - r.samples).value();
          in_zhang += std::abs(m) <= 2.0 * ta.std_of_mean_autocorr ? 1 : 0;
          in_umean += std::abs(m) <= 2.0 * ta.u_mean ? 1 : 0;
          in_nocut += std::abs(MeanFrom(x, 0)) <= 2.0 * ExactStdOfMean(n, sigma, phi) ? 1 : 0;
          const size_t mser = DetectSettleMser5(x.data(), n).samples;
          const bool mser_covered =
              std::abs(MeanFrom(x, mser)) <= 2.0 * ExactStdOfMean(n - mser, sigma, phi);
          in_mser += mser_covered ? 1 : 0;
          in_mser30 += mser_covered && k < 30 ? 1 : 0;
        }
        if (print) {
          std::printf(
              "%5.1f %6.0f %5.1f | %5d/200 %5d/200 %5d/200 %5d/200 | %6d/30 %6d/30 | %10.1f %8d\n",
              phi, tau_s, a_sigma, in_exact, in_zhang, in_nocut, in_mser, in_exact30, in_mser30,
              cut_sum_s / sessions, at_limit);
        }
        INFO("phi " << phi << ", tau " << tau_s << " s, amplitude " << a_sigma << " sigma");
        CHECK(in_exact >= 180);
        CHECK(in_zhang >= (phi == 0.0 ? 180 : 170));
        // The issue's own bar: within 2 u_mean (the report's u of the mean) in >= 90 %.
        CHECK(in_umean >= 180);
        // A cut that stops at half the record carries a warning (at_limit); rare here.
        CHECK(at_limit <= sessions / 20);
      }
    }
  }
}

TEST_CASE("Settle on stationary records drops at most 10 %", "[stats][settle][slow]") {
  // 30 sessions each of white and AR(1) phi = 0.9 noise, n = 6000, no transient.
  const bool print = std::getenv("METRO_PRINT_SETTLE_TABLE") != nullptr;
  int seed = 5000;
  for (double phi : {0.0, 0.9}) {
    size_t worst = 0, total = 0;
    int cut_any = 0;
    for (int k = 0; k < 30; ++k) {
      std::mt19937_64 rng(seed++);
      const std::vector<double> x = Noise(6000, 1.0, phi, &rng);
      const SettleResult r = DetectSettleTransient(x.data(), x.size());
      worst = std::max(worst, r.samples);
      total += r.samples;
      cut_any += r.samples > 0 ? 1 : 0;
      CHECK(r.samples <= 600);
    }
    if (print) {
      std::printf("stationary phi %.1f: sessions cut %d/30, mean kept %.4f, worst kept %.4f\n", phi,
                  cut_any, 1.0 - double(total) / (30.0 * 6000.0), 1.0 - double(worst) / 6000.0);
    }
  }
}

}  // namespace
}  // namespace metro
