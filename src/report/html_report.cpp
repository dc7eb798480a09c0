#include "metro/report/html_report.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <utility>

#include "accuracy_view.hpp"
#include "html_common.hpp"
#include "html_templates.hpp"
#include "metro/calibration/calibration_io.hpp"
#include "metro/core/angles.hpp"
#include "metro/core/file.hpp"
#include "metro/core/json_text.hpp"
#include "metro/core/rounding.hpp"
#include "metro/io/session_io.hpp"
#include "metro/noise/allan.hpp"
#include "metro/noise/noise_model.hpp"
#include "metro/report/batch.hpp"
#include "metro/report/batch_page.hpp"
#include "metro/report/budget_page.hpp"
#include "metro/report/certificate.hpp"
#include "metro/report/svg_plot.hpp"
#include "metro/report/type_a_report.hpp"
#include "metro/stats/quantization.hpp"
#include "metro/stats/type_a.hpp"

namespace metro {

using nlohmann::ordered_json;
namespace mustache = kainjow::mustache;
using report_internal::JsonNumber;
using report_internal::JsonString;
using report_internal::ShortNumber;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

bool IsQuaternionComponent(const std::string& name) {
  return name == "qw" || name == "qx" || name == "qy" || name == "qz";
}

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

struct QuantityPlots {
  mustache::data plots{mustache::data::type::list};
  mustache::data unavailable{mustache::data::type::list};
};

// Adds `plot` (or its error as an unavailable note).
void AddPlot(const Result<std::string>& svg, const std::string& caption, QuantityPlots* out) {
  if (svg.ok()) {
    out->plots.push_back(Figure(svg.value(), caption));
  } else {
    out->unavailable.push_back(
        mustache::data(fmt::format("{}: not drawn ({})", caption, svg.error().message)));
  }
}

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
  ts.x_label = "t_s [s]";
  ts.y_label = fmt::format("{} [{}]", qname, unit);
  if (first > 0) ts.bands.push_back({"excluded (skip/settle)", tag.t_s.front(), tag.t_s[first]});
  if (end < n_total) {
    ts.bands.push_back({first > 0 ? "" : "excluded (window)", tag.t_s[end], tag.t_s.back()});
  }
  ts.hlines.push_back({"mean of the window", mean, PlotColor::kRed, true});
  PlotSeries line;
  line.style = SeriesStyle::kLine;
  Decimate(tag.t_s, q.values, static_cast<size_t>(options.max_series_points), &line.x, &line.y);
  ts.series.push_back(std::move(line));
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
    hp.x_label = fmt::format("{} [{}]", qname, unit);
    hp.y_label = fmt::format("density [1/{}]", unit.empty() ? "1" : unit);
    hp.series = {std::move(hist), std::move(normal)};
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
    ap.x_label = "lag k [samples]";
    ap.y_label = "rho_k";
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
  PlotSeries curve;
  curve.style = SeriesStyle::kErrorBars;
  curve.color = PlotColor::kBlue;
  const std::string estimator = JsonString(allan, "estimator");
  curve.label = fmt::format("{} with confidence interval", estimator);
  const auto& tau = allan["tau_s"];
  for (size_t i = 0; i < tau.size(); ++i) {
    curve.x.push_back(report_internal::NumberAt(tau, i));
    curve.y.push_back(report_internal::NumberAt(allan["adev"], i));
    curve.y_low.push_back(report_internal::NumberAt(allan["ci_low"], i));
    curve.y_high.push_back(report_internal::NumberAt(allan["ci_high"], i));
  }
  XyPlot plot;
  plot.title = fmt::format("{}: Allan deviation", qname);
  plot.x_label = "tau [s]";
  plot.y_label = fmt::format("{} [{}]", estimator, unit);
  plot.log_x = plot.log_y = true;
  const Result<AllanEstimator> est = ParseAllanEstimator(estimator);
  const ordered_json* noise = allan.contains("noise") ? &allan["noise"] : nullptr;
  if (est.ok() && noise != nullptr && !curve.x.empty()) {
    const double tau_lo = *std::min_element(curve.x.begin(), curve.x.end());
    const double tau_hi = *std::max_element(curve.x.begin(), curve.x.end());
    PlotSeries total;
    total.style = SeriesStyle::kLine;
    total.color = PlotColor::kBlack;
    total.label = "fitted noise model";
    std::vector<double> total_var(60, 0.0);
    std::vector<double> grid(60);
    for (size_t i = 0; i < grid.size(); ++i) {
      grid[i] = tau_lo * std::pow(tau_hi / tau_lo,
                                  static_cast<double>(i) / static_cast<double>(grid.size() - 1));
    }
    const PlotColor colors[] = {PlotColor::kGreen, PlotColor::kOrange, PlotColor::kPurple,
                                PlotColor::kRed, PlotColor::kGrey};
    bool any = false;
    for (NoiseTerm term : kAllNoiseTerms) {
      const std::string key = NoiseTermKey(term);
      if (!noise->contains(key)) continue;
      const ordered_json& t = (*noise)[key];
      const double value = JsonNumber(t, "value");
      if (!std::isfinite(value) || value <= 0.0) continue;
      PlotSeries line;
      line.style = SeriesStyle::kLine;
      line.dashed = true;
      line.color = colors[static_cast<int>(term)];
      line.label =
          fmt::format("{} = {} {}", key, ShortNumber(JsonNumber(t, "value_conventional"), 3),
                      JsonString(t, "unit_conventional"));
      for (size_t i = 0; i < grid.size(); ++i) {
        double factor = 0.0;
        if (!NoiseBasis(est.value(), term, grid[i], &factor)) continue;
        line.x.push_back(grid[i]);
        line.y.push_back(std::sqrt(factor) * value);
        total_var[i] += factor * value * value;
      }
      if (!line.x.empty()) {
        any = true;
        plot.series.push_back(std::move(line));
      }
    }
    if (any) {
      for (size_t i = 0; i < grid.size(); ++i) {
        total.x.push_back(grid[i]);
        total.y.push_back(std::sqrt(total_var[i]));
      }
      plot.series.insert(plot.series.begin(), std::move(total));
    }
    // Table of the terms, rounded per GUM 7.2.6.
    for (NoiseTerm term : kAllNoiseTerms) {
      const std::string key = NoiseTermKey(term);
      if (!noise->contains(key)) continue;
      const ordered_json& t = (*noise)[key];
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
  plot.series.insert(plot.series.begin(), std::move(curve));
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

std::string SettleText(const ordered_json& window) {
  if (!window.contains("settle")) return "none";
  const ordered_json& s = window["settle"];
  // `driver`: the quantity whose cut the tag window takes (each quantity has its own).
  const std::string driver = s.contains("driver") && s["driver"].is_string()
                                 ? fmt::format(", the cut of {}", s["driver"].get<std::string>())
                                 : "";
  return fmt::format("{}: {} samples{}{}", JsonString(s, "method"),
                     ShortNumber(JsonNumber(s, "samples"), 10), driver,
                     s.value("at_limit", false) ? " (at the limit)" : "");
}

// How the file was read (the report's input.dialect, mapping and time), in words: empty for
// a receiver capture, which has none of them.
std::string DialectText(const ordered_json& input) {
  if (!input.contains("dialect") || !input["dialect"].is_object()) return "";
  const ordered_json& d = input["dialect"];
  const std::string delimiter = JsonString(d, "delimiter");
  std::string text = delimiter == "\t"  ? "tab-separated"
                     : delimiter == ";" ? "semicolon-separated"
                     : delimiter == "," ? "comma-separated"
                                        : fmt::format("separated by {}", delimiter);
  if (JsonString(d, "decimal_point") == ",") text += ", decimal comma";
  text += fmt::format(", {} line ends", JsonString(d, "line_ends"));
  if (d.value("bom", false)) text += ", UTF-8 byte-order mark";
  if (d.value("quoted", false)) text += ", quoted fields";
  if (d.value("header_in_comment", false)) text += ", header in a '#' comment";
  return text;
}

std::string MappingText(const ordered_json& input) {
  if (!input.contains("mapping") || !input["mapping"].is_array()) return "";
  std::string text;
  for (const ordered_json& m : input["mapping"]) {
    const std::string canonical = JsonString(m, "canonical");
    text += fmt::format("{}{} \u2192 {}", text.empty() ? "" : "; ", JsonString(m, "source"),
                        canonical.empty() ? "(left out)" : canonical);
  }
  return text;
}

std::string TimeText(const ordered_json& input) {
  if (!input.contains("time") || !input["time"].is_object()) return "";
  const ordered_json& t = input["time"];
  const std::string source = JsonString(t, "source");
  std::string text = t.contains("rate_hz")
                         ? fmt::format("none in the file: sample i at i / {} Hz",
                                       ShortNumber(JsonNumber(t, "rate_hz"), 10))
                         : fmt::format("column {} in {}", source, JsonString(t, "unit"));
  if (t.value("integer", false)) {
    text += fmt::format(", integer (exact), origin {} ns",
                        t.contains("origin_ns") ? JsonText(t["origin_ns"]) : "0");
  }
  if (t.contains("resolution_s")) {
    text +=
        fmt::format(", resolution {} s as written", ShortNumber(JsonNumber(t, "resolution_s"), 3));
  }
  return text;
}

mustache::data StringList(const ordered_json& j, const char* key) {
  mustache::data list{mustache::data::type::list};
  if (j.contains(key) && j[key].is_array()) {
    for (const auto& v : j[key])
      list.push_back(mustache::data(v.is_string() ? v.get<std::string>() : JsonText(v)));
  }
  return list;
}

Status ValidateReport(const ordered_json& report) {
  if (!report.is_object() || report.value("schema", "") != kReportSchema) {
    return MakeError(
        fmt::format("not a {} report (schema key missing or different)", kReportSchema));
  }
  for (const char* key : {"input", "sensors"}) {
    if (!report.contains(key)) {
      return MakeError(fmt::format("{} report: missing key '{}'", kReportSchema, key));
    }
  }
  if (!report["sensors"].is_array()) {
    return MakeError(fmt::format("{} report: 'sensors' is not an array", kReportSchema));
  }
  return Status::Ok();
}

}  // namespace

bool HtmlReportOptions::IsValid(std::string* why) const {
  if (max_plotted_quantities < 0) {
    *why = "html: max_plotted_quantities must be >= 0";
    return false;
  }
  if (max_series_points < 16) {
    *why = "html: max_series_points must be >= 16";
    return false;
  }
  if (histogram_bins < 0 || histogram_bins > 1000) {
    *why = "html: histogram_bins must be in 0..1000";
    return false;
  }
  if (max_autocorr_lag < 2) {
    *why = "html: max_autocorr_lag must be >= 2";
    return false;
  }
  return true;
}

Result<std::string> RenderSessionReportHtml(const ordered_json& report, const Session* session,
                                            const std::string& session_note,
                                            const HtmlReportOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) return MakeError(why);
  if (Status s = ValidateReport(report); !s.ok()) return s.error();
  const ordered_json& input = report["input"];
  mustache::data data;
  data.set("input_path", JsonString(input, "path"));
  data.set("input_sha256", JsonString(input, "sha256"));
  data.set("input_format", JsonString(input, "format"));
  data.set("input_rows", ShortNumber(JsonNumber(input, "rows"), 12));
  data.set("input_rejected_rows", ShortNumber(JsonNumber(input, "rejected_rows"), 12));
  // Each row only when the report has it (a receiver capture has no dialect, a canonical
  // file no mapping): a missing value renders no section.
  for (const auto& [key, text] :
       {std::pair{"input_dialect", DialectText(input)},
        std::pair{"input_mapping", MappingText(input)}, std::pair{"input_time", TimeText(input)}}) {
    if (!text.empty()) data.set(key, text);
  }
  data.set("input_notes", StringList(input, "notes"));
  data.set("input_warnings", StringList(input, "warnings"));
  data.set("window_options", report.contains("options") ? JsonText(report["options"]) : "");
  data.set("session_ok", session != nullptr);
  data.set("session_note", session_note);

  mustache::data summary{mustache::data::type::list};
  mustache::data sensors{mustache::data::type::list};
  int plotted = 0;
  int not_plotted = 0;
  for (const ordered_json& s : report["sensors"]) {
    const int sensor = static_cast<int>(JsonNumber(s, "sensor"));
    const std::string tag_name = JsonString(s, "name");
    const Tag* tag = session != nullptr ? session->FindTag(sensor) : nullptr;
    mustache::data sd;
    sd.set("sensor", std::to_string(sensor));
    sd.set("tag", tag_name);
    sd.set("frames", ShortNumber(JsonNumber(s, "frames"), 12));
    sd.set("fresh", ShortNumber(JsonNumber(s, "fresh"), 12));
    sd.set("stale", ShortNumber(JsonNumber(s, "stale"), 12));
    sd.set("loss", fmt::format("{:.2f} %", 100.0 * JsonNumber(s, "packet_loss_ratio")));
    const ordered_json empty = ordered_json::object();
    const ordered_json& window = s.contains("window") ? s["window"] : empty;
    sd.set("n", ShortNumber(JsonNumber(window, "n"), 12));
    sd.set("n_total", ShortNumber(JsonNumber(window, "n_total"), 12));
    sd.set("t_first_s", ShortNumber(JsonNumber(window, "t_first_s"), 6));
    sd.set("t_last_s", ShortNumber(JsonNumber(window, "t_last_s"), 6));
    sd.set("settle", SettleText(window));
    mustache::data sensor_warnings{mustache::data::type::list};
    if (s.contains("warnings")) {
      for (const auto& w : s["warnings"]) {
        sensor_warnings.push_back(
            mustache::data(w.is_string() ? w.get<std::string>() : JsonText(w)));
      }
    }
    sd.set("warnings", sensor_warnings);
    mustache::data quantities{mustache::data::type::list};
    if (s.contains("quantities") && s["quantities"].is_object()) {
      for (const auto& [qname, q] : s["quantities"].items()) {
        const bool evaluated = q.contains("type_a") && q["type_a"].is_object();
        if (evaluated) {
          const ordered_json& a = q["type_a"];
          const double u = JsonNumber(a, a.contains("u_mean") ? "u_mean" : "std_of_mean_autocorr");
          RoundedResult r = RoundForStatement(JsonNumber(a, "mean"), u);
          const double n = JsonNumber(a, "n");
          const double n_eff = JsonNumber(a, "n_eff");
          // Null in the report (a constant series, n <= 3): not computed, never "nan".
          const std::string not_computed = "not computed";
          if (!std::isfinite(u)) r.uncertainty = not_computed;
          mustache::data row;
          row.set("sensor", std::to_string(sensor));
          row.set("tag", tag_name);
          row.set("quantity", qname);
          row.set("unit", JsonString(q, "unit"));
          row.set("n", ShortNumber(n, 12));
          row.set("mean", r.value);
          row.set("u_mean", r.uncertainty);
          row.set("std", ShortNumber(JsonNumber(a, "std"), 2));
          row.set("n_eff", std::isfinite(n_eff) ? fmt::format("{:.1f}", n_eff) : not_computed);
          row.set("n_eff_ratio",
                  std::isfinite(n_eff) && n > 0 ? fmt::format("{:.3f}", n_eff / n) : not_computed);
          summary.push_back(row);
        }
        const bool wanted =
            options.plot_quantities.empty()
                ? !IsQuaternionComponent(qname)
                : std::find(options.plot_quantities.begin(), options.plot_quantities.end(),
                            qname) != options.plot_quantities.end();
        if (!evaluated || !wanted) continue;
        if (plotted >= options.max_plotted_quantities) {
          ++not_plotted;
          continue;
        }
        ++plotted;
        mustache::data qd;
        qd.set("sensor", std::to_string(sensor));
        qd.set("quantity", qname);
        qd.set("unit", JsonString(q, "unit"));
        mustache::data qwarn{mustache::data::type::list};
        if (q.contains("warnings")) {
          for (const auto& w : q["warnings"]) {
            qwarn.push_back(mustache::data(w.is_string() ? w.get<std::string>() : JsonText(w)));
          }
        }
        qd.set("warnings", qwarn);
        QuantityPlots plots;
        const Quantity* column = tag != nullptr ? tag->Find(qname) : nullptr;
        if (column != nullptr) {
          AddSeriesPlots(s, qname, q, *tag, *column, options, &plots);
        } else {
          plots.unavailable.push_back(mustache::data(fmt::format(
              "time series, histogram and autocorrelation of {}: unavailable ({})", qname,
              session == nullptr ? session_note : "the session has no such tag or column")));
        }
        mustache::data terms{mustache::data::type::list};
        if (q.contains("allan")) AddAllanPlot(qname, q, &plots, &terms);
        qd.set("has_allan_terms", !terms.is_empty_list());
        qd.set("allan_terms", terms);
        qd.set("plots", plots.plots);
        qd.set("unavailable", plots.unavailable);
        quantities.push_back(qd);
      }
    }
    sd.set("quantities", quantities);
    sensors.push_back(sd);
  }
  data.set("summary_rows", summary);
  data.set("sensors", sensors);
  data.set("has_more_quantities", not_plotted > 0);
  data.set("more_quantities",
           fmt::format("{} more quantities are in the tables but not plotted (at most {} are "
                       "plotted).",
                       not_plotted, options.max_plotted_quantities));
  if (report.contains("budget")) {
    Result<mustache::data> budget = report_internal::BudgetViewData(report["budget"]);
    if (!budget.ok()) return budget.error();
    data.set("budget", budget.value());
  } else {
    data.set("budget", false);
  }
  Result<std::string> body = report_internal::RenderTemplate("session", std::move(data));
  if (!body.ok()) return body;
  const std::string file = std::filesystem::path(JsonString(input, "path")).filename().string();
  return report_internal::RenderPage(
      fmt::format("Session report: {}", file),
      fmt::format("{} (GUM Type A{}{}) - sha256 {}", kReportSchema,
                  report_internal::AnyAllan(report) ? ", Allan deviation" : "",
                  report.contains("budget") ? ", uncertainty budget" : "",
                  JsonString(input, "sha256").substr(0, 16)),
      body.value());
}

Result<std::string> RenderSessionAnalysisHtml(const SessionAnalysis& analysis,
                                              const HtmlReportOptions& options) {
  if (!analysis.ok) return MakeError("no HTML report of a failed analysis");
  return RenderSessionReportHtml(
      analysis.report, &analysis.session,
      fmt::format("Plots drawn from the session as analysed ({}).", analysis.session.path),
      options);
}

namespace {

// Reloads the report's session: `explicit_path`, or input.path as given and relative to the
// report's directory. Sets *note to what happened.
std::optional<Session> ReloadReportSession(const ordered_json& report, const std::string& json_path,
                                           const std::string& explicit_path, std::string* note) {
  const ordered_json& input = report["input"];
  const std::string path = JsonString(input, "path");
  const std::string sha256 = JsonString(input, "sha256");
  std::vector<std::string> candidates;
  if (!explicit_path.empty()) {
    candidates.push_back(explicit_path);
  } else if (!path.empty()) {
    candidates.push_back(path);
    const std::filesystem::path dir = std::filesystem::path(json_path).parent_path();
    if (std::filesystem::path(path).is_relative() && !dir.empty()) {
      candidates.push_back((dir / path).string());
    }
  }
  std::vector<std::string> reasons;
  for (const std::string& candidate : candidates) {
    Result<std::string> hash = Sha256File(candidate);
    if (!hash.ok()) {
      reasons.push_back(fmt::format("{}: cannot be read", candidate));
      continue;
    }
    if (hash.value() != sha256) {
      reasons.push_back(
          fmt::format("{}: its SHA-256 {} differs from the report's", candidate, hash.value()));
      continue;
    }
    LoadOptions load;
    if (!ParseSessionFormat(JsonString(input, "format"), &load.format)) {
      load.format = SessionFormat::kAuto;
    }
    // The same columns, time and scales as the report's load (type_a_report's "input").
    if (input.contains("mapping") && input["mapping"].is_array()) {
      for (const auto& m : input["mapping"]) {
        if (m.is_object() && m.value("source", ordered_json()).is_string() &&
            m.value("canonical", ordered_json()).is_string()) {
          load.column_map.push_back(
              {m["source"].get<std::string>(), m["canonical"].get<std::string>()});
        }
      }
    }
    if (input.contains("time") && input["time"].is_object()) {
      const double rate_hz = JsonNumber(input["time"], "rate_hz");
      if (std::isfinite(rate_hz) && rate_hz > 0.0) load.rate_hz = rate_hz;
    }
    if (input.contains("raw_full_scale") && input["raw_full_scale"].is_object()) {
      const double accel = JsonNumber(input["raw_full_scale"], "accel_fs_g");
      const double gyro = JsonNumber(input["raw_full_scale"], "gyro_fs_dps");
      if (std::isfinite(accel) && accel > 0.0) load.accel_fs_g = accel;
      if (std::isfinite(gyro) && gyro > 0.0) load.gyro_fs_dps = gyro;
    }
    load.lenient = JsonNumber(input, "rejected_rows") > 0;
    const double period = JsonNumber(input, "frame_period_s");
    if (std::isfinite(period) && period > 0.0) load.frame_period_s = period;
    load.threads = 1;
    Result<Session> session = LoadSession(candidate, load);
    if (!session.ok()) {
      reasons.push_back(session.error().ToString());
      continue;
    }
    *note = fmt::format(
        "Plots drawn from the session reloaded from {} (SHA-256 matches the "
        "report).",
        candidate);
    return std::move(session).value();
  }
  if (candidates.empty()) reasons.push_back("the report names no input file");
  std::string joined;
  for (const std::string& r : reasons) joined += (joined.empty() ? "" : "; ") + r;
  *note = fmt::format(
      "The session's raw data are not available ({}): the time series, histogram and "
      "autocorrelation plots need them and are omitted; tables, Allan curves and budget bars "
      "come from the JSON alone.",
      joined);
  return std::nullopt;
}

}  // namespace

Result<std::string> RenderJsonHtml(const ordered_json& document, const std::string& json_path,
                                   const std::string& session_path,
                                   const HtmlReportOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) return MakeError(why);
  const std::string schema =
      document.is_object() && document.contains("schema") && document["schema"].is_string()
          ? document["schema"].get<std::string>()
          : "";
  if (schema == kReportSchema) {
    if (Status s = ValidateReport(document); !s.ok()) {
      Error e = s.error();
      e.file = json_path;
      return e;
    }
    std::string note;
    std::optional<Session> session = ReloadReportSession(document, json_path, session_path, &note);
    return RenderSessionReportHtml(document, session ? &*session : nullptr, note, options);
  }
  if (schema == kCalibrationSchema) {
    Result<Calibration> cal =
        CalibrationFromJson(nlohmann::json::parse(JsonText(document)), json_path);
    if (!cal.ok()) return cal.error();
    ReloadedInputs inputs = ReloadCalibrationInputs(cal.value(), json_path);
    std::vector<const Session*> ptrs;
    for (const Session& s : inputs.sessions) ptrs.push_back(&s);
    // The id of the file's own bytes: what `fit` printed and the registry recorded.
    CertificateOptions certificate;
    Result<std::string> sha = Sha256File(json_path);
    if (sha.ok()) certificate.certificate_id = sha.value().substr(0, 16);
    return RenderCalibrationCertificate(cal.value(),
                                        inputs.complete ? ptrs : std::vector<const Session*>{},
                                        inputs.note, certificate);
  }
  if (schema == report_internal::kAccuracyReportSchema) {
    Result<std::string> html = report_internal::RenderAccuracyHtml(document, json_path);
    if (!html.ok() && html.error().file.empty()) {
      Error e = html.error();
      e.file = json_path;
      return e;
    }
    return html;
  }
  if (schema == kBudgetReportSchema) {
    Result<std::string> html = RenderBudgetReportHtml(document);
    if (!html.ok() && html.error().file.empty()) {
      Error e = html.error();
      e.file = json_path;
      return e;
    }
    return html;
  }
  if (schema == kBatchSummarySchema) {
    // The links are relative to the summary's folder, where batch wrote the session pages.
    Result<std::string> html = RenderBatchSummaryHtml(document);
    if (!html.ok() && html.error().file.empty()) {
      Error e = html.error();
      e.file = json_path;
      return e;
    }
    return html;
  }
  if (IsBudgetDefinition(document)) {
    return MakeError(json_path, 0,
                     "this is a budget definition (docs/budget-format.md), not a report: run "
                     "`characterize budget " +
                         json_path + " --html PAGE.html` to evaluate it and write its page");
  }
  return report_internal::RenderGenericHtml(document, json_path, schema);
}

Result<std::string> RenderJsonFileHtml(const std::string& json_path,
                                       const std::string& session_path,
                                       const HtmlReportOptions& options) {
  Result<std::string> text = ReadFile(json_path);
  if (!text.ok()) return text.error();
  Result<ordered_json> document = ParseOrderedJsonText(text.value(), json_path);
  if (!document.ok()) return document.error();
  return RenderJsonHtml(document.value(), json_path, session_path, options);
}

}  // namespace metro
