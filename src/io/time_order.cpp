#include "io/time_order.hpp"

#include <algorithm>
#include <limits>
#include <numeric>

namespace metro::internal {

TimeOrderPlan PlanTimeOrder(const std::vector<int64_t>& t) {
  TimeOrderPlan plan;
  int64_t high = std::numeric_limits<int64_t>::min();
  for (size_t i = 0; i < t.size(); ++i) {
    if (i > 0 && t[i] <= t[i - 1] && plan.in_order()) plan.first_not_after = i;
    if (t[i] < high) ++plan.late;
    high = std::max(high, t[i]);
  }
  if (plan.in_order()) return plan;
  std::vector<size_t> order(t.size());
  std::iota(order.begin(), order.end(), size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return t[a] < t[b]; });
  plan.keep.reserve(order.size());
  for (size_t j = 0; j < order.size(); ++j) {
    if (j == 0 || t[order[j]] != t[order[j - 1]]) plan.keep.push_back(order[j]);
  }
  plan.repeats = static_cast<int64_t>(order.size() - plan.keep.size());
  return plan;
}

}  // namespace metro::internal
