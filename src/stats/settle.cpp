#include "metro/stats/settle.hpp"

#include <limits>
#include <vector>

namespace metro {

SettleResult DetectSettleMser5(const double* values, size_t n) {
  constexpr size_t kBatch = 5;
  SettleResult result;
  const size_t m = n / kBatch;
  if (m < 2) return result;
  std::vector<double> batch(m);
  double grand = 0.0;
  for (size_t j = 0; j < m; ++j) {
    double s = 0.0;
    for (size_t i = 0; i < kBatch; ++i) s += values[j * kBatch + i];
    batch[j] = s / kBatch;
    grand += batch[j];
  }
  grand /= static_cast<double>(m);
  // Suffix sums of centred batch means: MSER(d) for every d in O(m).
  std::vector<double> sum(m + 1, 0.0), sum2(m + 1, 0.0);
  for (size_t j = m; j-- > 0;) {
    const double b = batch[j] - grand;
    sum[j] = sum[j + 1] + b;
    sum2[j] = sum2[j + 1] + b * b;
  }
  const size_t d_max = m / 2;
  double best = std::numeric_limits<double>::infinity();
  size_t best_d = 0;
  for (size_t d = 0; d <= d_max; ++d) {
    const double k = static_cast<double>(m - d);
    const double ss = sum2[d] - sum[d] * sum[d] / k;
    const double mser = ss / (k * k);
    if (mser < best) {
      best = mser;
      best_d = d;
    }
  }
  result.samples = best_d * kBatch;
  result.mser = best;
  result.at_limit = best_d == d_max;
  return result;
}

}  // namespace metro
