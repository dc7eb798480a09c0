// Dwell plateaus of a rotation-table reference (docs/accuracy.md, "Segmentation").
//
// A plateau is a run of observations whose reference angle stays within tolerance_deg of the
// run's first value (compared with the first value, not the neighbour, so a slow creep is
// not taken for rest), lasting at least min_dwell_s with at least min_samples observations.
// Observations with an unknown reference (NaN) end a run. Everything else is motion and is
// excluded (counted and reported). Within a plateau the first settle_s seconds after the
// table stopped are dropped, then, with settle_auto, the tag's own settling found by MSER-5
// (stats/settle.hpp) on its error series. Last, with trim_departures, observations at either
// end whose error departs from the plateau's level (its median) by more than
// departure_sigmas robust standard deviations (1.4826 MAD, at least tolerance_deg) are
// trimmed, plus one more: the tag moving while the reference says it is still (a reference
// clock offset off by a fraction of a second, a slowly sampled reference, a tag still
// settling). A departure longer than max_departure_fraction of the plateau is drift, not
// motion: it is left in place and counted (departure_kept). A plateau with fewer than
// min_samples left is excluded ("too short after settling"); trimmed ends are listed in
// Segmentation::excluded ("tag moving at the plateau's end").
//
// Angle differences are wrap-safe: |WrapDeg180(ref_i - ref_first)|.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "metro/core/status.hpp"

namespace metro {

struct PlateauOptions {
  double tolerance_deg = 0.005;  // Largest reference change within a plateau.
  double min_dwell_s = 3.0;      // Shortest rest that counts as a plateau.
  size_t min_samples = 10;       // Fewest observations left after settling.
  double settle_s = 2.0;         // Always dropped after the table stops.
  // Then MSER-5 on the tag's error series. Off by default: on a short plateau of strongly
  // correlated DMP output without a transient, MSER-5 truncates noise excursions and leaves
  // an optimistic u of the mean (docs/accuracy.md, "Settling").
  bool settle_auto = false;
  // With a modelled lag (FindPlateaus' transient_deg): observations are also dropped until
  // the tag's modelled lag behind the table is within this (deg).
  double settle_lag_residual_deg = 0.002;
  // Trimming of departing ends (on by default; see the header comment).
  bool trim_departures = true;
  double departure_sigmas = 5.0;
  double max_departure_fraction = 0.25;

  bool IsValid(std::string* why) const;
};

struct Plateau {
  size_t rest_begin = 0;        // First observation at rest (index into the series).
  size_t begin = 0;             // First observation used (after settling).
  size_t end = 0;               // One past the last observation used.
  size_t rest_end = 0;          // One past the last observation at rest (>= end).
  size_t settle_samples = 0;    // begin - rest_begin.
  size_t start_trimmed = 0;     // Of settle_samples: trimmed as a departing start.
  size_t end_trimmed = 0;       // rest_end - end: trimmed as a departing end.
  bool departure_kept = false;  // An end departed for longer than max_departure_fraction.
  bool settle_at_limit = false;
  bool settled_by_lag = false;  // The lag rule dropped more than settle_s.
  double t_rest_s = 0.0;        // Time the table stopped (first observation at rest).
  double t_start_s = 0.0;       // First used observation.
  double t_end_s = 0.0;         // Last used observation.
  double reference_deg = 0.0;   // Mean reference angle over the used observations (unwrapped
                                // about the run's first value, so 359.99/0.01 average to 0).
  size_t n() const { return end - begin; }
};

// A stretch of observations left out, with the reason.
struct ExcludedSpan {
  size_t begin = 0;
  size_t end = 0;
  double t_start_s = 0.0;
  double t_end_s = 0.0;
  std::string reason;  // "motion", "rest shorter than min_dwell_s", "reference unknown",
                       // "too short after settling", "tag moving at the plateau's end"
};

struct Segmentation {
  std::vector<Plateau> plateaus;
  std::vector<ExcludedSpan> excluded;
  size_t motion_samples = 0;           // Observations in excluded spans of every reason.
  double motion_s = 0.0;               // Their total time span.
  size_t settle_samples = 0;           // Dropped by settling within plateaus.
  int departure_trimmed_plateaus = 0;  // Plateaus with a departing start or end trimmed.
  size_t departure_trimmed_samples = 0;
  double max_end_trimmed_s = 0.0;  // Longest trimmed end (last kept to first at motion).
  int departure_kept_plateaus = 0;
};

// `t_s` strictly increasing; `reference_deg` (NaN = unknown) and `tag_error_deg` (the tag's
// error against the reference, used for MSER-5) of the same length. Errors: mismatched
// lengths, invalid options, and no plateau found (the message says what to collect).
// `transient_deg` (optional, same length): the tag's modelled lag behind the reference
// (ResponseTransient, accuracy_stages.hpp); a plateau starts no earlier than where it has
// decayed to settle_lag_residual_deg.
Result<Segmentation> FindPlateaus(const std::vector<double>& t_s,
                                  const std::vector<double>& reference_deg,
                                  const std::vector<double>& tag_error_deg,
                                  const PlateauOptions& options = {},
                                  const std::vector<double>* transient_deg = nullptr);

}  // namespace metro
