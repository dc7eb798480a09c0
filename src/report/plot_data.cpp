#include "metro/report/plot_data.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <optional>
#include <utility>

#include "core/parallel.hpp"
#include "metro/core/angles.hpp"
#include "metro/io/columns.hpp"
#include "metro/report/session_report.hpp"
#include "metro/stats/quantization.hpp"
#include "metro/stats/type_a.hpp"

namespace metro {
namespace {

// `v` to `digits` significant digits, so its JSON text is short and reads back exactly.
double Rounded(double v, int digits) {
  if (!std::isfinite(v) || v == 0.0) return v;
  return std::strtod(fmt::format("{:.{}g}", v, digits).c_str(), nullptr);
}

constexpr int kTimeDigits = 9;
constexpr int kValueDigits = 7;

// The record decimated to the min and max of each bucket, in the order they occur, so a long
// series keeps its envelope. Non-finite values are left out.
void Decimate(const std::vector<double>& t, const std::vector<double>& v, size_t max_points,
              SeriesPlotData* out) {
  const size_t n_pairs = std::min(t.size(), v.size());
  size_t n = 0;
  for (size_t i = 0; i < n_pairs; ++i) n += std::isfinite(v[i]) && std::isfinite(t[i]) ? 1 : 0;
  // The finite pairs' positions: an index only when some pair is not finite (a whole
  // column's index is as large as the column).
  std::vector<size_t> finite;
  if (n < n_pairs) {
    finite.reserve(n);
    for (size_t i = 0; i < n_pairs; ++i) {
      if (std::isfinite(v[i]) && std::isfinite(t[i])) finite.push_back(i);
    }
  }
  auto at = [&](size_t i) { return finite.empty() ? i : finite[i]; };
  auto keep = [&](size_t i) {
    out->t_s.push_back(Rounded(t[i], kTimeDigits));
    out->values.push_back(Rounded(v[i], kValueDigits));
  };
  if (n <= max_points) {
    for (size_t i = 0; i < n; ++i) keep(at(i));
    return;
  }
  const size_t buckets = std::max<size_t>(1, max_points / 2);
  for (size_t b = 0; b < buckets; ++b) {
    const size_t lo = b * n / buckets;
    const size_t hi = (b + 1) * n / buckets;
    if (hi <= lo) continue;
    // The first lowest and the first highest value of the bucket.
    size_t i_min = lo, i_max = lo;
    if (finite.empty()) {
      double v_min = v[lo], v_max = v[lo];
      for (size_t i = lo + 1; i < hi; ++i) {
        const double x = v[i];
        if (x < v_min) {
          v_min = x;
          i_min = i;
        }
        if (x > v_max) {
          v_max = x;
          i_max = i;
        }
      }
    } else {
      for (size_t i = lo; i < hi; ++i) {
        if (v[at(i)] < v[at(i_min)]) i_min = i;
        if (v[at(i)] > v[at(i_max)]) i_max = i;
      }
    }
    keep(at(std::min(i_min, i_max)));
    if (i_min != i_max) keep(at(std::max(i_min, i_max)));
  }
}

// The window's observations as the evaluation used them: finite, angles unwrapped when the
// evaluation unwrapped them. A view into the column when it needs neither (no copy).
struct WindowView {
  std::vector<double> copy;
  const double* data = nullptr;
  size_t size = 0;
  const double* begin() const { return data; }
  const double* end() const { return data + size; }
};

WindowView WindowValues(const Quantity& q, size_t first, size_t end, bool unwrapped) {
  WindowView w;
  const double* begin = q.values.data() + first;
  const double* stop = q.values.data() + end;
  if (!unwrapped && std::all_of(begin, stop, [](double v) { return std::isfinite(v); })) {
    w.data = begin;
    w.size = end - first;
    return w;
  }
  w.copy.assign(begin, stop);
  std::vector<double>& x = w.copy;
  x.erase(std::remove_if(x.begin(), x.end(), [](double v) { return !std::isfinite(v); }), x.end());
  if (unwrapped) UnwrapDegInPlace(&x);
  w.data = x.data();
  w.size = x.size();
  return w;
}

// Bins of the window's values (sqrt(n) of them, 10..60, unless the options fix the number).
// Quantized data (the packets' 0.01 deg, raw counts): bins a whole number of steps wide and
// centred on the steps, never narrower than one step, so no bin is empty or doubled by where
// the lattice falls (the histogram of 0.01 deg data looked non-normal).
HistogramPlotData Histogram(const WindowView& x, double lo, double hi, double mean, bool unwrapped,
                            const PlotDataOptions& options) {
  HistogramPlotData h;
  const size_t n = x.size;
  h.n = static_cast<int64_t>(n);
  int bins = options.histogram_bins > 0
                 ? options.histogram_bins
                 : std::clamp(static_cast<int>(std::sqrt(static_cast<double>(n))), 10, 60);
  double width = (hi - lo) / bins;
  double first_edge = lo;
  const double step = QuantizationStep(x.data, x.size);
  if (step > 0.0) {
    width = std::max(1.0, std::ceil(width / step - 1e-9)) * step;
    first_edge = lo - 0.5 * step;
    bins = std::max(1, static_cast<int>(std::ceil((hi + 0.5 * step - first_edge) / width - 1e-9)));
    h.resolution = step;
  }
  h.counts.assign(static_cast<size_t>(bins), 0);
  for (double v : x) {
    const int b = std::min(bins - 1, static_cast<int>((v - first_edge) / width));
    ++h.counts[static_cast<size_t>(std::max(0, b))];
  }
  for (int b = 0; b <= bins; ++b) h.edges_value.push_back(first_edge + b * width);
  h.density_mean = mean;
  if (unwrapped) {
    double sum = 0.0;
    for (double v : x) sum += v;
    const double sample_mean = sum / static_cast<double>(n);
    h.density_mean = mean + 360.0 * std::round((sample_mean - mean) / 360.0);
  }
  return h;
}

}  // namespace

bool PlotDataOptions::IsValid(std::string* why) const {
  auto fail = [why](const char* message) {
    if (why != nullptr) *why = message;
    return false;
  };
  if (max_quantities < 0) return fail("plot data: max_quantities must be >= 0");
  if (max_series_points < 16) return fail("plot data: max_series_points must be >= 16");
  if (histogram_bins < 0 || histogram_bins > 1000) {
    return fail("plot data: histogram_bins must be 0 (automatic) or 1..1000");
  }
  if (max_autocorrelation_lag < 2) return fail("plot data: max_autocorrelation_lag must be >= 2");
  return true;
}

bool PlotDataOptions::Selects(const std::string& name) const {
  if (quantities.empty()) return !IsQuaternionComponent(name);
  return std::find(quantities.begin(), quantities.end(), name) != quantities.end();
}

Result<QuantityPlotData> ComputeQuantityPlotData(const Tag& tag, const Quantity& q,
                                                 const AppliedWindow& window,
                                                 const QuantityTypeA& result,
                                                 const PlotDataOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) return MakeError(why);
  const size_t n_record = std::min(tag.t_s.size(), q.values.size());
  const size_t first = result.window_begin;
  const size_t end = window.end;
  if (!(first < end && end <= n_record)) {
    return MakeFailedError(
        fmt::format("{}: the window [{}, {}) does not fit the tag's {} observations", result.name,
                    first, end, n_record));
  }
  QuantityPlotData data;
  SeriesPlotData& series = data.series;
  Decimate(tag.t_s, q.values, static_cast<size_t>(options.max_series_points), &series);
  series.n_record = static_cast<int64_t>(n_record);
  series.n_window = static_cast<int64_t>(end - first);
  series.record_first_t_s = Rounded(tag.t_s.front(), kTimeDigits);
  series.record_last_t_s = Rounded(tag.t_s[n_record - 1], kTimeDigits);
  series.window_first_t_s = Rounded(tag.t_s[first], kTimeDigits);
  if (end < n_record) series.window_end_t_s = Rounded(tag.t_s[end], kTimeDigits);

  const bool unwrapped = result.angle_handling == "unwrapped";
  const WindowView x = WindowValues(q, first, end, unwrapped);
  const size_t n = x.size;
  const double s = result.type_a.std;
  double lo = 0.0, hi = 0.0;
  if (n >= 1) {
    const auto [lo_it, hi_it] = std::minmax_element(x.begin(), x.end());
    lo = *lo_it;
    hi = *hi_it;
  }
  const bool spread = n >= 2 && std::isfinite(s) && s > 0.0 && hi > lo;
  if (spread) data.histogram = Histogram(x, lo, hi, result.type_a.mean, unwrapped, options);

  // Sample autocorrelation (the same estimator as the Type A evaluation's n_eff, Zhang 2006).
  const size_t max_lag =
      std::min(static_cast<size_t>(options.max_autocorrelation_lag), n >= 8 ? n / 4 : size_t{0});
  if (spread && max_lag >= 2) {
    std::vector<double> rho(max_lag + 1);
    Autocorrelation(x.data, n, max_lag, rho.data());
    AutocorrelationPlotData a;
    a.n = static_cast<int64_t>(n);
    a.band = 1.96 / std::sqrt(static_cast<double>(n));
    for (size_t k = 1; k <= max_lag; ++k) a.rho.push_back(Rounded(rho[k], kValueDigits));
    data.autocorrelation = std::move(a);
  }
  return data;
}

Result<SessionPlotData> ComputeSessionPlotData(const Session& session, const SessionTypeA& type_a,
                                               const PlotDataOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) return MakeError(why);
  SessionPlotData out;
  // The quantities to plot, in report order (max_quantities counts in this order), then
  // computed at once; the first failure in report order is the one reported.
  struct Job {
    size_t tag_index, quantity_index;
    const Tag* tag;
    const Quantity* column;
  };
  std::vector<Job> jobs;
  for (size_t k = 0; k < type_a.tags.size(); ++k) {
    const TagTypeA& t = type_a.tags[k];
    out.quantities.emplace_back().resize(t.quantities.size());
    const Tag* tag = session.FindTag(t.sensor);
    for (size_t j = 0; j < t.quantities.size(); ++j) {
      const QuantityTypeA& q = t.quantities[j];
      if (!q.ok || !options.Selects(q.name)) continue;
      if (static_cast<int>(jobs.size()) >= options.max_quantities) {
        ++out.not_plotted;
        continue;
      }
      const Quantity* column = tag != nullptr ? tag->Find(q.name) : nullptr;
      if (column == nullptr) {
        return MakeFailedError(fmt::format("plot data: sensor {} has no column {} in {}", t.sensor,
                                           q.name, session.path));
      }
      jobs.push_back({k, j, tag, column});
    }
  }
  std::vector<std::optional<Error>> errors(jobs.size());
  internal::ParallelFor(jobs.size(), options.threads, [&](size_t i) {
    const Job& job = jobs[i];
    const TagTypeA& t = type_a.tags[job.tag_index];
    Result<QuantityPlotData> data = ComputeQuantityPlotData(
        *job.tag, *job.column, t.window, t.quantities[job.quantity_index], options);
    if (!data.ok()) {
      errors[i] = data.error().WithContext(fmt::format("sensor {}", t.sensor));
      return;
    }
    out.quantities[job.tag_index][job.quantity_index] = std::move(data).value();
  });
  for (std::optional<Error>& e : errors) {
    if (e) return std::move(*e);
  }
  return out;
}

Result<int> AddPlotData(const Session& session, const SessionTypeA& type_a,
                        const PlotDataOptions& options, SessionReport* report) {
  Result<SessionPlotData> data = ComputeSessionPlotData(session, type_a, options);
  if (!data.ok()) return data.error();
  for (size_t k = 0; k < type_a.tags.size(); ++k) {
    const TagTypeA& t = type_a.tags[k];
    SensorReport* sensor = nullptr;
    for (SensorReport& s : report->sensors) {
      if (s.sensor == t.sensor) sensor = &s;
    }
    for (size_t j = 0; j < t.quantities.size(); ++j) {
      std::optional<QuantityPlotData>& plot = data.value().quantities[k][j];
      if (!plot) continue;
      QuantityReport* q = sensor != nullptr ? sensor->Find(t.quantities[j].name) : nullptr;
      if (q == nullptr) {
        return MakeFailedError(fmt::format("plot data: the report has no sensor {} quantity {}",
                                           t.sensor, t.quantities[j].name));
      }
      q->plot = std::move(plot);
    }
  }
  return data.value().not_plotted;
}

}  // namespace metro
