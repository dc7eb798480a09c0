#include "metro/calibration/segments.hpp"

#include <algorithm>
#include <cmath>

#include "metro/core/check.hpp"

namespace metro {

const char* SegmentKindName(SegmentKind kind) {
  switch (kind) {
    case SegmentKind::kStatic:
      return "static";
    case SegmentKind::kTable:
      return "table";
    case SegmentKind::kRotation:
      return "rotation";
  }
  return "static";
}

bool SegmentationOptions::IsValid(std::string* why) const {
  auto fail = [why](const char* message) {
    if (why != nullptr) *why = message;
    return false;
  };
  if (!(window_s > 0)) return fail("window_s must be > 0");
  if (!(min_static_s > 0)) return fail("min_static_s must be > 0");
  if (threshold_factors.empty()) return fail("threshold_factors must not be empty");
  for (double c : threshold_factors) {
    if (!(c > 1)) return fail("every threshold factor must be > 1");
  }
  if (!(table_settle_s >= 0)) return fail("table_settle_s must be >= 0");
  if (!(min_table_s > 0)) return fail("min_table_s must be > 0");
  if (!(max_gap_factor > 1)) return fail("max_gap_factor must be > 1");
  return true;
}

namespace {

// Sum over the axes of the sample variance in the window [k - h, k + h] (clipped).
std::vector<double> WindowVariance(const std::vector<Eigen::Vector3d>& x, size_t h) {
  const size_t n = x.size();
  const Eigen::Vector3d x0 = x[n / 2];  // Centring keeps the prefix sums well conditioned.
  std::vector<Eigen::Vector3d> s1(n + 1, Eigen::Vector3d::Zero());
  std::vector<Eigen::Vector3d> s2(n + 1, Eigen::Vector3d::Zero());
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d d = x[i] - x0;
    s1[i + 1] = s1[i] + d;
    s2[i + 1] = s2[i] + d.cwiseProduct(d);
  }
  std::vector<double> v(n, 0.0);
  for (size_t k = 0; k < n; ++k) {
    const size_t lo = k >= h ? k - h : 0;
    const size_t hi = std::min(n, k + h + 1);
    const double m = static_cast<double>(hi - lo);
    if (m < 2) continue;
    const Eigen::Vector3d sum = s1[hi] - s1[lo];
    const Eigen::Vector3d sum2 = s2[hi] - s2[lo];
    const Eigen::Vector3d var = (sum2 - sum.cwiseProduct(sum) / m) / (m - 1);
    v[k] = std::max(0.0, var.sum());
  }
  return v;
}

double Percentile(std::vector<double> v, double p) {
  METRO_CHECK(!v.empty());
  const size_t i = std::min(v.size() - 1, static_cast<size_t>(p * static_cast<double>(v.size())));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(i), v.end());
  return v[i];
}

struct Run {
  size_t begin, end;
};

Eigen::Vector3d MeanOf(const std::vector<Eigen::Vector3d>& x, const Run& r) {
  Eigen::Vector3d s = Eigen::Vector3d::Zero();
  for (size_t i = r.begin; i < r.end; ++i) s += x[i];
  return s / static_cast<double>(r.end - r.begin);
}

}  // namespace

SegmentationSummary DetectSegments(const SegmentationInput& input,
                                   const SegmentationOptions& options) {
  METRO_CHECK(options.IsValid(nullptr));
  METRO_CHECK(input.t_s != nullptr && input.accel != nullptr);
  const std::vector<double>& t = *input.t_s;
  const std::vector<Eigen::Vector3d>& accel = *input.accel;
  const size_t n = t.size();
  METRO_CHECK(n > 0 && accel.size() == n);
  const bool has_gyro = input.gyro != nullptr && !input.gyro->empty();
  if (has_gyro) METRO_CHECK(input.gyro->size() == n);
  const bool has_table = input.table_rate_dps != nullptr && !input.table_rate_dps->empty();
  if (has_table) METRO_CHECK(input.table_rate_dps->size() == n);
  const bool has_sat = input.saturated != nullptr && !input.saturated->empty();
  if (has_sat) METRO_CHECK(input.saturated->size() == n);

  SegmentationSummary summary;
  if (n < 3) return summary;

  std::vector<double> dt(n - 1);
  for (size_t i = 0; i + 1 < n; ++i) dt[i] = t[i + 1] - t[i];
  const double dt_median = Percentile(dt, 0.5);
  const double gap_s = options.max_gap_factor * dt_median;
  // gap_before[k]: a time gap between samples k-1 and k.
  std::vector<unsigned char> gap_before(n, 0);
  for (size_t i = 1; i < n; ++i) gap_before[i] = dt[i - 1] > gap_s ? 1 : 0;

  const size_t h = std::max<size_t>(
      2, static_cast<size_t>(std::lround(0.5 * options.window_s / std::max(dt_median, 1e-9))));
  const std::vector<double> va = WindowVariance(accel, h);
  std::vector<double> vg;
  summary.accel_floor = Percentile(va, 0.05);
  if (has_gyro) {
    vg = WindowVariance(*input.gyro, h);
    summary.gyro_floor = Percentile(vg, 0.05);
  }
  auto table_turning = [&](size_t k) {
    if (!has_table) return false;
    const double r = (*input.table_rate_dps)[k];
    return std::isfinite(r) && r != 0.0;
  };
  const size_t min_static_n = static_cast<size_t>(std::ceil(options.min_static_s / dt_median));
  const double same_pose = 3.0 * std::sqrt(summary.accel_floor);

  auto static_runs = [&](double c) {
    std::vector<Run> runs;
    // A floor of exactly 0 (quantised, perfectly still data) still admits equal samples.
    const double ta = std::max(c * summary.accel_floor, 1e-300);
    const double tg = has_gyro ? std::max(c * summary.gyro_floor, 1e-300) : 0.0;
    size_t k = 0;
    while (k < n) {
      auto is_static = [&](size_t i) {
        if (va[i] >= ta) return false;
        if (has_gyro && vg[i] >= tg) return false;
        if (has_sat && (*input.saturated)[i]) return false;
        return !table_turning(i);
      };
      if (!is_static(k)) {
        ++k;
        continue;
      }
      size_t e = k + 1;
      while (e < n && is_static(e) && !gap_before[e]) ++e;
      if (e - k >= min_static_n) runs.push_back({k, e});
      k = e;
    }
    // Neighbouring runs of one pose (same accelerometer mean, nothing turning between) merge.
    std::vector<Run> merged;
    for (const Run& r : runs) {
      if (!merged.empty()) {
        Run& last = merged.back();
        bool clean = true;
        for (size_t i = last.end; i < r.begin && clean; ++i) {
          if (table_turning(i) || gap_before[i] || (has_sat && (*input.saturated)[i])) {
            clean = false;
          }
        }
        if (clean && gap_before[r.begin]) clean = false;
        if (clean && (MeanOf(accel, last) - MeanOf(accel, r)).norm() < same_pose) {
          last.end = r.end;
          continue;
        }
      }
      merged.push_back(r);
    }
    return merged;
  };

  // Automatic threshold: the factors reaching the most static intervals, median of them.
  std::vector<std::pair<double, size_t>> counts;
  size_t best = 0;
  for (double c : options.threshold_factors) {
    const size_t count = static_runs(c).size();
    counts.push_back({c, count});
    best = std::max(best, count);
  }
  std::vector<double> best_factors;
  for (const auto& [c, count] : counts) {
    if (count == best) best_factors.push_back(c);
  }
  std::sort(best_factors.begin(), best_factors.end());
  summary.threshold_factor = best_factors[(best_factors.size() - 1) / 2];
  const std::vector<Run> statics = static_runs(summary.threshold_factor);

  std::vector<Segment> segments;
  auto make = [&](SegmentKind kind, size_t b, size_t e) {
    Segment s;
    s.kind = kind;
    s.piece = input.piece;
    s.begin = b;
    s.end = e;
    s.start_s = t[b];
    s.end_s = t[e - 1];
    return s;
  };
  for (const Run& r : statics) segments.push_back(make(SegmentKind::kStatic, r.begin, r.end));
  for (size_t i = 0; i + 1 < statics.size(); ++i) {
    const size_t b = statics[i].end;
    const size_t e = statics[i + 1].begin;
    if (e <= b) continue;
    Segment s = make(SegmentKind::kRotation, b, e);
    for (size_t k = b; k <= e && k < n; ++k) {
      if (gap_before[k]) {
        s.used = false;
        s.note = "time gap inside the rotation";
        break;
      }
    }
    segments.push_back(s);
  }
  if (has_table) {
    const std::vector<double>& rate = *input.table_rate_dps;
    const size_t settle_n =
        static_cast<size_t>(std::lround(options.table_settle_s / std::max(dt_median, 1e-9)));
    const size_t min_table_n =
        static_cast<size_t>(std::ceil(options.min_table_s / std::max(dt_median, 1e-9)));
    size_t k = 0;
    while (k < n) {
      if (!table_turning(k)) {
        ++k;
        continue;
      }
      size_t e = k + 1;
      while (e < n && rate[e] == rate[k] && !gap_before[e]) ++e;
      if (e - k > 2 * settle_n && e - k - 2 * settle_n >= min_table_n) {
        Segment s = make(SegmentKind::kTable, k + settle_n, e - settle_n);
        s.table_rate_dps = rate[k];
        segments.push_back(s);
      }
      k = e;
    }
  }
  std::sort(segments.begin(), segments.end(),
            [](const Segment& a, const Segment& b) { return a.begin < b.begin; });
  for (const Segment& s : segments) {
    if (s.kind == SegmentKind::kStatic) ++summary.static_count;
    if (s.kind == SegmentKind::kTable) ++summary.table_count;
    if (s.kind == SegmentKind::kRotation) ++summary.rotation_count;
  }
  summary.segments = std::move(segments);
  return summary;
}

}  // namespace metro
