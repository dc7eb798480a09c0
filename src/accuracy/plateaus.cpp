#include "metro/accuracy/plateaus.hpp"

#include <fmt/format.h>

#include <algorithm>
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
  if (!(departure_sigmas > 0.0) || !std::isfinite(departure_sigmas)) {
    return fail("departure_sigmas must be > 0");
  }
  if (!(max_departure_fraction > 0.0 && max_departure_fraction < 1.0)) {
    return fail("max_departure_fraction must be in (0, 1)");
  }
  return true;
}

namespace {

struct Departures {
  size_t start = 0;   // Observations trimmed at the start.
  size_t end = 0;     // ... and at the end.
  bool kept = false;  // A departure too long to be motion was left in place.
};

// The departing ends of e[begin, end): runs at either end beyond departure_sigmas robust
// standard deviations of the plateau's median, plus one observation (the one before the
// crossing is already moving, by less). Runs longer than max_departure_fraction are drift.
Departures FindDepartures(const std::vector<double>& e, size_t begin, size_t end,
                          const PlateauOptions& options) {
  Departures out;
  std::vector<double> v(e.begin() + static_cast<ptrdiff_t>(begin),
                        e.begin() + static_cast<ptrdiff_t>(end));
  v.erase(std::remove_if(v.begin(), v.end(), [](double x) { return std::isnan(x); }), v.end());
  if (v.size() < options.min_samples) return out;
  const auto mid = v.begin() + static_cast<ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  const double median = *mid;
  for (double& x : v) x = std::fabs(x - median);
  std::nth_element(v.begin(), mid, v.end());
  const double sigma = std::max(1.4826 * *mid, options.tolerance_deg);
  const double limit = options.departure_sigmas * sigma;
  auto departs = [&](size_t k) { return std::fabs(e[k] - median) > limit; };
  const auto max_run =
      static_cast<size_t>(options.max_departure_fraction * static_cast<double>(end - begin));
  size_t run = 0;
  while (run < max_run && departs(end - 1 - run)) ++run;
  if (run >= max_run) {
    out.kept = max_run > 0;
  } else if (run > 0) {
    out.end = run + 1;
  }
  run = 0;
  while (run < max_run && departs(begin + run)) ++run;
  if (run >= max_run) {
    out.kept = out.kept || max_run > 0;
  } else if (run > 0) {
    out.start = run + 1;
  }
  return out;
}

}  // namespace

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
    size_t end = j;
    if (options.trim_departures && j - begin >= options.min_samples) {
      const Departures d = FindDepartures(tag_error_deg, begin, j, options);
      p.departure_kept = d.kept;
      if (d.start + d.end + options.min_samples <= j - begin) {
        p.start_trimmed = d.start;
        p.end_trimmed = d.end;
        begin += d.start;
        end -= d.end;
      }
    }
    if (end - begin < options.min_samples) {
      exclude(i, j, "too short after settling");
      i = j;
      continue;
    }
    p.begin = begin;
    p.end = end;
    p.rest_end = j;
    p.settle_samples = begin - i;
    p.t_start_s = t_s[begin];
    p.t_end_s = t_s[end - 1];
    double sum = 0.0;
    for (size_t k = begin; k < end; ++k) sum += WrapDeg180(reference_deg[k] - reference_deg[i]);
    p.reference_deg = reference_deg[i] + sum / static_cast<double>(end - begin);
    seg.settle_samples += p.settle_samples;
    if (p.start_trimmed + p.end_trimmed > 0) {
      ++seg.departure_trimmed_plateaus;
      seg.departure_trimmed_samples += p.start_trimmed + p.end_trimmed;
    }
    if (p.end_trimmed > 0) {
      // From the last kept observation to the first at motion.
      const double t_next = j < n ? t_s[j] : t_s[j - 1];
      seg.max_end_trimmed_s = std::max(seg.max_end_trimmed_s, t_next - t_s[end - 1]);
    }
    if (p.departure_kept) ++seg.departure_kept_plateaus;
    seg.plateaus.push_back(p);
    exclude(end, j, "tag moving at the plateau's end");
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
