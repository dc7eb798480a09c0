// Aligning a separate reference log with the tag log on t_s (docs/accuracy.md, "Reference
// log").
//
// The reference log's clock is taken to run `offset_s` ahead of the tag's:
//   ref_clock = tag_clock + offset_s,  so the reference at a tag observation t is
//   r(t) = interp(t_ref, angle_ref; t + offset_s)
// with linear interpolation taken the short way round (wrap-safe); observations outside
// the reference log's span, or next to an unknown (NaN) reference sample, get NaN.
// With a given offset, that offset is used ("method": "linear interpolation on t_s, given
// offset"). Otherwise it is estimated: the offset on a grid of step_s over
// [-max_offset_s, max_offset_s] that minimises the standard deviation of the residual
//   d(t) = WrapDeg180(tag(t) - r(t))
// over the overlapping observations, refined by a parabola through the grid minimum and
// its neighbours. Motion carries the timing information (a wrong offset puts the turning
// table against a resting tag). The estimate includes the tag's response delay (its DMP
// lag) as well as the clock offset; plateau settling absorbs both.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "metro/core/status.hpp"

namespace metro {

struct AlignmentOptions {
  std::optional<double> offset_s;  // Given offset; empty: estimate.
  double max_offset_s = 5.0;       // Search half-range.
  double step_s = 0.01;            // Search grid.
  // With an estimated offset: estimate the tag's first-order response time tau with it
  // (tag(t) = L_tau[r](t) + error), so that the offset is the clock offset and not the clock
  // offset less the tag's delay.
  bool model_lag = true;
  double max_lag_s = 3.0;  // Largest tau searched.

  bool IsValid(std::string* why) const;
};

struct Alignment {
  std::string method;
  bool estimated = false;
  double offset_s = 0.0;
  double residual_std_deg = 0.0;          // std of d(t) at offset_s (the alignment residual).
  double residual_std_at_zero_deg = 0.0;  // The same at offset 0, for comparison (NaN if no
                                          // overlap there).
  size_t overlap_samples = 0;             // Tag observations with a reference.
  size_t outside_samples = 0;             // Tag observations without one.
  double tag_t_first_s = 0.0, tag_t_last_s = 0.0;
  double reference_t_first_s = 0.0, reference_t_last_s = 0.0;  // Reference clock.
  std::vector<double> reference_deg;  // r(t) per tag observation (NaN outside).
  double delay_s = 0.0;               // The pure-delay estimate (offset less the tag's lag).
  bool lag_modelled = false;          // offset_s and lag_tau_s estimated together.
  double lag_tau_s = 0.0;             // The tag's response time found with the offset.
};

// The tag's first-order response to its input, on the tag's own (irregular) times:
//   y_0 = x_0,  y_k = y_{k-1} + (1 - exp(-(t_k - t_{k-1}) / tau)) WrapDeg180(x_k - y_{k-1})
// (exact for an input held over each step; tau = 0: y = x). A NaN input gives NaN and
// restarts the response at the next known input.
void FirstOrderLag(const std::vector<double>& t_s, const std::vector<double>& input_deg,
                   double tau_s, std::vector<double>* out_deg);

// The tag's response time tau against a reference on the same clock: the tau on a grid of
// step_s over [0, max_tau_s] minimising the standard deviation of tag - L_tau[reference],
// refined by a parabola. Motion carries the information; a sweep without motion gives 0.
struct LagEstimate {
  double tau_s = 0.0;
  double residual_std_deg = 0.0;
  double residual_std_at_zero_deg = 0.0;
  bool at_limit = false;  // The minimum lies at max_tau_s.
};
LagEstimate EstimateLag(const std::vector<double>& t_s, const std::vector<double>& tag_deg,
                        const std::vector<double>& reference_deg, double max_tau_s = 3.0,
                        double step_s = 0.02);

// Errors: empty or mismatched series, logs that do not overlap in time (naming both
// spans), too few overlapping observations, a best offset at the edge of the search range.
Result<Alignment> AlignReference(const std::vector<double>& tag_t_s,
                                 const std::vector<double>& tag_angle_deg,
                                 const std::vector<double>& reference_t_s,
                                 const std::vector<double>& reference_angle_deg,
                                 const AlignmentOptions& options = {});

}  // namespace metro
