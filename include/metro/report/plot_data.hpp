// What the session page plots of one quantity, computed once when the session is analysed
// and kept in the report ("plot" of each plotted quantity, docs/report-schema.md), so a page
// is drawn from the report alone: no view reloads the session or guesses how it was loaded.
//
//   series           the whole record, decimated to the min and max of each bucket in the
//                    order they occur (the envelope survives), with the window's bounds;
//   histogram        the window's observations binned, bins a whole number of the data's
//                    resolution wide when it is quantized (never narrower than one step);
//   autocorrelation  the window's sample autocorrelation rho_k, k = 1..L (Zhang 2006's
//                    n_eff sums them), with the white-noise band +-1.96/sqrt(n).
//
// Stored numbers are rounded to what a plot resolves (times to 9 significant digits, values
// to 7), which keeps a 15-tag report's plots near 1 MB.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "metro/core/status.hpp"
#include "metro/io/session.hpp"
#include "metro/stats/session_type_a.hpp"

namespace metro {

struct PlotDataOptions {
  // Quantities that get plot data; empty: every evaluated quantity except the quaternion
  // components qw qx qy qz (their Euler angles are plotted instead).
  std::vector<std::string> quantities;
  int max_quantities = 48;            // Over all tags; the rest are in the tables only.
  int max_series_points = 1000;       // Longer records are kept as min/max per bucket.
  int histogram_bins = 0;             // 0: sqrt(n), clamped to 10..60.
  int max_autocorrelation_lag = 200;  // Also at most n/4.
  int threads = 0;                    // Quantities computed at once; 0: all cores.

  bool IsValid(std::string* why) const;
  // Whether quantity `name` is one the options select (before max_quantities).
  bool Selects(const std::string& name) const;
};

struct SeriesPlotData {
  std::vector<double> t_s;     // Decimated record, in time order.
  std::vector<double> values;  // In the quantity's unit, as loaded (angles not unwrapped).
  int64_t n_record = 0;        // Observations in the record.
  int64_t n_window = 0;        // ... of which the window kept.
  double record_first_t_s = 0.0;
  double record_last_t_s = 0.0;
  double window_first_t_s = 0.0;  // First observation evaluated.
  // First observation after the window; absent when the window runs to the record's end.
  std::optional<double> window_end_t_s;
};

struct HistogramPlotData {
  std::vector<double> edges_value;  // bins + 1 edges, in the quantity's unit.
  std::vector<int64_t> counts;      // Observations per bin.
  int64_t n = 0;                    // Finite observations binned.
  double resolution = 0.0;          // The data's quantization step; 0: not quantized.
  // Where the normal density of the Type A result is drawn: the mean, moved by whole turns
  // for an unwrapped angle so it sits on the unwrapped values.
  double density_mean = 0.0;
};

struct AutocorrelationPlotData {
  std::vector<double> rho;  // rho_1 .. rho_L.
  int64_t n = 0;            // Observations it is computed from.
  double band = 0.0;        // 1.96 / sqrt(n): the white-noise band.
};

struct QuantityPlotData {
  SeriesPlotData series;
  // Absent for fewer than two observations or a constant window.
  std::optional<HistogramPlotData> histogram;
  // Absent for fewer than 8 observations or a constant window.
  std::optional<AutocorrelationPlotData> autocorrelation;
};

// The plot data of quantity `q` of `tag`, whose evaluation `result` (one of the
// TagTypeA `window`'s quantities) kept observations [result.window_begin, window.end).
// Errors: a window outside the tag's observations.
Result<QuantityPlotData> ComputeQuantityPlotData(const Tag& tag, const Quantity& q,
                                                 const AppliedWindow& window,
                                                 const QuantityTypeA& result,
                                                 const PlotDataOptions& options);

// The plot data of a whole analysis, in `type_a`'s order: quantities[k][j] belongs to
// type_a.tags[k].quantities[j]; nullopt for a quantity not evaluated, not selected by the
// options, or beyond max_quantities (counted in `not_plotted`).
struct SessionPlotData {
  std::vector<std::vector<std::optional<QuantityPlotData>>> quantities;
  int not_plotted = 0;
};

// Errors: invalid options, a tag or column of `type_a` missing from `session`, a window
// outside its tag (none of which a SessionTypeA made from `session` has).
Result<SessionPlotData> ComputeSessionPlotData(const Session& session, const SessionTypeA& type_a,
                                               const PlotDataOptions& options);

struct SessionReport;  // metro/report/session_report.hpp

// Computes the plot data (ComputeSessionPlotData) and puts each quantity's into `report`'s
// QuantityReport::plot; `report` was made from `type_a` (same tags and quantity names).
// Returns how many selected quantities were left without plots (max_quantities).
Result<int> AddPlotData(const Session& session, const SessionTypeA& type_a,
                        const PlotDataOptions& options, SessionReport* report);

}  // namespace metro
