// Phase integration over fixed blocks on several threads (allan.cpp IntegratePhase, used by
// PhaseFromRate and ComputeAllan) and overlapping sums over fixed slices: accuracy against
// long double, errors found in any block, curves that do not depend on the thread count.
#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <vector>

#include "metro/noise/allan.hpp"
#include "noise/allan_internal.hpp"

namespace metro {
namespace {

// 3.3 blocks of 2^16 samples of a large gyro bias plus white noise.
std::vector<double> BiasedRate(size_t n, double bias) {
  std::vector<double> y(n);
  uint64_t s = 777;
  for (double& v : y) {
    s = s * 6364136223846793005ULL + 1442695040888963407ULL;
    v = bias + (static_cast<double>(s >> 11) * 0x1.0p-53 - 0.5);
  }
  return y;
}

TEST_CASE("Phase from rate is exact to a few ulp across blocks", "[noise]") {
  const double tau0_s = 0.01;
  const std::vector<double> y = BiasedRate(216000, 1234.5);
  double mean = 0.0;
  const std::vector<double> x = PhaseFromRate(y, tau0_s, &mean);
  // Reference: mean and running sum in long double (64-bit mantissa).
  long double sum = 0.0L;
  for (double v : y) sum += v;
  const long double exact_mean = sum / y.size();
  // Plain sums of 2^14 values per lane: relative error below 2^14 eps (Higham 4.2) = 1.8e-12.
  CHECK(mean == Approx(static_cast<double>(exact_mean)).epsilon(1.8e-12));
  REQUIRE(x.size() == y.size() + 1);
  CHECK(x[0] == 0.0);
  long double exact = 0.0L;
  double worst = 0.0;
  double largest = 0.0;
  for (size_t k = 0; k < y.size(); ++k) {
    // The same step as the code: (y_k - mean) tau0 in double, then summed exactly.
    exact += static_cast<long double>((y[k] - mean) * tau0_s);
    worst = std::max(worst, std::fabs(x[k + 1] - static_cast<double>(exact)));
    largest = std::max(largest, std::fabs(x[k + 1]));
  }
  // A few ulp of the largest |x|.
  CHECK(worst <= 4.0 * std::numeric_limits<double>::epsilon() * largest);
}

TEST_CASE("Non-finite rate samples are found in any block", "[noise]") {
  std::vector<double> y = BiasedRate(300000, 0.0);
  y[250001] = -std::numeric_limits<double>::infinity();
  y[140000] = std::nan("");  // The first one, in the third block.
  AllanOptions options;
  options.threads = 2;
  const Result<AllanCurve> r = ComputeAllan(y, 0.01, options);
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().message == "rate sample 140000 (0-based) is not finite (nan)");
  y[140000] = 0.0;
  const Result<AllanCurve> r2 = ComputeAllan(y, 0.01, options);
  REQUIRE_FALSE(r2.ok());
  CHECK(r2.error().message == "rate sample 250001 (0-based) is not finite (-inf)");
}

TEST_CASE("Allan curve and noise types do not depend on the thread count", "[noise]") {
  const std::vector<double> y = BiasedRate(300000, 15.0);
  AllanOptions options;
  options.threads = 1;
  const Result<AllanCurve> one = ComputeAllan(y, 0.01, options);
  options.threads = 2;
  const Result<AllanCurve> two = ComputeAllan(y, 0.01, options);
  options.threads = 3;
  const Result<AllanCurve> three = ComputeAllan(y, 0.01, options);
  REQUIRE(one.ok());
  REQUIRE(two.ok());
  REQUIRE(three.ok());
  CHECK(one.value().rate_mean == two.value().rate_mean);
  CHECK(one.value().rate_mean == three.value().rate_mean);
  REQUIRE(one.value().size() == two.value().size());
  REQUIRE(one.value().size() == three.value().size());
  for (size_t k = 0; k < one.value().size(); ++k) {
    // Fixed blocks for the phase and fixed slices for the sums: bit-identical.
    CHECK(two.value().dev[k] == one.value().dev[k]);
    CHECK(three.value().dev[k] == one.value().dev[k]);
    CHECK(two.value().alpha[k] == one.value().alpha[k]);
    CHECK(three.value().alpha[k] == one.value().alpha[k]);
    CHECK(two.value().alpha_source[k] == one.value().alpha_source[k]);
    CHECK(three.value().alpha_source[k] == one.value().alpha_source[k]);
  }
  // White rate noise: alpha = 0 identified at the small taus.
  CHECK(one.value().alpha[0] == 0);
  CHECK(one.value().alpha_source[0] == AlphaSource::kLag1Acf);
}

TEST_CASE("In-place Allan computation equals ComputeAllan bit for bit", "[noise]") {
  const std::vector<double> y = BiasedRate(300001, 42.0);
  for (int threads : {1, 2}) {
    for (AllanEstimator e : {AllanEstimator::kOadev, AllanEstimator::kMdev}) {
      INFO("threads " << threads << ", " << AllanEstimatorName(e));
      AllanOptions options;
      options.threads = threads;
      options.estimator = e;
      const Result<AllanCurve> reference = ComputeAllan(y, 0.01, options);
      std::vector<double> buffer(y.size() + 1);
      std::copy(y.begin(), y.end(), buffer.begin() + 1);
      const Result<AllanCurve> in_place = internal::ComputeAllanInPlace(&buffer, 0.01, options);
      REQUIRE(reference.ok());
      REQUIRE(in_place.ok());
      CHECK(in_place.value().rate_mean == reference.value().rate_mean);
      CHECK(in_place.value().dev == reference.value().dev);
      CHECK(in_place.value().ci_low == reference.value().ci_low);
      CHECK(in_place.value().alpha == reference.value().alpha);
      // The buffer now holds the phase.
      CHECK(buffer == PhaseFromRate(y, 0.01));
    }
  }
  std::vector<double> bad(1001, 1.0);
  bad[501] = std::nan("");  // Sample 500.
  const Result<AllanCurve> r = internal::ComputeAllanInPlace(&bad, 0.01);
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().message == "rate sample 500 (0-based) is not finite (nan)");
}

}  // namespace
}  // namespace metro
