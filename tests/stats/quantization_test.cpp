// The resolution of quantized data (the session page's histogram bins rest on it).
#include "metro/stats/quantization.hpp"

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <pcg_random.hpp>
#include <random>
#include <string>
#include <utility>
#include <vector>

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

// The definition (quantization.hpp) by sorting every value: the reference for metro's
// lattice path, which orders the values by bucket instead of sorting them.
double StepBySorting(std::vector<double> v) {
  v.erase(std::remove_if(v.begin(), v.end(), [](double d) { return !std::isfinite(d); }), v.end());
  std::sort(v.begin(), v.end());
  if (v.size() < 5) return 0.0;
  const double same =
      1e-9 * std::max({std::fabs(v.front()), std::fabs(v.back()), v.back() - v.front()});
  std::vector<double> gaps;
  for (size_t i = 0; i + 1 < v.size(); ++i) {
    if (v[i + 1] - v[i] > same) gaps.push_back(v[i + 1] - v[i]);
  }
  if (gaps.size() < 4) return 0.0;
  const double q = *std::min_element(gaps.begin(), gaps.end());
  size_t whole = 0;
  for (double g : gaps) whole += std::fabs(g / q - std::round(g / q)) <= 1e-3 ? 1 : 0;
  return static_cast<double>(whole) >= 0.95 * static_cast<double>(gaps.size()) ? q : 0.0;
}

TEST_CASE("Quantization step without a sort equals the sorted definition bit for bit", "[stats]") {
  pcg64 rng(38);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::vector<std::pair<std::string, std::vector<double>>> cases;
  const size_t n = 200000;
  std::vector<double> decimals(n), counts(n), wide(n), rare_odd(n), off(n), continuous(n);
  for (size_t i = 0; i < n; ++i) {
    const double v = normal(rng);
    decimals[i] = std::round((12.0 + 0.3 * v) * 1e4) / 1e4;  // printed with 4 decimals
    counts[i] = std::round(800.0 * v);                       // raw counts
    wide[i] = std::round(3e6 * v);                           // > 2^20 buckets: sorted
    // Even counts, with an odd one every 5000 samples (the sample's step is 2, the data's 1).
    rare_odd[i] = 2.0 * std::round(50.0 * v) + (i % 5000 == 17 ? 1.0 : 0.0);
    off[i] = decimals[i] + (i == n / 2 ? 3e-5 : 0.0);  // one value off the lattice
    continuous[i] = v;
  }
  decimals[10] = std::numeric_limits<double>::quiet_NaN();
  cases.emplace_back("4 decimals with a NaN", decimals);
  cases.emplace_back("raw counts", counts);
  cases.emplace_back("counts over 2^20 steps", wide);
  cases.emplace_back("even counts with rare odd ones", rare_odd);
  cases.emplace_back("one value off the lattice", off);
  cases.emplace_back("continuous", continuous);
  for (const auto& [name, x] : cases) {
    CAPTURE(name);
    const double expected = StepBySorting(x);
    CHECK(QuantizationStep(x) == expected);  // exact: the same gaps, the same minimum
  }
  CHECK(QuantizationStep(counts) == 1.0);
  CHECK(QuantizationStep(rare_odd) == 1.0);
  CHECK(QuantizationStep(decimals) == Approx(1e-4).epsilon(1e-6));
  CHECK(QuantizationStep(continuous) == 0.0);
}

}  // namespace
}  // namespace metro
