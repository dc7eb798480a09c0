#include "metro/noise/noise_id.hpp"

#include <catch2/catch.hpp>
#include <cstdlib>

#include "metro/noise/allan.hpp"
#include "noise/noise_simulation.hpp"

namespace metro {
namespace {

TEST_CASE("Lag-1 ACF identifies simulated power-law noise", "[noise]") {
  // Truth by construction (noise_simulation.hpp). White PM, white FM and random-walk FM are
  // identified exactly at every m with >= 30 points; flicker PM and flicker FM exactly at
  // small m and within one step beyond (the lag-1 ACF of 1/f noise is biased for short series).
  const size_t n = 1 << 16;
  for (int alpha : {2, 1, 0, -1, -2}) {
    const std::vector<double> x = PhaseFromRate(testing::PowerLawRate(alpha, n, 11), 1.0);
    for (int64_t m : {1, 2, 4, 16, 64, 256, 1024}) {
      const Result<NoiseIdentification> id = IdentifyNoiseLag1(x, m, 2);
      REQUIRE(id.ok());
      INFO("alpha = " << alpha << " m = " << m << " p = " << id.value().p);
      if (alpha == 1 || alpha == -1) {
        if (m <= 4) CHECK(id.value().alpha == alpha);
        CHECK(std::abs(id.value().alpha - alpha) <= 1);
      } else {
        CHECK(id.value().alpha == alpha);
      }
    }
  }
}

TEST_CASE("Hadamard noise id reaches flicker walk FM", "[noise]") {
  // alpha = -3: the rate is a random walk of flicker noise; d_max = 3 allows p = -5.
  std::vector<double> f = testing::FlickerNoise(1 << 15, 1.0, 5);
  double s = 0.0;
  for (double& v : f) {
    s += v;
    v = s;
  }
  const std::vector<double> x = PhaseFromRate(f, 1.0);
  const Result<NoiseIdentification> id = IdentifyNoiseLag1(x, 1, 3);
  REQUIRE(id.ok());
  CHECK(id.value().alpha == -3);
  // Decimated flicker-type noise reads about one step redder (p ~ -5.9 here), as for
  // flicker PM and flicker FM above.
  const Result<NoiseIdentification> coarse = IdentifyNoiseLag1(x, 4, 3);
  REQUIRE(coarse.ok());
  CHECK(std::abs(coarse.value().alpha + 3) <= 1);
  const Result<NoiseIdentification> allan = IdentifyNoiseLag1(x, 4, 2);
  REQUIRE(allan.ok());
  CHECK(allan.value().alpha == -2);  // Clamped: the Allan EDF needs alpha >= -2.
}

TEST_CASE("Noise id refuses bad input with a message", "[noise]") {
  const std::vector<double> x(100, 0.0);
  CHECK(IdentifyNoiseLag1(x, 0, 2).error().message ==
        "noise id: averaging factor m = 0 is below 1");
  CHECK(IdentifyNoiseLag1(x, 1, 4).error().message ==
        "noise id: d_max = 4 is not 2 (Allan) or 3 (Hadamard)");
  CHECK(IdentifyNoiseLag1(x, 1, 2, 4).error().message == "noise id: min_points must be >= 8");
  CHECK(IdentifyNoiseLag1(x, 10, 2).error().message ==
        "noise id: 10 decimated points at m = 10 are fewer than the 30 needed");
  CHECK(IdentifyNoiseLag1(x, 1, 2).error().message ==
        "noise id: the series at m = 1 is constant after 0 differences");
}

}  // namespace
}  // namespace metro
