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

using nlohmann::ordered_json;
namespace mustache = kainjow::mustache;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Min and max of each bucket, in the order they occur, so a long series keeps its envelope.
void Decimate(const std::vector<double>& t, const std::vector<double>& v, size_t max_points,
              std::vector<double>* t_out, std::vector<double>* v_out) {
  const size_t n = std::min(t.size(), v.size());
  if (n <= max_points) {
    t_out->assign(t.begin(), t.begin() + static_cast<std::ptrdiff_t>(n));
    v_out->assign(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(n));
    return;
  }
  const size_t buckets = std::max<size_t>(1, max_points / 2);
  for (size_t b = 0; b < buckets; ++b) {
    const size_t lo = b * n / buckets;
    const size_t hi = (b + 1) * n / buckets;
    if (hi <= lo) continue;
    size_t i_min = lo, i_max = lo;
    for (size_t i = lo; i < hi; ++i) {
      if (v[i] < v[i_min]) i_min = i;
      if (v[i] > v[i_max]) i_max = i;
    }
    for (size_t i : {std::min(i_min, i_max), std::max(i_min, i_max)}) {
      t_out->push_back(t[i]);
      v_out->push_back(v[i]);
    }
  }
}

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

// The curve of an "allan" object with its confidence interval as bars.
PlotSeries AllanCurveSeries(const ordered_json& allan, PlotColor color, const std::string& label) {
  PlotSeries curve;
  curve.style = SeriesStyle::kErrorBars;
  curve.color = color;
  curve.label = label;
  const auto& tau = allan["tau_s"];
  for (size_t i = 0; i < tau.size(); ++i) {
    curve.x.push_back(NumberAt(tau, i));
    curve.y.push_back(NumberAt(allan["adev"], i));
    curve.y_low.push_back(NumberAt(allan["ci_low"], i));
    curve.y_high.push_back(NumberAt(allan["ci_high"], i));
  }
  return curve;
}

// The fitted IEEE Std 952-1997 Annex C model of an "allan" object over the curve's tau range:
// each term sqrt(f_term(tau)) * c (NoiseBasis) and the model sqrt(sum f_term(tau) c^2).
struct AllanModel {
  std::vector<PlotSeries> terms;  // Dashed, one colour per term, labelled with its value.
  PlotSeries total;               // Empty when no term was fitted.
};

AllanModel FitAllanModel(const ordered_json& allan, const std::vector<double>& tau_s) {
  AllanModel model;
  const Result<AllanEstimator> est = ParseAllanEstimator(JsonString(allan, "estimator"));
  if (!est.ok() || !allan.contains("noise") || tau_s.empty()) return model;
  const ordered_json& noise = allan["noise"];
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
    if (!noise.contains(key)) continue;
    const ordered_json& t = noise[key];
    const double value = JsonNumber(t, "value");
    if (!std::isfinite(value) || value <= 0.0) continue;
    PlotSeries line;
    line.style = SeriesStyle::kLine;
    line.dashed = true;
    line.color = colors[static_cast<int>(term)];
    line.label = fmt::format("{} = {} {}", key, ShortNumber(JsonNumber(t, "value_conventional"), 3),
                             JsonString(t, "unit_conventional"));
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

void AddSeriesPlots(const ordered_json& sensor, const std::string& qname,
                    const ordered_json& quantity, const Tag& tag, const Quantity& q,
                    const HtmlReportOptions& options, QuantityPlots* out) {
  const std::string unit = JsonString(quantity, "unit");
  const ordered_json& window = sensor["window"];
  const size_t n_total = tag.size();
  size_t first = static_cast<size_t>(JsonNumber(window, "first_index"));
  // `--settle auto` evaluates each quantity from its own settle point.
  if (quantity.contains("window_first_index")) {
    first = static_cast<size_t>(JsonNumber(quantity, "window_first_index"));
  }
  size_t end = static_cast<size_t>(JsonNumber(window, "end_index"));
  if (!(first < end && end <= n_total)) {
    out->unavailable.push_back(mustache::data(
        "time series, histogram and autocorrelation: the report's window does not fit the "
        "session's observations"));
    return;
  }
  const ordered_json& type_a = quantity["type_a"];
  const double mean = JsonNumber(type_a, "mean");
  const double s = JsonNumber(type_a, "std");

  // Time series with the part outside the window shaded.
  XyPlot ts;
  ts.title = fmt::format("{}: time series", qname);
  if (first > 0) ts.bands.push_back({"excluded (skip/settle)", tag.t_s.front(), tag.t_s[first]});
  if (end < n_total) {
    ts.bands.push_back({first > 0 ? "" : "excluded (window)", tag.t_s[end], tag.t_s.back()});
  }
  ts.hlines.push_back({"mean of the window", mean, PlotColor::kRed, true});
  PlotSeries line;
  line.style = SeriesStyle::kLine;
  Decimate(tag.t_s, q.values, static_cast<size_t>(options.max_series_points), &line.x, &line.y);
  ts.series.push_back(std::move(line));
  ScaleAxes("t_s", "s", tag.t_s.front(), qname, unit, mean, &ts);
  AddPlot(RenderXyPlot(ts),
          fmt::format("{} over the whole record; shaded: observations left out of the Type A "
                      "window ({} of {} kept).",
                      qname, end - first, n_total),
          out);

  // The window's values, unwrapped as the evaluation did.
  std::vector<double> x(q.values.begin() + static_cast<std::ptrdiff_t>(first),
                        q.values.begin() + static_cast<std::ptrdiff_t>(end));
  double density_mean = mean;
  if (JsonString(quantity, "angle_handling") == "unwrapped") {
    UnwrapDegInPlace(&x);
    double sum = 0.0;
    for (double v : x) sum += v;
    const double sample_mean = sum / static_cast<double>(x.size());
    density_mean = mean + 360.0 * std::round((sample_mean - mean) / 360.0);
  }
  const size_t n = x.size();
  if (n >= 2 && std::isfinite(s) && s > 0.0) {
    // Histogram as a density, with the normal density N(mean, s^2) of the Type A result.
    const auto [lo_it, hi_it] = std::minmax_element(x.begin(), x.end());
    const double lo = *lo_it, hi = *hi_it;
    int bins = options.histogram_bins > 0
                   ? options.histogram_bins
                   : std::clamp(static_cast<int>(std::sqrt(static_cast<double>(n))), 10, 60);
    double width = hi > lo ? (hi - lo) / bins : 1.0;
    double first_edge = lo;
    // Quantized data (the packets' 0.01 deg, raw counts): bins a whole number of steps wide
    // and centred on the steps, never narrower than one step, so no bin is empty or doubled
    // by where the lattice falls (the histogram of 0.01 deg data looked non-normal).
    const double step = QuantizationStep(x);
    if (step > 0.0 && hi > lo) {
      width = std::max(1.0, std::ceil(width / step - 1e-9)) * step;
      first_edge = lo - 0.5 * step;
      bins =
          std::max(1, static_cast<int>(std::ceil((hi + 0.5 * step - first_edge) / width - 1e-9)));
    }
    PlotSeries hist;
    hist.style = SeriesStyle::kBins;
    hist.color = PlotColor::kBlue;
    hist.label = "observations (density)";
    std::vector<double> counts(static_cast<size_t>(bins), 0.0);
    for (double v : x) {
      const int b = std::min(bins - 1, static_cast<int>((v - first_edge) / width));
      counts[static_cast<size_t>(std::max(0, b))] += 1.0;
    }
    for (int b = 0; b <= bins; ++b) hist.x.push_back(first_edge + b * width);
    for (double c : counts) hist.y.push_back(c / (static_cast<double>(n) * width));
    PlotSeries normal;
    normal.style = SeriesStyle::kLine;
    normal.color = PlotColor::kRed;
    normal.label = "normal density of the Type A mean and s";
    const double from = std::min(lo, density_mean - 4.0 * s);
    const double to = std::max(hi, density_mean + 4.0 * s);
    for (int i = 0; i <= 200; ++i) {
      const double v = from + (to - from) * i / 200.0;
      const double z = (v - density_mean) / s;
      normal.x.push_back(v);
      normal.y.push_back(std::exp(-0.5 * z * z) / (s * std::sqrt(2.0 * M_PI)));
    }
    XyPlot hp;
    hp.title = fmt::format("{}: histogram", qname);
    hp.series = {std::move(hist), std::move(normal)};
    ScaleAxes(qname, unit, density_mean, "density", unit.empty() || unit == "1" ? "1" : "1/" + unit,
              kNaN, &hp);
    AddPlot(RenderXyPlot(hp),
            fmt::format("Histogram of the {} observations in the window ({} bins{}) and the "
                        "normal density with the reported mean and s.",
                        n, bins,
                        step > 0.0 ? fmt::format(", each a whole number of the data's "
                                                 "resolution {:g} {}",
                                                 step, unit)
                                   : std::string()),
            out);
  }

  // Autocorrelation with the band of white noise and the lags Zhang's n_eff uses.
  const size_t max_lag =
      std::min(static_cast<size_t>(options.max_autocorr_lag), n >= 8 ? n / 4 : size_t{0});
  if (max_lag >= 2 && std::isfinite(s) && s > 0.0) {
    std::vector<double> rho(max_lag + 1);
    Autocorrelation(x.data(), n, max_lag, rho.data());
    XyPlot ap;
    ap.title = fmt::format("{}: autocorrelation", qname);
    const double band = 1.96 / std::sqrt(static_cast<double>(n));
    const double cutoff = JsonNumber(type_a, "autocorr_cutoff_lag");
    if (std::isfinite(cutoff) && cutoff >= 1.0) {
      ap.bands.push_back({fmt::format("lags in n_eff (n_c = {:.0f})", cutoff), 0.5,
                          std::min(cutoff, static_cast<double>(max_lag)) + 0.5});
    }
    ap.hlines.push_back({"+-1.96/sqrt(n) (white noise)", band, PlotColor::kRed, true});
    ap.hlines.push_back({"", -band, PlotColor::kRed, true});
    PlotSeries stems;
    stems.style = SeriesStyle::kStems;
    for (size_t k = 1; k <= max_lag; ++k) {
      stems.x.push_back(static_cast<double>(k));
      stems.y.push_back(rho[k]);
    }
    ap.series.push_back(std::move(stems));
    ScaleAxes("lag k", "samples", kNaN, "rho_k", "1", kNaN, &ap);
    AddPlot(RenderXyPlot(ap),
            fmt::format("Sample autocorrelation of the window, lags 1..{}; n_eff = {}.", max_lag,
                        ShortNumber(JsonNumber(type_a, "n_eff"), 4)),
            out);
  }
}

// Allan deviation with its confidence interval and the fitted IEEE 952 terms.
void AddAllanPlot(const std::string& qname, const ordered_json& quantity, QuantityPlots* out,
                  mustache::data* terms_table) {
  const ordered_json& allan = quantity["allan"];
  if (allan.contains("error")) {
    out->unavailable.push_back(
        mustache::data(fmt::format("Allan deviation: {}", JsonString(allan, "error"))));
    return;
  }
  if (!allan.contains("tau_s") || !allan["tau_s"].is_array()) return;
  const std::string unit = JsonString(quantity, "unit");
  const std::string estimator = JsonString(allan, "estimator");
  XyPlot plot;
  plot.title = fmt::format("{}: Allan deviation", qname);
  plot.x_label = "tau [s]";
  plot.y_label = fmt::format("{} [{}]", estimator, unit);
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
  if (allan.contains("noise")) {
    const ordered_json& noise = allan["noise"];
    for (NoiseTerm term : kAllNoiseTerms) {
      const std::string key = NoiseTermKey(term);
      if (!noise.contains(key)) continue;
      const ordered_json& t = noise[key];
      const double value = JsonNumber(t, "value");
      if (!std::isfinite(value)) continue;
      const RoundedResult r = RoundForStatement(value, JsonNumber(t, "u"));
      const RoundedResult rc =
          RoundForStatement(JsonNumber(t, "value_conventional"), JsonNumber(t, "u_conventional"));
      mustache::data row;
      row.set("term", key);
      row.set("value", r.value);
      row.set("u", r.uncertainty);
      row.set("unit", JsonString(t, "unit"));
      row.set("value_conventional", fmt::format("{} +- {}", rc.value, rc.uncertainty));
      row.set("unit_conventional", JsonString(t, "unit_conventional"));
      terms_table->push_back(row);
    }
  }
  AddPlot(RenderXyPlot(plot),
          fmt::format("{} of {} on log-log axes with its confidence interval (bars) and the "
                      "fitted IEEE Std 952-1997 Annex C noise terms (dashed).",
                      estimator, qname),
          out);
  if (allan.contains("fit_error")) {
    out->unavailable.push_back(
        mustache::data(fmt::format("noise terms not fitted: {}", JsonString(allan, "fit_error"))));
  }
}

void AddAllanGroupPlots(const ordered_json& sensor, QuantityPlots* out) {
  if (!sensor.contains("quantities") || !sensor["quantities"].is_object()) return;
  struct Member {
    std::string name;
    char axis;
    const ordered_json* quantity;
  };
  std::vector<std::pair<std::string, std::vector<Member>>> groups;  // In report order.
  for (const auto& [qname, q] : sensor["quantities"].items()) {
    std::string group;
    char axis = 0;
    if (!AxisOfSensorGroup(qname, &group, &axis) || !q.contains("allan") ||
        !q["allan"].contains("tau_s") || !q["allan"]["tau_s"].is_array()) {
      continue;
    }
    auto it = std::find_if(groups.begin(), groups.end(),
                           [&group](const auto& g) { return g.first == group; });
    if (it == groups.end()) it = groups.insert(groups.end(), {group, {}});
    // One unit and one estimator in a plot.
    const Member& first = it->second.empty() ? Member{qname, axis, &q} : it->second.front();
    if (JsonString(*first.quantity, "unit") != JsonString(q, "unit") ||
        JsonString((*first.quantity)["allan"], "estimator") !=
            JsonString(q["allan"], "estimator")) {
      continue;
    }
    it->second.push_back({qname, axis, &q});
  }
  for (const auto& group : groups) {
    const std::vector<Member>& members = group.second;
    if (members.size() < 2) continue;
    const std::string unit = JsonString(*members.front().quantity, "unit");
    const std::string estimator = JsonString((*members.front().quantity)["allan"], "estimator");
    std::string names;
    for (size_t i = 0; i < members.size(); ++i) {
      names += (i == 0 ? "" : i + 1 == members.size() ? " and " : ", ") + members[i].name;
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
      const ordered_json& allan = (*m.quantity)["allan"];
      PlotSeries curve = AllanCurveSeries(allan, color, m.name);
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
