// The --time-order stage shared by the log readers (MCAP, ROS bags, PX4 ULog): a stream's
// sample times made strictly increasing, sorted or refused (docs/formats.md "ROS bags and
// MCAP", "PX4 ULog").
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace metro::internal {

// What ordering one stream's times needs. first_not_after is the first index i whose time is
// not after the one before it (t[i] <= t[i-1]), or kInOrder; `late` counts the times below
// the largest one before them in the file; `keep` lists, when the times are not strictly
// increasing, the indexes to keep in their sorted order: a stable sort (equal times keep file
// order) with the repeats after the first dropped, so `repeats` = t.size() - keep.size().
struct TimeOrderPlan {
  static constexpr size_t kInOrder = static_cast<size_t>(-1);
  size_t first_not_after = kInOrder;
  int64_t late = 0;
  int64_t repeats = 0;
  std::vector<size_t> keep;  // Empty when the times are already strictly increasing.

  bool in_order() const { return first_not_after == kInOrder; }
};

TimeOrderPlan PlanTimeOrder(const std::vector<int64_t>& t);

// v = v[keep[0]], v[keep[1]], ...
template <typename T>
void Permute(const std::vector<size_t>& keep, std::vector<T>* v) {
  std::vector<T> out;
  out.reserve(keep.size());
  for (size_t i : keep) out.push_back((*v)[i]);
  v->swap(out);
}

}  // namespace metro::internal
