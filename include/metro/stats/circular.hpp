#pragma once

#include <cmath>
#include <vector>

namespace metro {

// Circular statistics of angles in degrees (Mardia & Jupp, Directional Statistics, Wiley
// 2000, 2.2.1-2.3.2): with C = (1/n) sum cos(a_k), S = (1/n) sum sin(a_k),
//   mean = atan2(S, C)                        (circular mean, wrapped into (-180, 180])
//   R = sqrt(C^2 + S^2)                       (mean resultant length, 0..1)
//   std_deg = sqrt(-2 ln R)                   (circular standard deviation, in rad -> deg)
// For a small spread std_deg is the linear standard deviation with divisor n; sample_std_deg
// = sqrt(n / (n - 1)) std_deg is the one with n - 1 (JCGM 100:2008 4.2.2), NaN for n < 2.
// The mean is NaN when R <= 1e-12 (no preferred direction, e.g. 0 and 180 deg). Tags at +179.95 and
// -179.95 deg give mean 180, std 0.05, sample_std 0.0707 (a linear mean would say 0 and 180).
struct CircularStatistics {
  double mean_deg = std::nan("");
  double resultant_length = 0.0;
  double std_deg = std::nan("");
  double sample_std_deg = std::nan("");
};
CircularStatistics CircularStatisticsDeg(const std::vector<double>& angles_deg);

}  // namespace metro
