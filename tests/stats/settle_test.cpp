#include "metro/stats/settle.hpp"

#include <catch2/catch.hpp>
#include <cmath>
#include <random>
#include <vector>

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

}  // namespace
}  // namespace metro
