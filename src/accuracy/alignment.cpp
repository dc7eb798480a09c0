// AlignReference runs these stages, in this order:
//
//   logs     CheckLogs         lengths, sizes, overlap within the searched offsets
//   offset   GridOffset        grid search of the clock offset, parabolic refinement
//   lag      FitOffsetAndLag   with model_lag: offset and first-order response time together
//   result   (driver)          the reference at the tag's times, its residual and overlap
#include "metro/accuracy/alignment.hpp"

#include <fmt/format.h>

#include <algorithm>
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

// Standard deviation of WrapDeg180(tag - L_tau[r]) (FirstOrderLag), `gain` precomputed.
double LaggedResidualStd(const std::vector<double>& tag_a, const std::vector<double>& r,
                         const std::vector<double>& gain, size_t* count) {
  double y = kNaN, mean = 0.0, m2 = 0.0;
  size_t k = 0;
  for (size_t i = 0; i < r.size(); ++i) {
    if (std::isnan(r[i])) {
      y = kNaN;
      continue;
    }
    y = std::isnan(y) ? r[i] : y + gain[i] * WrapDeg180(r[i] - y);
    const double d = WrapDeg180(tag_a[i] - y);
    ++k;
    const double delta = d - mean;
    mean += delta / static_cast<double>(k);
    m2 += delta * (d - mean);
  }
  *count = k;
  return k >= 2 ? std::sqrt(m2 / static_cast<double>(k - 1)) : kNaN;
}

// g_k = 1 - exp(-(t_k - t_{k-1}) / tau), the exact discrete first-order response to an input
// held over the step (1 for tau = 0).
void LagGains(const std::vector<double>& t, double tau_s, std::vector<double>* gain) {
  gain->assign(t.size(), 1.0);
  if (tau_s <= 0.0) return;
  for (size_t i = 1; i < t.size(); ++i) (*gain)[i] = -std::expm1(-(t[i] - t[i - 1]) / tau_s);
}

// Parabola through three equally spaced costs: the vertex's shift in steps, in [-1, 1].
double ParabolaShift(double c0, double c1, double c2) {
  const double curvature = c0 - 2.0 * c1 + c2;
  return curvature > 0.0 ? std::clamp(0.5 * (c0 - c2) / curvature, -1.0, 1.0) : 0.0;
}

}  // namespace

void FirstOrderLag(const std::vector<double>& t_s, const std::vector<double>& input_deg,
                   double tau_s, std::vector<double>* out_deg) {
  std::vector<double> gain;
  LagGains(t_s, tau_s, &gain);
  out_deg->assign(input_deg.size(), kNaN);
  double y = kNaN;
  for (size_t i = 0; i < input_deg.size(); ++i) {
    if (std::isnan(input_deg[i])) {
      y = kNaN;
      continue;
    }
    y = std::isnan(y) ? input_deg[i] : y + gain[i] * WrapDeg180(input_deg[i] - y);
    (*out_deg)[i] = y;
  }
}

LagEstimate EstimateLag(const std::vector<double>& t_s, const std::vector<double>& tag_deg,
                        const std::vector<double>& reference_deg, double max_tau_s, double step_s) {
  LagEstimate e;
  std::vector<double> gain;
  size_t count = 0;
  const int steps = static_cast<int>(std::lround(max_tau_s / step_s));
  std::vector<double> cost(static_cast<size_t>(steps + 1), kNaN);
  int best = 0;
  for (int g = 0; g <= steps; ++g) {
    LagGains(t_s, g * step_s, &gain);
    cost[static_cast<size_t>(g)] = LaggedResidualStd(tag_deg, reference_deg, gain, &count);
    if (cost[static_cast<size_t>(g)] < cost[static_cast<size_t>(best)]) best = g;
  }
  e.residual_std_at_zero_deg = cost[0];
  e.residual_std_deg = cost[static_cast<size_t>(best)];
  double shift = 0.0;
  if (best > 0 && best < steps) {
    shift = ParabolaShift(cost[static_cast<size_t>(best - 1)], cost[static_cast<size_t>(best)],
                          cost[static_cast<size_t>(best + 1)]);
  }
  e.tau_s = std::max(0.0, (best + shift) * step_s);
  e.at_limit = best == steps;
  return e;
}

bool AlignmentOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& m) {
    if (why) *why = m;
    return false;
  };
  if (offset_s && !std::isfinite(*offset_s)) return fail("the reference offset must be finite");
  if (!(max_offset_s > 0.0) || !std::isfinite(max_offset_s)) {
    return fail("max_offset_s must be > 0");
  }
  if (!(max_lag_s >= 0.0) || !std::isfinite(max_lag_s)) return fail("max_lag_s must be >= 0");
  if (!(step_s > 0.0) || !(step_s < max_offset_s)) {
    return fail("step_s must be > 0 and below max_offset_s");
  }
  return true;
}

namespace {

// ---- AlignReference's stages --------------------------------------------------------------

// The two logs.
struct AlignmentInput {
  const std::vector<double>& tag_t_s;
  const std::vector<double>& tag_angle_deg;
  const std::vector<double>& reference_t_s;
  const std::vector<double>& reference_angle_deg;
};

// The logs checked (lengths, at least 2 samples, overlap within the searched offsets): the
// alignment with their spans.
Result<Alignment> CheckLogs(const AlignmentInput& in, const AlignmentOptions& options) {
  if (in.tag_t_s.size() != in.tag_angle_deg.size() ||
      in.reference_t_s.size() != in.reference_angle_deg.size()) {
    return MakeError("alignment: time and angle series differ in length");
  }
  if (in.tag_t_s.size() < 2) return MakeError("the tag log has fewer than 2 observations");
  if (in.reference_t_s.size() < 2) return MakeError("the reference log has fewer than 2 samples");
  Alignment a;
  a.tag_t_first_s = in.tag_t_s.front();
  a.tag_t_last_s = in.tag_t_s.back();
  a.reference_t_first_s = in.reference_t_s.front();
  a.reference_t_last_s = in.reference_t_s.back();
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
  return a;
}

// The clock offset minimising the standard deviation of tag - reference over a grid of
// step_s within +-max_offset_s, refined by a parabola through the best three (a->offset_s,
// a->delay_s). r: scratch for the interpolated reference.
Status GridOffset(const AlignmentInput& in, const AlignmentOptions& options, Alignment* a,
                  std::vector<double>* r) {
  size_t count = 0;
  const int half = static_cast<int>(std::lround(options.max_offset_s / options.step_s));
  std::vector<double> cost(static_cast<size_t>(2 * half + 1), kNaN);
  int best = -1;
  for (int g = -half; g <= half; ++g) {
    Interpolate(in.tag_t_s, in.reference_t_s, in.reference_angle_deg, g * options.step_s, r);
    const double c = ResidualStd(in.tag_angle_deg, *r, &count);
    // Offsets that leave fewer than half the tag observations matched are not candidates.
    if (count * 2 < in.tag_t_s.size()) continue;
    cost[static_cast<size_t>(g + half)] = c;
    if (best < 0 || c < cost[static_cast<size_t>(best)]) best = g + half;
  }
  if (best < 0) {
    return MakeError(fmt::format(
        "the reference log (t_s {:.6g} .. {:.6g} s) covers less than half of the tag log "
        "(t_s {:.6g} .. {:.6g} s) at every offset within +-{} s: record the reference during "
        "the whole sweep",
        a->reference_t_first_s, a->reference_t_last_s, a->tag_t_first_s, a->tag_t_last_s,
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
  a->offset_s = (best - half + shift) * options.step_s;
  a->delay_s = a->offset_s;
  return Status::Ok();
}

// The pure delay d0 is the clock offset less the tag's response delay (a first-order
// lag of tau delays a ramp by tau). Fit both: tag(t) = L_tau[r(. + offset)](t) + e,
// minimising the standard deviation of the residual over (offset, tau), coarse grid
// around offset = d0 + tau, then a fine one around the coarse minimum.
void FitOffsetAndLag(const AlignmentInput& in, const AlignmentOptions& options, Alignment* a,
                     std::vector<double>* r_out) {
  std::vector<double>& r = *r_out;
  std::vector<double> gain;
  auto cost_at = [&](double offset, double tau) {
    LagGains(in.tag_t_s, tau, &gain);
    Interpolate(in.tag_t_s, in.reference_t_s, in.reference_angle_deg, offset, &r);
    size_t n = 0;
    const double c = LaggedResidualStd(in.tag_angle_deg, r, gain, &n);
    return n * 2 < in.tag_t_s.size() ? kNaN : c;
  };
  double best_offset = a->offset_s, best_tau = 0.0;
  double best_cost = cost_at(best_offset, 0.0);
  auto search = [&](double tau_lo, double tau_hi, double tau_step, double off_half, double off_step,
                    bool relative) {
    const double centre_offset = best_offset;
    for (double tau = tau_lo; tau <= tau_hi + 1e-12; tau += tau_step) {
      if (tau < 0.0) continue;
      const double mid = relative ? a->delay_s + tau : centre_offset;
      for (double off = mid - off_half; off <= mid + off_half + 1e-12; off += off_step) {
        const double c = cost_at(off, tau);
        if (c < best_cost) {
          best_cost = c;
          best_offset = off;
          best_tau = tau;
        }
      }
    }
  };
  search(0.0, options.max_lag_s, 0.1, 0.3, 0.02, true);
  search(best_tau - 0.1, best_tau + 0.1, 0.01, 0.04, 0.005, false);
  a->offset_s = best_offset;
  a->lag_tau_s = best_tau;
  a->lag_modelled = true;
  a->method =
      "linear interpolation of the reference at the tag's t_s + offset; offset and the tag's "
      "first-order response time tau estimated together by minimising the standard "
      "deviation of tag - L_tau[reference] (coarse then fine grid)";
}

}  // namespace

Result<Alignment> AlignReference(const std::vector<double>& tag_t_s,
                                 const std::vector<double>& tag_angle_deg,
                                 const std::vector<double>& reference_t_s,
                                 const std::vector<double>& reference_angle_deg,
                                 const AlignmentOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) return MakeError(why);
  const AlignmentInput in{tag_t_s, tag_angle_deg, reference_t_s, reference_angle_deg};
  Result<Alignment> checked = CheckLogs(in, options);
  if (!checked.ok()) return checked.error();
  Alignment a = std::move(checked).value();
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
    if (Status s = GridOffset(in, options, &a, &r); !s.ok()) return s.error();
    if (options.model_lag) FitOffsetAndLag(in, options, &a, &r);
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
