#include "session_plots.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

#include "html_common.hpp"
#include "metro/core/angles.hpp"
#include "metro/core/rounding.hpp"
#include "metro/noise/allan.hpp"
#include "metro/noise/noise_model.hpp"
#include "metro/report/svg_plot.hpp"
#include "metro/stats/quantization.hpp"
#include "metro/stats/type_a.hpp"

namespace metro::report_internal {

namespace mustache = kainjow::mustache;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

mustache::data Figure(const std::string& svg, const std::string& caption) {
  mustache::data f;
  f.set("svg", svg);
  f.set("caption", caption);
  return f;
}

// Adds `plot` (or its error as an unavailable note).
void AddPlot(const Result<std::string>& svg, const std::string& caption, QuantityPlots* out) {
  if (svg.ok()) {
    out->plots.push_back(Figure(svg.value(), caption));
  } else {
    out->unavailable.push_back(
        mustache::data(fmt::format("{}: not drawn ({})", caption, svg.error().message)));
  }
}

// The curve of an Allan report with its confidence interval as bars.
PlotSeries AllanCurveSeries(const AllanReport& allan, PlotColor color, const std::string& label) {
  PlotSeries curve;
  curve.style = SeriesStyle::kErrorBars;
  curve.color = color;
  curve.label = label;
  const size_t n =
      std::min({allan.tau_s.size(), allan.adev.size(), allan.ci_low.size(), allan.ci_high.size()});
  curve.x.assign(allan.tau_s.begin(), allan.tau_s.begin() + static_cast<std::ptrdiff_t>(n));
  curve.y.assign(allan.adev.begin(), allan.adev.begin() + static_cast<std::ptrdiff_t>(n));
  curve.y_low.assign(allan.ci_low.begin(), allan.ci_low.begin() + static_cast<std::ptrdiff_t>(n));
  curve.y_high.assign(allan.ci_high.begin(),
                      allan.ci_high.begin() + static_cast<std::ptrdiff_t>(n));
  return curve;
}

// The fitted IEEE Std 952-1997 Annex C model of an "allan" object over the curve's tau range:
// each term sqrt(f_term(tau)) * c (NoiseBasis) and the model sqrt(sum f_term(tau) c^2).
struct AllanModel {
  std::vector<PlotSeries> terms;  // Dashed, one colour per term, labelled with its value.
  PlotSeries total;               // Empty when no term was fitted.
};

AllanModel FitAllanModel(const AllanReport& allan, const std::vector<double>& tau_s) {
  AllanModel model;
  const Result<AllanEstimator> est = ParseAllanEstimator(allan.estimator);
  if (!est.ok() || tau_s.empty()) return model;
  const double tau_lo = *std::min_element(tau_s.begin(), tau_s.end());
  const double tau_hi = *std::max_element(tau_s.begin(), tau_s.end());
  std::vector<double> total_var(60, 0.0);
  std::vector<double> grid(60);
  for (size_t i = 0; i < grid.size(); ++i) {
    grid[i] = tau_lo * std::pow(tau_hi / tau_lo,
                                static_cast<double>(i) / static_cast<double>(grid.size() - 1));
  }
  const PlotColor colors[] = {PlotColor::kGreen, PlotColor::kOrange, PlotColor::kPurple,
                              PlotColor::kRed, PlotColor::kGrey};
  for (NoiseTerm term : kAllNoiseTerms) {
    const std::string key = NoiseTermKey(term);
    const AllanNoiseTermReport& t = allan.term(term);
    const double value = t.value;
    if (!std::isfinite(value) || value <= 0.0) continue;
    PlotSeries line;
    line.style = SeriesStyle::kLine;
    line.dashed = true;
    line.color = colors[static_cast<int>(term)];
    line.label =
        fmt::format("{} = {} {}", key, ShortNumber(t.value_conventional, 3), t.unit_conventional);
    for (size_t i = 0; i < grid.size(); ++i) {
      double factor = 0.0;
      if (!NoiseBasis(est.value(), term, grid[i], &factor)) continue;
      line.x.push_back(grid[i]);
      line.y.push_back(std::sqrt(factor) * value);
      total_var[i] += factor * value * value;
    }
    if (!line.x.empty()) model.terms.push_back(std::move(line));
  }
  if (!model.terms.empty()) {
    model.total.style = SeriesStyle::kLine;
    for (size_t i = 0; i < grid.size(); ++i) {
      model.total.x.push_back(grid[i]);
      model.total.y.push_back(std::sqrt(total_var[i]));
    }
  }
  return model;
}

// True when `name` is <letters><x|y|z>_<unit>; *group is the name with the axis left out
// ("a_g" for ax_g) and *axis the axis letter.
bool AxisOfSensorGroup(const std::string& name, std::string* group, char* axis) {
  const size_t underscore = name.find('_');
  if (underscore == std::string::npos || underscore < 2) return false;
  const char a = name[underscore - 1];
  if (a != 'x' && a != 'y' && a != 'z') return false;
  for (size_t i = 0; i + 1 < underscore; ++i) {
    if (name[i] < 'a' || name[i] > 'z') return false;
  }
  *group = name.substr(0, underscore - 1) + name.substr(underscore);
  *axis = a;
  return true;
}

// The finite range of a plot's x (bands included) or y (hlines and error bars included).
void PlotRange(const XyPlot& p, bool x_axis, double* lo, double* hi) {
  *lo = std::numeric_limits<double>::infinity();
  *hi = -std::numeric_limits<double>::infinity();
  auto add = [lo, hi](double v) {
    if (!std::isfinite(v)) return;
    *lo = std::min(*lo, v);
    *hi = std::max(*hi, v);
  };
  for (const PlotSeries& series : p.series) {
    for (double v : x_axis ? series.x : series.y) add(v);
    if (!x_axis) {
      for (double v : series.y_low) add(v);
      for (double v : series.y_high) add(v);
    }
  }
  for (const PlotBand& b : p.bands) {
    if (x_axis) {
      add(b.x_min);
      add(b.x_max);
    }
  }
  for (const PlotHLine& h : p.hlines) {
    if (!x_axis) add(h.y);
  }
}

// Labels the axes of a linear plot with their name and unit, scaled by a power of 1000 and
// shifted by an offset near `x_center`/`y_center` where the values sit far from zero
// (ChooseAxisScale), so PLplot draws no detached "x10^n" multiplier: "az_g - 0.971 g [1e-3 g]".
// A center of NaN: never an offset.
void ScaleAxes(const std::string& x_name, const std::string& x_unit, double x_center,
               const std::string& y_name, const std::string& y_unit, double y_center, XyPlot* p) {
  double lo = 0.0, hi = 0.0;
  PlotRange(*p, true, &lo, &hi);
  const AxisScale ax = ChooseAxisScale(x_name, x_unit, lo, hi, x_center);
  PlotRange(*p, false, &lo, &hi);
  const AxisScale ay = ChooseAxisScale(y_name, y_unit, lo, hi, y_center);
  for (PlotSeries& series : p->series) {
    for (double& v : series.x) v = ax.To(v);
    for (double& v : series.y) v = ay.To(v);
    for (double& v : series.y_low) v = ay.To(v);
    for (double& v : series.y_high) v = ay.To(v);
  }
  for (PlotBand& b : p->bands) {
    b.x_min = ax.To(b.x_min);
    b.x_max = ax.To(b.x_max);
  }
  for (PlotHLine& h : p->hlines) h.y = ay.To(h.y);
  p->x_label = ax.label;
  p->y_label = ay.label;
}

}  // namespace

void AddSeriesPlots(const QuantityReport& quantity, const QuantityPlotData& data,
                    QuantityPlots* out) {
  const std::string& qname = quantity.name;
  const std::string& unit = quantity.unit;
  const double mean = quantity.type_a ? quantity.type_a->mean : kNaN;
  const double s = quantity.type_a ? quantity.type_a->std : kNaN;
  const SeriesPlotData& series = data.series;

  // Time series with the part outside the window shaded.
  XyPlot ts;
  ts.title = fmt::format("{}: time series", qname);
  const bool cut_start = series.window_first_t_s > series.record_first_t_s;
  if (cut_start) {
    ts.bands.push_back(
        {"excluded (skip/settle)", series.record_first_t_s, series.window_first_t_s});
  }
  if (series.window_end_t_s) {
    ts.bands.push_back(
        {cut_start ? "" : "excluded (window)", *series.window_end_t_s, series.record_last_t_s});
  }
  ts.hlines.push_back({"mean of the window", mean, PlotColor::kRed, true});
  PlotSeries line;
  line.style = SeriesStyle::kLine;
  line.x = series.t_s;
  line.y = series.values;
  ts.series.push_back(std::move(line));
  ScaleAxes("t_s", "s", series.record_first_t_s, qname, unit, mean, &ts);
  AddPlot(RenderXyPlot(ts),
          fmt::format("{} over the whole record; shaded: observations left out of the Type A "
                      "window ({} of {} kept).",
                      qname, series.n_window, series.n_record),
          out);

  if (data.histogram && std::isfinite(s) && s > 0.0) {
    // Histogram as a density, with the normal density N(mean, s^2) of the Type A result.
    const HistogramPlotData& h = *data.histogram;
    const std::vector<double>& edges = h.edges_value;
    const size_t bins = h.counts.size();
    PlotSeries hist;
    hist.style = SeriesStyle::kBins;
    hist.color = PlotColor::kBlue;
    hist.label = "observations (density)";
    hist.x = edges;
    for (size_t b = 0; b < bins; ++b) {
      const double width = edges[b + 1] - edges[b];
      hist.y.push_back(static_cast<double>(h.counts[b]) / (static_cast<double>(h.n) * width));
    }
    PlotSeries normal;
    normal.style = SeriesStyle::kLine;
    normal.color = PlotColor::kRed;
    normal.label = "normal density of the Type A mean and s";
    const double from = std::min(edges.front(), h.density_mean - 4.0 * s);
    const double to = std::max(edges.back(), h.density_mean + 4.0 * s);
    for (int i = 0; i <= 200; ++i) {
      const double v = from + (to - from) * i / 200.0;
      const double z = (v - h.density_mean) / s;
      normal.x.push_back(v);
      normal.y.push_back(std::exp(-0.5 * z * z) / (s * std::sqrt(2.0 * M_PI)));
    }
    XyPlot hp;
    hp.title = fmt::format("{}: histogram", qname);
    hp.series = {std::move(hist), std::move(normal)};
    ScaleAxes(qname, unit, h.density_mean, "density",
              unit.empty() || unit == "1" ? "1" : "1/" + unit, kNaN, &hp);
    AddPlot(RenderXyPlot(hp),
            fmt::format("Histogram of the {} observations in the window ({} bins{}) and the "
                        "normal density with the reported mean and s.",
                        h.n, bins,
                        h.resolution > 0.0 ? fmt::format(", each a whole number of the data's "
                                                         "resolution {:g} {}",
                                                         h.resolution, unit)
                                           : std::string()),
            out);
  }

  // Autocorrelation with the band of white noise and the lags Zhang's n_eff uses.
  if (data.autocorrelation && data.autocorrelation->rho.size() >= 2) {
    const AutocorrelationPlotData& a = *data.autocorrelation;
    const size_t max_lag = a.rho.size();
    XyPlot ap;
    ap.title = fmt::format("{}: autocorrelation", qname);
    const std::optional<int64_t> cutoff =
        quantity.type_a ? quantity.type_a->autocorr_cutoff_lag : std::nullopt;
    if (cutoff && *cutoff >= 1) {
      ap.bands.push_back(
          {fmt::format("lags in n_eff (n_c = {})", *cutoff), 0.5,
           static_cast<double>(std::min<int64_t>(*cutoff, static_cast<int64_t>(max_lag))) + 0.5});
    }
    ap.hlines.push_back({"+-1.96/sqrt(n) (white noise)", a.band, PlotColor::kRed, true});
    ap.hlines.push_back({"", -a.band, PlotColor::kRed, true});
    PlotSeries stems;
    stems.style = SeriesStyle::kStems;
    for (size_t k = 1; k <= max_lag; ++k) {
      stems.x.push_back(static_cast<double>(k));
      stems.y.push_back(a.rho[k - 1]);
    }
    ap.series.push_back(std::move(stems));
    ScaleAxes("lag k", "samples", kNaN, "rho_k", "1", kNaN, &ap);
    AddPlot(RenderXyPlot(ap),
            fmt::format("Sample autocorrelation of the window, lags 1..{}; n_eff = {}.", max_lag,
                        ShortNumber(quantity.type_a ? quantity.type_a->n_eff : kNaN, 4)),
            out);
  }
}

// Allan deviation with its confidence interval and the fitted IEEE 952 terms.
void AddAllanPlot(const QuantityReport& quantity, QuantityPlots* out, mustache::data* terms_table) {
  if (!quantity.allan) return;
  const AllanReport& allan = *quantity.allan;
  if (!allan.ok()) {
    out->unavailable.push_back(mustache::data(fmt::format("Allan deviation: {}", allan.error)));
    return;
  }
  if (allan.tau_s.empty()) return;
  const std::string& qname = quantity.name;
  const std::string& estimator = allan.estimator;
  XyPlot plot;
  plot.title = fmt::format("{}: Allan deviation", qname);
  plot.x_label = "tau [s]";
  plot.y_label = fmt::format("{} [{}]", estimator, quantity.unit);
  plot.log_x = plot.log_y = true;
  PlotSeries curve = AllanCurveSeries(allan, PlotColor::kBlue,
                                      fmt::format("{} with confidence interval", estimator));
  AllanModel model = FitAllanModel(allan, curve.x);
  plot.series.push_back(std::move(curve));
  if (!model.total.x.empty()) {
    model.total.color = PlotColor::kBlack;
    model.total.label = "fitted noise model";
    plot.series.push_back(std::move(model.total));
  }
  for (PlotSeries& term : model.terms) plot.series.push_back(std::move(term));
  // Table of the terms, rounded per GUM 7.2.6.
  for (NoiseTerm term : kAllNoiseTerms) {
    const AllanNoiseTermReport& t = allan.term(term);
    if (!std::isfinite(t.value)) continue;
    const RoundedResult r = RoundForStatement(t.value, t.u);
    const RoundedResult rc = RoundForStatement(t.value_conventional, t.u_conventional);
    mustache::data row;
    row.set("term", NoiseTermKey(term));
    row.set("value", r.value);
    row.set("u", r.uncertainty);
    row.set("unit", t.unit);
    row.set("value_conventional", fmt::format("{} +- {}", rc.value, rc.uncertainty));
    row.set("unit_conventional", t.unit_conventional);
    terms_table->push_back(row);
  }
  AddPlot(RenderXyPlot(plot),
          fmt::format("{} of {} on log-log axes with its confidence interval (bars) and the "
                      "fitted IEEE Std 952-1997 Annex C noise terms (dashed).",
                      estimator, qname),
          out);
  if (allan.fit_error) {
    out->unavailable.push_back(
        mustache::data(fmt::format("noise terms not fitted: {}", *allan.fit_error)));
  }
}

void AddAllanGroupPlots(const SensorReport& sensor, QuantityPlots* out) {
  struct Member {
    char axis;
    const QuantityReport* quantity;
  };
  std::vector<std::pair<std::string, std::vector<Member>>> groups;  // In report order.
  for (const QuantityReport& q : sensor.quantities) {
    std::string group;
    char axis = 0;
    if (!AxisOfSensorGroup(q.name, &group, &axis) || !q.allan || !q.allan->ok() ||
        q.allan->tau_s.empty()) {
      continue;
    }
    auto it = std::find_if(groups.begin(), groups.end(),
                           [&group](const auto& g) { return g.first == group; });
    if (it == groups.end()) it = groups.insert(groups.end(), {group, {}});
    // One unit and one estimator in a plot.
    const QuantityReport& first = it->second.empty() ? q : *it->second.front().quantity;
    if (first.unit != q.unit || first.allan->estimator != q.allan->estimator) continue;
    it->second.push_back({axis, &q});
  }
  for (const auto& group : groups) {
    const std::vector<Member>& members = group.second;
    if (members.size() < 2) continue;
    const std::string& unit = members.front().quantity->unit;
    const std::string& estimator = members.front().quantity->allan->estimator;
    std::string names;
    for (size_t i = 0; i < members.size(); ++i) {
      names += (i == 0 ? "" : i + 1 == members.size() ? " and " : ", ") + members[i].quantity->name;
    }
    XyPlot plot;
    plot.title = fmt::format("{}: Allan deviation", names);
    plot.x_label = "tau [s]";
    plot.y_label = fmt::format("{} [{}]", estimator, unit);
    plot.log_x = plot.log_y = true;
    for (const Member& m : members) {
      const PlotColor color = m.axis == 'x'   ? PlotColor::kBlue
                              : m.axis == 'y' ? PlotColor::kOrange
                                              : PlotColor::kGreen;
      const AllanReport& allan = *m.quantity->allan;
      PlotSeries curve = AllanCurveSeries(allan, color, m.quantity->name);
      AllanModel model = FitAllanModel(allan, curve.x);
      plot.series.push_back(std::move(curve));
      if (!model.total.x.empty()) {
        model.total.color = color;
        model.total.dashed = true;
        plot.series.push_back(std::move(model.total));
      }
    }
    AddPlot(RenderXyPlot(plot),
            fmt::format("{} of {} on log-log axes, one colour per axis: each curve with its "
                        "confidence interval (bars) and its fitted IEEE Std 952-1997 Annex C "
                        "noise model (dashed).",
                        estimator, names),
            out);
  }
}

}  // namespace metro::report_internal
