// The streaming mode's Type A (EvaluateTypeAChunked, issue #38 step 2) against the in-memory
// evaluation: the same sums in the same blocks and lanes, so every number must be equal to
// the last bit, read back through a spill file in chunks of 2^16 values.
#include <catch2/catch.hpp>
#include <cmath>
#include <random>
#include <vector>

#include "metro/core/spill_file.hpp"
#include "metro/stats/spectral_mean.hpp"
#include "metro/stats/type_a.hpp"

namespace metro {
namespace {

struct Spilled {
  SpillColumn<double> column;
  ChunkReader reader;
};

void Spill(const std::vector<double>& x, Spilled* out) {
  REQUIRE(out->column.Open().ok());
  // Appended in uneven pieces, as the loader appends parsed blocks.
  for (size_t at = 0; at < x.size(); at += 7777) {
    const size_t count = std::min<size_t>(7777, x.size() - at);
    REQUIRE(out->column.Append(x.data() + at, count).ok());
  }
  REQUIRE(out->column.Finish().ok());
  REQUIRE(out->column.size() == x.size());
  out->reader = [col = &out->column](size_t begin, size_t count, double* dst) {
    return col->Read(begin, count, dst);
  };
}

void RequireSame(const TypeAResult& a, const TypeAResult& b) {
  CHECK(a.n == b.n);
  CHECK(a.mean == b.mean);
  CHECK(a.variance == b.variance);
  CHECK(a.std_of_mean == b.std_of_mean);
  CHECK(a.autocorr_computed == b.autocorr_computed);
  CHECK(a.n_eff == b.n_eff);
  CHECK(a.cutoff_lag == b.cutoff_lag);
  CHECK(a.rho1 == b.rho1);
  CHECK(a.std_of_mean_autocorr == b.std_of_mean_autocorr);
  CHECK(a.u_mean_available == b.u_mean_available);
  CHECK(a.u_mean == b.u_mean);
  CHECK(a.u_mean_dof == b.u_mean_dof);
  CHECK(a.u_mean_method == b.u_mean_method);
  CHECK(a.ar_order == b.ar_order);
  CHECK(a.u_mean_batch == b.u_mean_batch);
  CHECK(a.drift_detected == b.drift_detected);
  CHECK(a.u_mean_note == b.u_mean_note);
}

std::vector<double> Ar1(size_t n, double phi, double offset, double trend, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal;
  std::vector<double> x(n);
  double e = 0.0;
  for (size_t i = 0; i < n; ++i) {
    e = phi * e + normal(rng);
    x[i] = offset + 0.01 * e + trend * static_cast<double>(i);
  }
  return x;
}

}  // namespace

TEST_CASE("Type A in chunks equals the in-memory evaluation bit for bit", "[type_a][stream]") {
  struct Case {
    const char* name;
    std::vector<double> x;
  };
  const std::vector<Case> cases = {
      {"white noise about 9.81, 300000 values (5 chunks)", Ar1(300000, 0.0, 9.81, 0.0, 1)},
      {"AR(1) phi = 0.9, odd length 200003", Ar1(200003, 0.9, -0.2, 0.0, 2)},
      {"white noise with a drift (batch means)", Ar1(150001, 0.0, 1.0, 2e-7, 3)},
      {"AR(1) phi = 0.99 (cut-off beyond the direct lags)", Ar1(131075, 0.99, 0.0, 0.0, 4)},
      {"a random walk (the AR fit needs the lattice: read in for it)",
       Ar1(100000, 1.0, 0.0, 0.0, 7)},
      {"short: 9 values", Ar1(9, 0.5, 3.0, 0.0, 5)},
      {"short: 150 values", Ar1(150, 0.3, 3.0, 0.0, 6)},
  };
  for (const Case& c : cases) {
    INFO(c.name);
    Spilled spilled;
    Spill(c.x, &spilled);
    auto memory = EvaluateTypeA(c.x.data(), c.x.size());
    auto chunked = EvaluateTypeAChunked(spilled.reader, c.x.size());
    REQUIRE(memory.ok());
    REQUIRE(chunked.ok());
    RequireSame(memory.value(), chunked.value());
  }
}

TEST_CASE("Type A in chunks: Willink's digitized rules read the extremes in chunks",
          "[type_a][stream]") {
  std::vector<double> x(70001, 2.0);
  for (size_t i = 0; i < x.size(); i += 3) x[i] = 2.5;  // A spread of one step of 0.5.
  Spilled spilled;
  Spill(x, &spilled);
  TypeAOptions options;
  options.quantization_step = 0.5;
  auto memory = EvaluateTypeA(x.data(), x.size(), options);
  auto chunked = EvaluateTypeAChunked(spilled.reader, x.size(), options);
  REQUIRE(memory.ok());
  REQUIRE(chunked.ok());
  CHECK(chunked.value().u_mean_method == kUMeanDigitized);
  RequireSame(memory.value(), chunked.value());
}

TEST_CASE("AR spectral u in chunks: equal, or a lattice fallback said by name",
          "[spectral_mean][stream]") {
  // A random walk: sum phi -> 1, the case where the lag products hand over to the lattice.
  std::mt19937_64 rng(9);
  std::normal_distribution<double> normal;
  std::vector<double> walk(100000);
  double v = 0.0;
  for (double& w : walk) w = (v += normal(rng));
  for (const std::vector<double>* x : {&walk}) {
    Spilled spilled;
    Spill(*x, &spilled);
    auto memory = ArSpectralMeanUncertainty(x->data(), x->size());
    auto chunked = ArSpectralMeanUncertaintyChunked(spilled.reader, x->size());
    REQUIRE(memory.ok());
    if (memory.value().lattice_fallbacks > 0) {
      REQUIRE_FALSE(chunked.ok());
      CHECK_THAT(chunked.error().message, Catch::Contains("not available in streaming mode"));
    } else {
      REQUIRE(chunked.ok());
      CHECK(chunked.value().u_mean == memory.value().u_mean);
      CHECK(chunked.value().order == memory.value().order);
    }
  }
  // White noise: never a fallback, the same estimate.
  std::vector<double> white(99999);
  for (double& w : white) w = 5.0 + normal(rng);
  Spilled spilled;
  Spill(white, &spilled);
  auto memory = ArSpectralMeanUncertainty(white.data(), white.size());
  auto chunked = ArSpectralMeanUncertaintyChunked(spilled.reader, white.size());
  REQUIRE(memory.ok());
  REQUIRE(chunked.ok());
  CHECK(memory.value().lattice_fallbacks == 0);
  CHECK(chunked.value().u_mean == memory.value().u_mean);
  CHECK(chunked.value().dof == memory.value().dof);
  CHECK(chunked.value().phi == memory.value().phi);
}

}  // namespace metro
