#include "metro/stats/circular.hpp"

#include <algorithm>
#include <cmath>

#include "metro/core/angles.hpp"

namespace metro {

CircularStatistics CircularStatisticsDeg(const std::vector<double>& angles_deg) {
  CircularStatistics out;
  const size_t n = angles_deg.size();
  if (n == 0) return out;
  constexpr double kRadPerDeg = M_PI / 180.0;
  double c = 0.0, s = 0.0;
  for (double a : angles_deg) {
    c += std::cos(a * kRadPerDeg);
    s += std::sin(a * kRadPerDeg);
  }
  c /= static_cast<double>(n);
  s /= static_cast<double>(n);
  // Mardia & Jupp (2000) 2.2.1 (mean direction), 2.3.1 (R), 2.3.2 (circular std).
  out.resultant_length = std::min(1.0, std::hypot(c, s));
  // R below rounding noise (e.g. 0 and 180 deg): no mean direction.
  if (out.resultant_length > 1e-12) out.mean_deg = WrapDeg180(std::atan2(s, c) / kRadPerDeg);
  out.std_deg = std::sqrt(-2.0 * std::log(out.resultant_length)) / kRadPerDeg;
  if (n >= 2) {
    out.sample_std_deg =
        out.std_deg * std::sqrt(static_cast<double>(n) / static_cast<double>(n - 1));
  }
  return out;
}

}  // namespace metro
