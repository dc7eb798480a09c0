#include "metro/accuracy/plateaus.hpp"

#include <fmt/format.h>

#include <cmath>

#include "metro/core/angles.hpp"
#include "metro/stats/settle.hpp"

namespace metro {

bool PlateauOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& m) {
    if (why) *why = m;
    return false;
  };
  if (!(tolerance_deg >= 0.0) || !std::isfinite(tolerance_deg)) {
    return fail("plateau tolerance_deg must be >= 0");
  }
  if (!(min_dwell_s > 0.0) || !std::isfinite(min_dwell_s)) {
    return fail("plateau min_dwell_s must be > 0");
  }
  if (min_samples < 2) return fail("plateau min_samples must be >= 2");
  if (!(settle_s >= 0.0) || !std::isfinite(settle_s)) return fail("settle_s must be >= 0");
  if (!(settle_lag_residual_deg > 0.0) || !std::isfinite(settle_lag_residual_deg)) {
    return fail("settle_lag_residual_deg must be > 0");
  }
  return true;
}

Result<Segmentation> FindPlateaus(const std::vector<double>& t_s,
                                  const std::vector<double>& reference_deg,
                                  const std::vector<double>& tag_error_deg,
                                  const PlateauOptions& options,
                                  const std::vector<double>* transient_deg) {
  std::string why;
  if (!options.IsValid(&why)) return MakeError(why);
  const size_t n = t_s.size();
  if (reference_deg.size() != n || tag_error_deg.size() != n ||
      (transient_deg != nullptr && transient_deg->size() != n)) {
    return MakeError("plateaus: the time, reference and error series differ in length");
  }
  Segmentation seg;
  auto exclude = [&](size_t b, size_t e, const char* reason) {
    if (e <= b) return;
    if (!seg.excluded.empty() && seg.excluded.back().end == b &&
        seg.excluded.back().reason == reason) {
      seg.excluded.back().end = e;
      seg.excluded.back().t_end_s = t_s[e - 1];
    } else {
      seg.excluded.push_back({b, e, t_s[b], t_s[e - 1], reason});
    }
  };
  size_t i = 0;
  while (i < n) {
    if (std::isnan(reference_deg[i])) {
      size_t j = i;
      while (j < n && std::isnan(reference_deg[j])) ++j;
      exclude(i, j, "reference unknown");
      i = j;
      continue;
    }
    // A run at rest: every reference within tolerance of the run's first value.
    size_t j = i + 1;
    while (j < n && !std::isnan(reference_deg[j]) &&
           std::fabs(WrapDeg180(reference_deg[j] - reference_deg[i])) <= options.tolerance_deg) {
      ++j;
    }
    if (j - i < 2 || t_s[j - 1] - t_s[i] < options.min_dwell_s) {
      exclude(i, j, j - i < 2 ? "motion" : "rest shorter than min_dwell_s");
      i = j;
      continue;
    }
    Plateau p;
    p.rest_begin = i;
    p.end = j;
    p.t_rest_s = t_s[i];
    size_t begin = i;
    while (begin < j && t_s[begin] < t_s[i] + options.settle_s) ++begin;
    if (transient_deg != nullptr) {
      const size_t fixed = begin;
      while (begin < j && std::fabs((*transient_deg)[begin]) > options.settle_lag_residual_deg) {
        ++begin;
      }
      p.settled_by_lag = begin > fixed;
    }
    if (options.settle_auto && j - begin >= 10) {
      const SettleResult settle = DetectSettleMser5(tag_error_deg.data() + begin, j - begin);
      begin += settle.samples;
      p.settle_at_limit = settle.at_limit;
    }
    if (j - begin < options.min_samples) {
      exclude(i, j, "too short after settling");
      i = j;
      continue;
    }
    p.begin = begin;
    p.settle_samples = begin - i;
    p.t_start_s = t_s[begin];
    p.t_end_s = t_s[j - 1];
    double sum = 0.0;
    for (size_t k = begin; k < j; ++k) sum += WrapDeg180(reference_deg[k] - reference_deg[i]);
    p.reference_deg = reference_deg[i] + sum / static_cast<double>(j - begin);
    seg.settle_samples += p.settle_samples;
    seg.plateaus.push_back(p);
    i = j;
  }
  for (const ExcludedSpan& e : seg.excluded) {
    seg.motion_samples += e.end - e.begin;
    // Time of an excluded span: from its first observation to the next kept one.
    const double t_next = e.end < n ? t_s[e.end] : t_s[e.end - 1];
    seg.motion_s += t_next - e.t_start_s;
  }
  if (seg.plateaus.empty()) {
    return MakeError(fmt::format(
        "no plateau found: the reference never stayed within {} deg for {} s with {} "
        "observations left after settling ({} observations examined); collect a sweep that "
        "dwells at each table angle (e.g. 20 s per step) or lower --min-dwell-s",
        options.tolerance_deg, options.min_dwell_s, options.min_samples, n));
  }
  return seg;
}

}  // namespace metro
