// The streaming mode's Allan curve (ComputeAllanChunked, issue #38 step 2) against
// ComputeAllan: the same phase bits, the sums in another order, so every deviation within
// 1e-12 relative and everything else (m, terms, alpha, EDF inputs) identical.
#include <catch2/catch.hpp>
#include <cmath>
#include <random>
#include <vector>

#include "metro/core/spill_file.hpp"
#include "metro/noise/allan.hpp"

namespace metro {
namespace {

std::vector<double> Gyro(size_t n, uint64_t seed) {
  // White rate noise, a rate random walk and an offset: the terms a gyro shows.
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal;
  std::vector<double> x(n);
  double walk = 0.0;
  for (size_t i = 0; i < n; ++i) {
    walk += 1e-4 * normal(rng);
    x[i] = 0.3 + 0.05 * normal(rng) + walk;
  }
  return x;
}

void RequireSameCurve(const AllanCurve& a, const AllanCurve& b) {
  REQUIRE(a.m == b.m);
  CHECK(a.rate_mean == b.rate_mean);
  CHECK(a.n_terms == b.n_terms);
  CHECK(a.alpha == b.alpha);
  for (size_t k = 0; k < a.m.size(); ++k) {
    INFO("m = " << a.m[k]);
    CHECK(b.dev[k] == Approx(a.dev[k]).epsilon(1e-12));
    CHECK(b.edf[k] == Approx(a.edf[k]).epsilon(1e-12));
    CHECK(b.ci_low[k] == Approx(a.ci_low[k]).epsilon(1e-12));
    CHECK(b.ci_high[k] == Approx(a.ci_high[k]).epsilon(1e-12));
  }
}

}  // namespace

TEST_CASE("Allan in chunks equals ComputeAllan", "[allan][stream]") {
  // 2^19 + 3 samples: far offsets (> 2^16) and a record that is not a whole number of blocks.
  const std::vector<double> rate = Gyro((size_t{1} << 19) + 3, 21);
  SpillColumn<double> column;
  REQUIRE(column.Open().ok());
  REQUIRE(column.Append(rate.data(), rate.size()).ok());
  REQUIRE(column.Finish().ok());
  const ChunkReader read = [&column](size_t begin, size_t count, double* out) {
    return column.Read(begin, count, out);
  };
  for (AllanEstimator estimator : {AllanEstimator::kOadev, AllanEstimator::kOhdev}) {
    AllanOptions options;
    options.estimator = estimator;
    INFO(AllanEstimatorName(estimator));
    auto memory = ComputeAllan(rate, 0.0025, options);
    auto chunked = ComputeAllanChunked(read, static_cast<int64_t>(rate.size()), 0.0025, options);
    REQUIRE(memory.ok());
    REQUIRE(chunked.ok());
    RequireSameCurve(memory.value(), chunked.value());
  }
  SECTION("estimators the streaming mode does not have are refused by name") {
    AllanOptions options;
    options.estimator = AllanEstimator::kMdev;
    auto chunked = ComputeAllanChunked(read, static_cast<int64_t>(rate.size()), 0.0025, options);
    REQUIRE_FALSE(chunked.ok());
    CHECK_THAT(chunked.error().message, Catch::Contains("not available in streaming mode"));
  }
}

TEST_CASE("Allan in chunks names a non-finite sample", "[allan][stream]") {
  std::vector<double> rate = Gyro(40000, 5);
  rate[31234] = std::nan("");
  const ChunkReader read = [&rate](size_t begin, size_t count, double* out) {
    std::copy(rate.begin() + static_cast<ptrdiff_t>(begin),
              rate.begin() + static_cast<ptrdiff_t>(begin + count), out);
    return Status::Ok();
  };
  auto memory = ComputeAllan(rate, 0.01);
  auto chunked = ComputeAllanChunked(read, static_cast<int64_t>(rate.size()), 0.01);
  REQUIRE_FALSE(memory.ok());
  REQUIRE_FALSE(chunked.ok());
  CHECK(chunked.error().message == memory.error().message);
}

}  // namespace metro
