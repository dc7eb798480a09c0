#include "metro/stats/quantization.hpp"

#include <algorithm>
#include <cmath>

namespace metro {

double QuantizationStep(const std::vector<double>& x) {
  std::vector<double> v;
  v.reserve(x.size());
  for (double d : x) {
    if (std::isfinite(d)) v.push_back(d);
  }
  std::sort(v.begin(), v.end());
  if (v.size() < 5) return 0.0;
  // Values closer than the doubles' own rounding (1e-9 of the data's scale) are one value.
  const double scale = std::max({std::fabs(v.front()), std::fabs(v.back()), v.back() - v.front()});
  const double same = 1e-9 * scale;
  std::vector<double> gaps;
  for (size_t i = 0; i + 1 < v.size(); ++i) {
    if (v[i + 1] - v[i] > same) gaps.push_back(v[i + 1] - v[i]);
  }
  if (gaps.size() < 4) return 0.0;
  const double q = *std::min_element(gaps.begin(), gaps.end());
  // Values printed with a fixed number of decimals differ by whole multiples of that step up
  // to the rounding of their binary representation.
  size_t whole = 0;
  for (double g : gaps) {
    const double ratio = g / q;
    if (std::fabs(ratio - std::round(ratio)) <= 1e-3) ++whole;
  }
  return static_cast<double>(whole) >= 0.95 * static_cast<double>(gaps.size()) ? q : 0.0;
}

}  // namespace metro
