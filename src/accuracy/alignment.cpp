#include "metro/accuracy/alignment.hpp"

#include <fmt/format.h>

#include <cmath>
#include <limits>

#include "metro/core/angles.hpp"

namespace metro {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// r(t + offset) for every tag time (sorted), NaN outside the reference or next to a NaN.
void Interpolate(const std::vector<double>& tag_t, const std::vector<double>& ref_t,
                 const std::vector<double>& ref_a, double offset_s, std::vector<double>* out) {
  out->assign(tag_t.size(), kNaN);
  size_t j = 0;
  const size_t m = ref_t.size();
  for (size_t i = 0; i < tag_t.size(); ++i) {
    const double t = tag_t[i] + offset_s;
    if (t < ref_t.front() || t > ref_t.back()) continue;
    while (j + 1 < m && ref_t[j + 1] < t) ++j;
    if (j + 1 >= m) {
      (*out)[i] = ref_a[j];
      continue;
    }
    const double a0 = ref_a[j], a1 = ref_a[j + 1];
    if (std::isnan(a0) || std::isnan(a1)) continue;
    const double frac = (t - ref_t[j]) / (ref_t[j + 1] - ref_t[j]);
    (*out)[i] = a0 + frac * WrapDeg180(a1 - a0);
  }
}

// Standard deviation of WrapDeg180(tag - r) over the observations with a reference.
double ResidualStd(const std::vector<double>& tag_a, const std::vector<double>& r, size_t* count) {
  double mean = 0.0, m2 = 0.0;
  size_t k = 0;
  for (size_t i = 0; i < r.size(); ++i) {
    if (std::isnan(r[i])) continue;
    const double d = WrapDeg180(tag_a[i] - r[i]);
    ++k;
    const double delta = d - mean;  // Welford
    mean += delta / static_cast<double>(k);
    m2 += delta * (d - mean);
  }
  *count = k;
  return k >= 2 ? std::sqrt(m2 / static_cast<double>(k - 1)) : kNaN;
}

}  // namespace

bool AlignmentOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& m) {
    if (why) *why = m;
    return false;
  };
  if (offset_s && !std::isfinite(*offset_s)) return fail("the reference offset must be finite");
  if (!(max_offset_s > 0.0) || !std::isfinite(max_offset_s)) {
    return fail("max_offset_s must be > 0");
  }
  if (!(step_s > 0.0) || !(step_s < max_offset_s)) {
    return fail("step_s must be > 0 and below max_offset_s");
  }
  return true;
}

Result<Alignment> AlignReference(const std::vector<double>& tag_t_s,
                                 const std::vector<double>& tag_angle_deg,
                                 const std::vector<double>& reference_t_s,
                                 const std::vector<double>& reference_angle_deg,
                                 const AlignmentOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) return MakeError(why);
  if (tag_t_s.size() != tag_angle_deg.size() ||
      reference_t_s.size() != reference_angle_deg.size()) {
    return MakeError("alignment: time and angle series differ in length");
  }
  if (tag_t_s.size() < 2) return MakeError("the tag log has fewer than 2 observations");
  if (reference_t_s.size() < 2) return MakeError("the reference log has fewer than 2 samples");
  Alignment a;
  a.tag_t_first_s = tag_t_s.front();
  a.tag_t_last_s = tag_t_s.back();
  a.reference_t_first_s = reference_t_s.front();
  a.reference_t_last_s = reference_t_s.back();
  const double centre = options.offset_s.value_or(0.0);
  const double reach = options.offset_s ? 0.0 : options.max_offset_s;
  // Overlap over the whole search range: tag [t0, t1] against reference [r0 - o, r1 - o].
  if (a.reference_t_first_s - (centre + reach) > a.tag_t_last_s ||
      a.reference_t_last_s - (centre - reach) < a.tag_t_first_s) {
    return MakeError(fmt::format(
        "the reference log (t_s {:.6g} .. {:.6g} s) does not overlap the tag log (t_s {:.6g} .. "
        "{:.6g} s){}: record the reference during the same sweep on the same clock, or give "
        "the clock offset with --reference-offset-s",
        a.reference_t_first_s, a.reference_t_last_s, a.tag_t_first_s, a.tag_t_last_s,
        options.offset_s ? fmt::format(" at offset {} s", *options.offset_s)
                         : fmt::format(" within +-{} s", options.max_offset_s)));
  }
  std::vector<double> r;
  size_t count = 0;
  Interpolate(tag_t_s, reference_t_s, reference_angle_deg, 0.0, &r);
  a.residual_std_at_zero_deg = ResidualStd(tag_angle_deg, r, &count);
  if (options.offset_s) {
    a.method = "linear interpolation of the reference at the tag's t_s + offset (given offset)";
    a.offset_s = *options.offset_s;
  } else {
    a.method =
        "linear interpolation of the reference at the tag's t_s + offset; offset estimated by "
        "minimising the standard deviation of tag - reference over a grid, parabolic refinement";
    a.estimated = true;
    const int half = static_cast<int>(std::lround(options.max_offset_s / options.step_s));
    std::vector<double> cost(static_cast<size_t>(2 * half + 1), kNaN);
    int best = -1;
    for (int g = -half; g <= half; ++g) {
      Interpolate(tag_t_s, reference_t_s, reference_angle_deg, g * options.step_s, &r);
      const double c = ResidualStd(tag_angle_deg, r, &count);
      // Offsets that leave fewer than half the tag observations matched are not candidates.
      if (count * 2 < tag_t_s.size()) continue;
      cost[static_cast<size_t>(g + half)] = c;
      if (best < 0 || c < cost[static_cast<size_t>(best)]) best = g + half;
    }
    if (best < 0) {
      return MakeError(fmt::format(
          "the reference log (t_s {:.6g} .. {:.6g} s) covers less than half of the tag log "
          "(t_s {:.6g} .. {:.6g} s) at every offset within +-{} s: record the reference during "
          "the whole sweep",
          a.reference_t_first_s, a.reference_t_last_s, a.tag_t_first_s, a.tag_t_last_s,
          options.max_offset_s));
    }
    if (best == 0 || best == 2 * half || std::isnan(cost[static_cast<size_t>(best - 1)]) ||
        std::isnan(cost[static_cast<size_t>(best + 1)])) {
      return MakeError(fmt::format(
          "the reference log could not be aligned: the best clock offset lies at the edge of "
          "the searched range ({:.6g} s of +-{} s); give it with --reference-offset-s",
          (best - half) * options.step_s, options.max_offset_s));
    }
    const double c0 = cost[static_cast<size_t>(best - 1)];
    const double c1 = cost[static_cast<size_t>(best)];
    const double c2 = cost[static_cast<size_t>(best + 1)];
    const double curvature = c0 - 2.0 * c1 + c2;
    const double shift = curvature > 0.0 ? 0.5 * (c0 - c2) / curvature : 0.0;
    a.offset_s = (best - half + shift) * options.step_s;
  }
  Interpolate(tag_t_s, reference_t_s, reference_angle_deg, a.offset_s, &r);
  a.residual_std_deg = ResidualStd(tag_angle_deg, r, &count);
  a.overlap_samples = count;
  a.outside_samples = tag_t_s.size() - count;
  if (count < 2) {
    return MakeError(fmt::format(
        "the reference log (t_s {:.6g} .. {:.6g} s) does not overlap the tag log (t_s {:.6g} .. "
        "{:.6g} s) at offset {} s: record the reference during the same sweep",
        a.reference_t_first_s, a.reference_t_last_s, a.tag_t_first_s, a.tag_t_last_s, a.offset_s));
  }
  a.reference_deg = std::move(r);
  return a;
}

}  // namespace metro
