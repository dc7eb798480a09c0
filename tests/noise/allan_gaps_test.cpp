// ComputeAllanWithGaps (NIST SP 1065 5.15 gap handling) against an independent reference:
// the frequency-average form of the estimators, written from the definitions, with every
// average that contains a missing sample left out; and against simulations with known truth.
#include <algorithm>
#include <atomic>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <mutex>
#include <random>
#include <stdexcept>
#include <vector>

#include "metro/noise/allan.hpp"
#include "noise/allan_internal.hpp"
#include "noise/noise_simulation.hpp"

namespace metro {
namespace {

// Average of y[i, i + m), or NaN when one of them is missing.
double Average(const std::vector<double>& y, const std::vector<uint8_t>& present, int64_t i,
               int64_t m) {
  double s = 0.0;
  for (int64_t k = i; k < i + m; ++k) {
    if (!present[static_cast<size_t>(k)]) return std::nan("");
    s += y[static_cast<size_t>(k)];
  }
  return s / static_cast<double>(m);
}

struct Reference {
  double dev = 0.0;
  int64_t terms = 0;
};

// SP 1065 5.2.4 (overlapping Allan) and 5.2.9 (overlapping Hadamard) from frequency averages:
// AVAR = <(ybar_{i+m} - ybar_i)^2> / 2, HVAR = <(ybar_{i+2m} - 2 ybar_{i+m} + ybar_i)^2> / 6,
// the mean over the terms whose averages are all complete.
Reference OverlappingReference(const std::vector<double>& y, const std::vector<uint8_t>& present,
                               int64_t m, bool hadamard) {
  const int64_t n = static_cast<int64_t>(y.size());
  const int64_t span = (hadamard ? 3 : 2) * m;
  double sum = 0.0;
  Reference r;
  for (int64_t i = 0; i + span <= n; ++i) {
    const double a = Average(y, present, i, m);
    const double b = Average(y, present, i + m, m);
    const double c = hadamard ? Average(y, present, i + 2 * m, m) : 0.0;
    if (std::isnan(a) || std::isnan(b) || std::isnan(c)) continue;
    const double d = hadamard ? (c - 2.0 * b) + a : b - a;
    sum += d * d;
    ++r.terms;
  }
  r.dev = std::sqrt(sum / ((hadamard ? 6.0 : 2.0) * static_cast<double>(r.terms)));
  return r;
}

// SP 1065 5.2.5 (modified Allan) from frequency samples: the term at j is
// (1/m) sum_{i=j}^{j+m-1} (ybar_{i+m} - ybar_i), MVAR = <term^2> / 2.
Reference ModifiedReference(const std::vector<double>& y, const std::vector<uint8_t>& present,
                            int64_t m) {
  const int64_t n = static_cast<int64_t>(y.size());
  double sum = 0.0;
  Reference r;
  for (int64_t j = 0; j + 3 * m - 1 <= n; ++j) {
    double inner = 0.0;
    bool complete = true;
    for (int64_t i = j; i < j + m && complete; ++i) {
      const double a = Average(y, present, i, m);
      const double b = Average(y, present, i + m, m);
      complete = !std::isnan(a) && !std::isnan(b);
      inner += b - a;
    }
    if (!complete) continue;
    inner /= static_cast<double>(m);
    sum += inner * inner;
    ++r.terms;
  }
  r.dev = std::sqrt(sum / (2.0 * static_cast<double>(r.terms)));
  return r;
}

// n samples, a fraction `loss` of them missing at random, plus a burst of 25.
std::vector<uint8_t> LossPattern(size_t n, uint64_t seed, double loss = 0.05) {
  std::mt19937_64 rng(seed);
  std::bernoulli_distribution lost(loss);
  std::vector<uint8_t> present(n, 1);
  for (auto& p : present) p = lost(rng) ? 0 : 1;
  for (size_t k = n / 3; k < n / 3 + 25 && k < n; ++k) present[k] = 0;
  return present;
}

TEST_CASE("Allan through gaps equals the frequency-average definition with gaps left out",
          "[noise][allan][gaps]") {
  const size_t n = 600;
  std::vector<double> y = testing::WhiteNoise(n, 0.3, 11);
  for (size_t k = 0; k < n; ++k) y[k] += 2.0 + 1e-3 * static_cast<double>(k);  // bias + drift
  const std::vector<uint8_t> present = LossPattern(n, 12);
  const double tau0 = 0.1;
  for (AllanEstimator e : {AllanEstimator::kOadev, AllanEstimator::kOhdev, AllanEstimator::kMdev}) {
    AllanOptions o;
    o.estimator = e;
    o.m_list = {1, 2, 3, 5, 8};
    Result<AllanCurve> c = ComputeAllanWithGaps(y, present, tau0, o);
    REQUIRE(c.ok());
    REQUIRE(c.value().m == std::vector<int64_t>{1, 2, 3, 5, 8});
    int64_t missing = 0;
    for (uint8_t p : present) missing += p ? 0 : 1;
    CHECK(c.value().n_missing_samples == missing);
    for (size_t k = 0; k < c.value().m.size(); ++k) {
      const int64_t m = c.value().m[k];
      const Reference r = e == AllanEstimator::kMdev
                              ? ModifiedReference(y, present, m)
                              : OverlappingReference(y, present, m, e == AllanEstimator::kOhdev);
      INFO(AllanEstimatorName(e) << " m = " << m);
      CHECK(c.value().n_terms[k] == r.terms);
      CHECK(c.value().n_terms_gap_free[k] == AllanTermCount(e, static_cast<int64_t>(n) + 1, m));
      CHECK(c.value().n_terms[k] < c.value().n_terms_gap_free[k]);
      // The rate unit is whatever y's is; tau0 only scales tau.
      CHECK(c.value().dev[k] == Approx(r.dev).epsilon(1e-9));
      CHECK(c.value().tau_s[k] == Approx(static_cast<double>(m) * tau0));
    }
  }
}

TEST_CASE("Allan through gaps without gaps is ComputeAllan", "[noise][allan][gaps]") {
  const std::vector<double> y = testing::WhiteNoise(5000, 1.0, 3);
  const std::vector<uint8_t> present(y.size(), 1);
  for (AllanEstimator e : {AllanEstimator::kOadev, AllanEstimator::kMdev, AllanEstimator::kOhdev,
                           AllanEstimator::kAdev, AllanEstimator::kHdev}) {
    AllanOptions o;
    o.estimator = e;
    Result<AllanCurve> a = ComputeAllan(y, 0.01, o);
    Result<AllanCurve> g = ComputeAllanWithGaps(y, present, 0.01, o);
    REQUIRE(a.ok());
    REQUIRE(g.ok());
    REQUIRE(a.value().m == g.value().m);
    CHECK(g.value().n_terms == a.value().n_terms);
    CHECK(g.value().alpha == a.value().alpha);
    for (size_t k = 0; k < a.value().size(); ++k) {
      INFO(AllanEstimatorName(e) << " m = " << a.value().m[k]);
      CHECK(g.value().dev[k] == Approx(a.value().dev[k]).epsilon(1e-10));
      CHECK(g.value().edf[k] == Approx(a.value().edf[k]).epsilon(1e-12));
    }
  }
}

TEST_CASE("Allan through gaps: the confidence intervals keep their coverage",
          "[noise][allan][gaps]") {
  // White rate noise of N = 1 (AVAR = N^2 / tau exactly, tau0 = 1 s) with random loss and a
  // burst of 25: the 68.3 % interval at each tau must hold the true deviation about 68 % of
  // the time, with the EDF of the runs of terms that remain. 300 records: the binomial
  // 3-sigma band around 0.683 is +-0.081. At 5 % loss a 2m = 32 span is complete with
  // probability 0.95^32 = 0.19, so the valid terms come in many short runs.
  const int runs = 300;
  const std::vector<int64_t> m = {1, 4, 16, 32};
  for (double loss : {0.02, 0.05}) {
    std::vector<int> covered(m.size(), 0), estimated(m.size(), 0);
    for (int r = 0; r < runs; ++r) {
      const std::vector<double> y = testing::WhiteNoise(4000, 1.0, 1000 + r);
      AllanOptions o;
      o.m_list = m;
      Result<AllanCurve> c = ComputeAllanWithGaps(y, LossPattern(y.size(), 5000 + r, loss), 1.0, o);
      REQUIRE(c.ok());
      for (size_t k = 0; k < m.size(); ++k) {
        const auto at = std::find(c.value().m.begin(), c.value().m.end(), m[k]);
        if (at == c.value().m.end()) continue;
        const size_t i = static_cast<size_t>(at - c.value().m.begin());
        ++estimated[k];
        const double truth = 1.0 / std::sqrt(static_cast<double>(m[k]));
        if (c.value().ci_low[i] <= truth && truth <= c.value().ci_high[i]) ++covered[k];
      }
    }
    for (size_t k = 0; k < m.size(); ++k) {
      INFO("loss " << loss << ", m = " << m[k] << ": covered " << covered[k] << " of "
                   << estimated[k]);
      REQUIRE(estimated[k] == runs);
      CHECK(covered[k] / static_cast<double>(runs) == Approx(0.683).margin(0.081));
    }
  }
}

TEST_CASE("Allan through gaps refuses what it cannot estimate", "[noise][allan][gaps]") {
  std::vector<double> y(40, 1.0);
  std::vector<uint8_t> present(40, 0);
  present[3] = 1;
  Result<AllanCurve> c = ComputeAllanWithGaps(y, present, 1.0);
  REQUIRE_FALSE(c.ok());
  CHECK(c.error().message == "1 of 40 samples are present: at least 2 are needed");
  // Every other sample missing: no term of any tau is complete.
  for (size_t k = 0; k < present.size(); ++k) present[k] = k % 2 == 0 ? 1 : 0;
  c = ComputeAllanWithGaps(y, present, 1.0);
  REQUIRE_FALSE(c.ok());
  CHECK(c.error().message ==
        "every oadev term at every tau reads a missing sample (20 of 40 samples missing)");
  present.assign(40, 1);
  y[7] = std::nan("");
  c = ComputeAllanWithGaps(y, present, 1.0);
  REQUIRE_FALSE(c.ok());
  CHECK(c.error().message == "rate sample 7 (0-based) is not finite (nan)");
  // A missing sample's value is never read.
  present[7] = 0;
  CHECK(ComputeAllanWithGaps(y, present, 1.0).ok());
}

TEST_CASE("An exception in an Allan worker reaches the caller", "[noise][allan]") {
  // The module's tasks run on core/parallel.hpp: a throwing task used to end the process from
  // a std::thread; now the caller gets it after the other threads stop.
  std::atomic<int> ran{0};
  CHECK_THROWS_AS(internal::RunAllanTasks(4, 64,
                                          [&](int64_t t) {
                                            ++ran;
                                            if (t == 5) throw std::runtime_error("task 5");
                                          }),
                  std::runtime_error);
  CHECK(ran.load() >= 1);
  int64_t sum = 0;
  std::mutex mutex;
  internal::RunAllanTasks(3, 100, [&](int64_t t) {
    std::lock_guard<std::mutex> lock(mutex);
    sum += t;
  });
  CHECK(sum == 4950);
}

}  // namespace
}  // namespace metro
