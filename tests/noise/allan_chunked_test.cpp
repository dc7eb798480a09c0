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

ChunkReader ReaderOf(const SpillColumn<double>& column) {
  return
      [&column](size_t begin, size_t count, double* out) { return column.Read(begin, count, out); };
}

Status Spill(const std::vector<double>& rate, SpillColumn<double>* column) {
  if (Status s = column->Open(); !s.ok()) return s;
  if (Status s = column->Append(rate.data(), rate.size()); !s.ok()) return s;
  return column->Finish();
}

TEST_CASE("Allan in chunks equals ComputeAllan", "[allan][stream]") {
  // 2^19 + 3 samples: far offsets (> 2^16) and a record that is not a whole number of blocks.
  const std::vector<double> rate = Gyro((size_t{1} << 19) + 3, 21);
  SpillColumn<double> column;
  REQUIRE(Spill(rate, &column).ok());
  for (AllanEstimator estimator : {AllanEstimator::kOadev, AllanEstimator::kOhdev}) {
    AllanOptions options;
    options.estimator = estimator;
    INFO(AllanEstimatorName(estimator));
    auto memory = ComputeAllan(rate, 0.0025, options);
    auto chunked =
        ComputeAllanChunked(ReaderOf(column), static_cast<int64_t>(rate.size()), 0.0025, options);
    REQUIRE(memory.ok());
    REQUIRE(chunked.ok());
    RequireSameCurve(memory.value(), chunked.value());
  }
}

TEST_CASE("mdev, adev and hdev in chunks are ComputeAllan's bits", "[allan][stream]") {
  // 1.5 M samples: mdev's inner sums restart every max(2^16, 16 m) terms (several segments at
  // every m up to 32768), from the sweep's window where 3 m <= 2^16 and from cursors beyond;
  // the non-overlapping terms fall on chunk boundaries and between them.
  const std::vector<double> rate = Gyro(1500007, 8);
  SpillColumn<double> column;
  REQUIRE(Spill(rate, &column).ok());
  for (AllanEstimator estimator :
       {AllanEstimator::kMdev, AllanEstimator::kAdev, AllanEstimator::kHdev}) {
    INFO(AllanEstimatorName(estimator));
    AllanOptions options;
    options.estimator = estimator;
    options.threads = 3;
    auto memory = ComputeAllan(rate, 0.0025, options);
    auto chunked =
        ComputeAllanChunked(ReaderOf(column), static_cast<int64_t>(rate.size()), 0.0025, options);
    REQUIRE(memory.ok());
    REQUIRE(chunked.ok());
    REQUIRE(chunked.value().m.back() > 32768);
    RequireSameCurve(memory.value(), chunked.value());
    CHECK(chunked.value().dev == memory.value().dev);
  }
}

TEST_CASE("mdev does not depend on the thread count", "[allan]") {
  // Its sum is a total per fixed segment, added in order (allan.cpp ModifiedSum).
  const std::vector<double> rate = Gyro(400000, 3);
  AllanOptions options;
  options.estimator = AllanEstimator::kMdev;
  options.threads = 1;
  auto one = ComputeAllan(rate, 0.01, options);
  options.threads = 3;
  auto three = ComputeAllan(rate, 0.01, options);
  REQUIRE(one.ok());
  REQUIRE(three.ok());
  CHECK(one.value().dev == three.value().dev);
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
