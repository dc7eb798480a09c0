#include "metro/noise/noise_id.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace metro {
namespace {

// Lag-1 autocorrelation, normalized by the sum of squares about the mean. False if the
// series is constant.
bool Lag1Autocorrelation(const std::vector<double>& z, double* r1) {
  const size_t n = z.size();
  double s[4] = {0.0, 0.0, 0.0, 0.0};
  size_t k = 0;
  for (; k + 4 <= n; k += 4) {
    for (size_t j = 0; j < 4; ++j) s[j] += z[k + j];
  }
  for (; k < n; ++k) s[0] += z[k];
  const double mean = ((s[0] + s[1]) + (s[2] + s[3])) / static_cast<double>(n);
  // Centered sums with interleaved accumulators (no long double: this runs on every point).
  double num[2] = {0.0, 0.0}, den[2] = {0.0, 0.0};
  double prev = z[0] - mean;
  den[0] = prev * prev;
  for (k = 1; k < n; ++k) {
    const double a = z[k] - mean;
    num[k & 1] += prev * a;
    den[k & 1] += a * a;
    prev = a;
  }
  const double sum_den = den[0] + den[1];
  if (!(sum_den > 0.0)) return false;
  *r1 = (num[0] + num[1]) / sum_den;
  return true;
}

}  // namespace

Result<NoiseIdentification> IdentifyNoiseLag1(const std::vector<double>& phase, int64_t m,
                                              int d_max, int64_t min_points, int64_t max_points) {
  return IdentifyNoiseLag1(phase.data(), static_cast<int64_t>(phase.size()), m, d_max, min_points,
                           max_points);
}

Result<NoiseIdentification> IdentifyNoiseLag1(const double* phase, int64_t n_phase, int64_t m,
                                              int d_max, int64_t min_points, int64_t max_points) {
  if (m < 1) return MakeError(fmt::format("noise id: averaging factor m = {} is below 1", m));
  if (d_max != 2 && d_max != 3) {
    return MakeError(fmt::format("noise id: d_max = {} is not 2 (Allan) or 3 (Hadamard)", d_max));
  }
  if (min_points < 8) return MakeError("noise id: min_points must be >= 8");
  const int64_t n_points = n_phase < 1 ? 0 : (n_phase - 1) / m + 1;
  if (n_points < min_points) {
    return MakeError(
        fmt::format("noise id: {} decimated points at m = {} are fewer than the {} needed",
                    n_points, m, min_points));
  }
  const int64_t used = std::min(n_points, std::max(max_points, min_points));
  std::vector<double> z(static_cast<size_t>(used));
  for (int64_t k = 0; k < used; ++k) z[static_cast<size_t>(k)] = phase[k * m];

  NoiseIdentification id;
  id.n_points = used;
  for (int diff = 0;; ++diff) {
    double r1 = 0.0;
    if (z.size() < 3 || !Lag1Autocorrelation(z, &r1)) {
      return MakeError(
          fmt::format("noise id: the series at m = {} is constant after {} differences", m, diff));
    }
    const double delta = r1 / std::max(1.0 + r1, 1e-9);  // r1 -> -1: strongly blue noise.
    if (delta < 0.25 || diff >= d_max) {
      // Riley & Greenhall 2004: p = -2 (delta + d) is the exponent of the (phase) series.
      id.p = -2.0 * (delta + diff);
      id.lag1_acf = r1;
      id.differences = diff;
      const int alpha = static_cast<int>(std::lround(id.p)) + 2;
      id.alpha = std::clamp(alpha, 2 - 2 * d_max, 2);
      return id;
    }
    for (size_t k = 0; k + 1 < z.size(); ++k) z[k] = z[k + 1] - z[k];
    z.pop_back();
  }
}

}  // namespace metro
