// The resolution of quantized data (the session page's histogram bins rest on it).
#include "metro/stats/quantization.hpp"

#include <catch2/catch.hpp>
#include <cmath>
#include <pcg_random.hpp>
#include <random>

namespace metro {
namespace {

TEST_CASE("Quantization step of lattice data and none for continuous data", "[stats]") {
  pcg64 rng(3);
  std::normal_distribution<double> normal(0.0, 0.03);
  std::vector<double> angles, counts, continuous;
  for (int i = 0; i < 2000; ++i) {
    const double v = normal(rng);
    angles.push_back(std::round(v / 0.01) * 0.01 + 12.0);  // 0.01 deg packets, about 12 deg
    counts.push_back(std::round(v * 1e4));                 // raw counts
    continuous.push_back(v);
  }
  CHECK(QuantizationStep(angles) == Approx(0.01).epsilon(1e-9));
  CHECK(QuantizationStep(counts) == 1.0);
  CHECK(QuantizationStep(continuous) == 0.0);
  CHECK(QuantizationStep({1.0, 2.0, 3.0}) == 0.0);  // too few distinct values
  // Two values that differ by the doubles' rounding alone are one value, not a 1e-21 lattice.
  std::vector<double> with_noise = angles;
  with_noise.push_back(angles[0] + 3e-21);
  with_noise.push_back(std::nextafter(angles[1], 1e9));
  CHECK(QuantizationStep(with_noise) == Approx(0.01).epsilon(1e-9));
  // A lattice of 0.02 with one stray value at 0.413: the smallest gap (0.007) is not a step
  // of the rest (fewer than 95 % of the gaps are its multiples), so no resolution is claimed.
  std::vector<double> mostly;
  for (int i = 0; i < 40; ++i) mostly.push_back(0.02 * i);
  mostly.push_back(0.413);
  CHECK(QuantizationStep(mostly) == 0.0);
}

}  // namespace
}  // namespace metro
