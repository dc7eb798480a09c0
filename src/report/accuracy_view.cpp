#include "accuracy_view.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <vector>

#include "accuracy/accuracy_report_json.hpp"
#include "html_common.hpp"
#include "html_templates.hpp"
#include "metro/accuracy/error_fit.hpp"
#include "metro/core/json_text.hpp"
#include "metro/core/rounding.hpp"
#include "metro/report/accuracy_page.hpp"
#include "metro/report/svg_plot.hpp"
#include "metro/uncertainty/gum.hpp"

namespace metro::report_internal {

using nlohmann::ordered_json;
namespace mustache = kainjow::mustache;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr int kCurvePoints = 241;
constexpr size_t kMaxExcludedRows = 40;

// A number of the report where null means an infinite dof (docs/accuracy.md).
double Dof(const ordered_json& j, const char* key) {
  if (j.is_object() && j.contains(key) && j[key].is_null()) {
    return std::numeric_limits<double>::infinity();
  }
  return JsonNumber(j, key);
}

// Coverage factor t_{(1+p)/2}(nu) (JCGM 100:2008 G.3.2, 6.2.1); NaN when nu is not > 0.
double CoverageK(double coverage, double dof) {
  if (std::isnan(dof) || dof <= 0.0 || !(coverage > 0.0 && coverage < 1.0)) return kNaN;
  return CoverageFactor(coverage, dof);
}

std::string DofText(double dof) {
  if (std::isinf(dof)) return "inf";
  return ShortNumber(dof, 3);
}

const ordered_json& Member(const ordered_json& j, const char* key) {
  static const ordered_json kEmpty = ordered_json::object();
  return j.is_object() && j.contains(key) ? j[key] : kEmpty;
}

// The fitted curve of a "fit" object: terms by name, parameters and covariance.
struct Curve {
  std::vector<ErrorTerm> terms;
  std::vector<double> beta;
  std::vector<std::vector<double>> covariance;
  bool ok = false;

  double Value(double theta_deg) const {
    double e = 0.0;
    for (size_t i = 0; i < terms.size(); ++i) e += beta[i] * ErrorTermBasis(terms[i], theta_deg);
    return e;
  }
  // u_fit(theta) = sqrt(g^T C g), g_i = basis_i(theta) (JCGM 100:2008 5.2.2).
  double U(double theta_deg) const {
    if (covariance.size() != terms.size()) return kNaN;
    std::vector<double> g(terms.size());
    for (size_t i = 0; i < terms.size(); ++i) g[i] = ErrorTermBasis(terms[i], theta_deg);
    double var = 0.0;
    for (size_t i = 0; i < g.size(); ++i) {
      if (covariance[i].size() != g.size()) return kNaN;
      for (size_t j = 0; j < g.size(); ++j) var += g[i] * covariance[i][j] * g[j];
    }
    return var >= 0.0 ? std::sqrt(var) : kNaN;
  }
};

Curve ParseCurve(const ordered_json& fit) {
  Curve c;
  const ordered_json& params = Member(fit, "params");
  if (!params.is_array() || params.empty()) return c;
  for (const ordered_json& p : params) {
    const std::string name = JsonString(p, "name");
    bool found = false;
    for (ErrorTerm t : {ErrorTerm::kOffset, ErrorTerm::kScale, ErrorTerm::kCos1, ErrorTerm::kSin1,
                        ErrorTerm::kCos2, ErrorTerm::kSin2, ErrorTerm::kHysteresis}) {
      if (name == ErrorTermName(t)) {
        c.terms.push_back(t);
        found = true;
      }
    }
    const double value = JsonNumber(p, "value");
    if (!found || !std::isfinite(value)) return Curve{};
    c.beta.push_back(value);
  }
  const ordered_json& cov = Member(fit, "covariance");
  if (cov.is_array() && cov.size() == c.terms.size()) {
    for (const ordered_json& row : cov) {
      std::vector<double> r;
      if (row.is_array()) {
        for (size_t j = 0; j < row.size(); ++j) r.push_back(NumberAt(row, j));
      }
      c.covariance.push_back(std::move(r));
    }
  }
  c.ok = true;
  return c;
}

mustache::data Figure(const Result<std::string>& svg, const std::string& caption) {
  mustache::data f;
  f.set("svg", svg.ok()
                   ? svg.value()
                   : "<p class=\"note\">Not drawn: " + EscapeHtml(svg.error().message) + "</p>");
  f.set("caption", caption);
  return f;
}

struct Point {
  double reference_deg = kNaN;
  double mean_deg = kNaN;
  double error_deg = kNaN;
  double u_deg = kNaN;
  double dof = kNaN;
  double expanded_deg = kNaN;  // U_i = k_i u_i
  double k = kNaN;
  std::string direction;
};

Result<std::vector<Point>> ParsePoints(const ordered_json& report, double coverage) {
  const ordered_json& points = report["points"];
  if (!points.is_array() || points.empty()) {
    return MakeError(
        fmt::format("{} report: 'points' is not a non-empty array", kAccuracyReportSchema));
  }
  std::vector<Point> out;
  for (size_t i = 0; i < points.size(); ++i) {
    const ordered_json& p = points[i];
    Point q;
    q.reference_deg = JsonNumber(p, "reference_deg");
    q.mean_deg = JsonNumber(p, "mean_deg");
    q.error_deg = JsonNumber(p, "error_deg");
    const ordered_json& a = Member(p, "type_a");
    q.u_deg = JsonNumber(a, "u_deg");
    q.dof = Dof(a, "dof");
    q.direction = JsonString(p, "direction");
    if (!std::isfinite(q.reference_deg) || !std::isfinite(q.error_deg) || !std::isfinite(q.u_deg)) {
      return MakeError(
          fmt::format("{} report: point {} lacks a finite reference_deg, error_deg or type_a.u_deg",
                      kAccuracyReportSchema, i));
    }
    q.k = CoverageK(coverage, q.dof);
    q.expanded_deg = q.k * q.u_deg;
    out.push_back(q);
  }
  return out;
}

// Error against the reference angle: the plateaus with U_i bars per direction, the fitted
// curve and its band.
Result<std::string> ErrorPlot(const std::vector<Point>& points, const Curve& curve, double k_fit,
                              const std::string& quantity) {
  XyPlot plot;
  plot.title = fmt::format("{} error against the reference angle", quantity);
  plot.x_label = "reference angle [deg]";
  plot.y_label = "error = reading - reference [deg]";
  plot.height_px = 420;
  struct Direction {
    const char* name;
    const char* label;
    PlotColor color;
  };
  for (const Direction& d : {Direction{"first", "first plateau", PlotColor::kGrey},
                             Direction{"up", "turning up", PlotColor::kBlue},
                             Direction{"down", "turning down", PlotColor::kOrange}}) {
    PlotSeries s;
    s.style = SeriesStyle::kErrorBars;
    s.color = d.color;
    s.label = fmt::format("{} (+-U_i)", d.label);
    for (const Point& p : points) {
      if (p.direction != d.name) continue;
      s.x.push_back(p.reference_deg);
      s.y.push_back(p.error_deg);
      s.y_low.push_back(p.error_deg - p.expanded_deg);
      s.y_high.push_back(p.error_deg + p.expanded_deg);
    }
    if (!s.x.empty()) plot.series.push_back(std::move(s));
  }
  if (curve.ok) {
    const auto [lo, hi] = std::minmax_element(
        points.begin(), points.end(),
        [](const Point& a, const Point& b) { return a.reference_deg < b.reference_deg; });
    const double from = lo->reference_deg, to = hi->reference_deg;
    PlotSeries line, upper, lower;
    line.style = upper.style = lower.style = SeriesStyle::kLine;
    line.color = PlotColor::kBlack;
    upper.color = lower.color = PlotColor::kRed;
    upper.dashed = lower.dashed = true;
    line.label = "fitted error curve e(theta)";
    upper.label = std::isfinite(k_fit) ? fmt::format("band e +- {:.3g} u_fit(theta)", k_fit)
                                       : "band e +- u_fit(theta)";
    const double k = std::isfinite(k_fit) ? k_fit : 1.0;
    for (int i = 0; i < kCurvePoints; ++i) {
      const double theta = from + (to - from) * i / (kCurvePoints - 1);
      const double e = curve.Value(theta);
      const double u = curve.U(theta);
      line.x.push_back(theta);
      line.y.push_back(e);
      upper.x.push_back(theta);
      upper.y.push_back(e + k * u);
      lower.x.push_back(theta);
      lower.y.push_back(e - k * u);
    }
    plot.series.push_back(std::move(line));
    plot.series.push_back(std::move(upper));
    plot.series.push_back(std::move(lower));
  }
  plot.hlines.push_back({"", 0.0, PlotColor::kGrey, false});
  return RenderXyPlot(plot);
}

// Sorted bars and rounded lines of one single-reading budget.
mustache::data BudgetData(const std::string& title, const ordered_json& b) {
  mustache::data d;
  d.set("title", title);
  d.set("u_c", UncertaintyText(JsonNumber(b, "u_deg")));
  d.set("dof_eff", DofText(Dof(b, "dof_eff")));
  d.set("k", ShortNumber(JsonNumber(b, "k"), 3));
  d.set("U", UncertaintyText(JsonNumber(b, "U_deg")));
  d.set("coverage", ShortNumber(100.0 * JsonNumber(b, "coverage"), 3));
  d.set("dof_note", JsonString(b, "dof_note"));
  std::vector<const ordered_json*> lines;
  const ordered_json& inputs = Member(b, "inputs");
  if (inputs.is_array()) {
    for (const ordered_json& l : inputs) lines.push_back(&l);
  }
  // Largest share of u_c^2 first.
  std::stable_sort(lines.begin(), lines.end(), [](const ordered_json* a, const ordered_json* c) {
    const double pa = JsonNumber(*a, "percent"), pc = JsonNumber(*c, "percent");
    return (std::isnan(pc) ? -1.0 : pc) < (std::isnan(pa) ? -1.0 : pa);
  });
  mustache::data rows{mustache::data::type::list};
  BarPlot bars;
  bars.title = fmt::format("{}: share of u_c^2", title);
  bars.x_label = "100 (c_i u_i)^2 / u_c^2 [%]";
  for (const ordered_json* l : lines) {
    const double percent = JsonNumber(*l, "percent");
    mustache::data row;
    row.set("name", JsonString(*l, "name"));
    row.set("u", UncertaintyText(JsonNumber(*l, "u_deg")));
    row.set("distribution", JsonString(*l, "distribution"));
    row.set("sensitivity", ShortNumber(JsonNumber(*l, "sensitivity"), 4));
    row.set("contribution", UncertaintyText(std::fabs(JsonNumber(*l, "contribution_deg"))));
    row.set("dof", DofText(Dof(*l, "dof")));
    row.set("percent", std::isfinite(percent) ? fmt::format("{:.1f}", percent) : "-");
    row.set("note", JsonString(*l, "note"));
    rows.push_back(row);
    bars.labels.push_back(JsonString(*l, "name"));
    bars.values.push_back(std::isfinite(percent) && percent > 0.0 ? percent : 0.0);
  }
  d.set("lines", rows);
  const Result<std::string> svg = bars.labels.empty()
                                      ? Result<std::string>(MakeError("the budget has no inputs"))
                                      : RenderBarPlot(bars);
  d.set("figure", Figure(svg,
                         "Contribution of each input to the variance of the error of one reading "
                         "(percent), largest first."));
  return d;
}

mustache::data InputData(const ordered_json& report) {
  const ordered_json& input = report["input"];
  mustache::data rows{mustache::data::type::list};
  auto add = [&rows](const std::string& key, const std::string& value) {
    mustache::data r;
    r.set("key", key);
    r.set("value", value);
    rows.push_back(r);
  };
  add("session", JsonString(input, "session"));
  add("SHA-256", JsonString(input, "sha256"));
  add("format", JsonString(input, "format"));
  add("sensor", JsonString(input, "sensor"));
  const ordered_json& tag = Member(input, "tag");
  if (tag.contains("name") && tag["name"].is_string()) {
    const std::string device = JsonString(tag, "device_id");
    add("tag", device.empty() ? JsonString(tag, "name")
                              : fmt::format("{}, device ID {}", JsonString(tag, "name"), device));
  }
  add("table axis", JsonString(input, "table_axis"));
  add("quantity", JsonString(input, "quantity"));
  const ordered_json& ref = Member(input, "reference");
  if (ref.contains("file") && ref["file"].is_string()) {
    add("reference log", JsonString(ref, "file"));
    add("reference SHA-256", JsonString(ref, "sha256"));
    const ordered_json& a = Member(ref, "alignment");
    add("alignment",
        fmt::format("{} offset {} s ({}); residual std {} deg (at zero offset {} deg); "
                    "{} observations overlap, {} outside",
                    JsonString(a, "method"), ShortNumber(JsonNumber(a, "offset_s"), 6),
                    a.value("estimated", false) ? "estimated" : "given",
                    ShortNumber(JsonNumber(a, "residual_std_deg"), 3),
                    ShortNumber(JsonNumber(a, "residual_std_at_zero_offset_deg"), 3),
                    JsonString(a, "overlap_samples"), JsonString(a, "outside_samples")));
  } else {
    add("reference", fmt::format("the session's column {}", JsonString(ref, "column")));
  }
  return rows;
}

}  // namespace

Result<std::string> RenderAccuracyHtml(const ordered_json& report, const std::string& json_path) {
  if (!report.is_object() || report.value("schema", "") != kAccuracyReportSchema) {
    return MakeError(
        fmt::format("not a {} report (schema key missing or different)", kAccuracyReportSchema));
  }
  for (const char* key : {"input", "points", "fit", "budget", "result"}) {
    if (!report.contains(key)) {
      return MakeError(fmt::format("{} report: missing key '{}'", kAccuracyReportSchema, key));
    }
  }
  for (const char* key : {"input", "fit", "budget", "result"}) {
    if (!report[key].is_object()) {
      return MakeError(fmt::format("{} report: '{}' is not an object", kAccuracyReportSchema, key));
    }
  }
  const ordered_json& result = report["result"];
  double coverage = JsonNumber(result, "coverage");
  if (!(coverage > 0.0 && coverage < 1.0))
    coverage = JsonNumber(Member(report, "options"), "coverage");
  if (!(coverage > 0.0 && coverage < 1.0)) coverage = 0.95;
  Result<std::vector<Point>> parsed = ParsePoints(report, coverage);
  if (!parsed.ok()) return parsed.error();
  const std::vector<Point>& points = parsed.value();
  const ordered_json& input = report["input"];
  const std::string quantity = JsonString(input, "quantity");

  mustache::data data;
  data.set("input_rows", InputData(report));
  // The options as a table, one row per option (as the session page), not a JSON string.
  const mustache::data option_rows = OptionRows(Member(report, "options"));
  data.set("option_rows", option_rows);
  data.set("has_options", !option_rows.is_empty_list());
  data.set("statement_corrected", JsonString(result, "statement_corrected"));
  data.set("statement_uncorrected", JsonString(result, "statement_uncorrected"));
  data.set("result_ok", result.value("ok", false));
  data.set("U_corrected", UncertaintyText(JsonNumber(result, "U_corrected_deg")));
  data.set("k_corrected", ShortNumber(JsonNumber(result, "k_corrected"), 3));
  data.set("U_uncorrected", UncertaintyText(JsonNumber(result, "U_uncorrected_deg")));
  data.set("k_uncorrected", ShortNumber(JsonNumber(result, "k_uncorrected"), 3));
  data.set("U_random", UncertaintyText(JsonNumber(result, "U_random_deg")));
  data.set("U_max_abs", UncertaintyText(JsonNumber(result, "U_uncorrected_max_abs_deg")));
  data.set("coverage", ShortNumber(100.0 * coverage, 3));
  const std::string which_u = JsonString(result, "which_U_to_quote");
  data.set("has_which_u", !which_u.empty());
  data.set("which_u", which_u);

  // The error plot and the fit.
  const ordered_json& fit = report["fit"];
  const Curve curve = ParseCurve(fit);
  const double fit_dof = JsonNumber(fit, "dof");
  const double k_fit = CoverageK(coverage, fit_dof);
  mustache::data figures{mustache::data::type::list};
  figures.push_back(Figure(
      ErrorPlot(points, curve, k_fit, quantity),
      fmt::format("Plateau errors e_i = mean reading - reference with their expanded "
                  "uncertainty U_i = k_i u_i, k_i = t_{{(1+p)/2}}(nu_i), p = {} % (bars); grey: "
                  "first plateau, blue: the table turning up, orange: turning down. Black: the "
                  "fitted error curve ({}); red dashed: e(theta) +- k u_fit(theta), "
                  "u_fit = sqrt(g^T C g), k = t(nu = {}) = {}.",
                  ShortNumber(100.0 * coverage, 3), JsonString(fit, "model"),
                  ShortNumber(fit_dof, 4), ShortNumber(k_fit, 3))));
  data.set("error_figures", figures);
  data.set("has_fit_note", !curve.ok);
  data.set("fit_note", "The report has no usable fitted parameters: the curve is not drawn.");
  mustache::data params{mustache::data::type::list};
  for (const ordered_json& p : Member(fit, "params")) {
    const RoundedResult r = RoundForStatement(JsonNumber(p, "value"), JsonNumber(p, "u"));
    mustache::data row;
    row.set("name", JsonString(p, "name"));
    row.set("value", r.value);
    row.set("u", r.uncertainty);
    row.set("unit", JsonString(p, "unit"));
    params.push_back(row);
  }
  data.set("fit_params", params);
  data.set("fit_model", JsonString(fit, "model"));
  data.set("fit_equation", JsonString(fit, "equation"));
  data.set("fit_order_rule", JsonString(fit, "order_rule"));
  data.set("fit_chi2", ShortNumber(JsonNumber(fit, "chi2"), 4));
  data.set("fit_dof", ShortNumber(fit_dof, 4));
  data.set("fit_reduced_chi2", ShortNumber(JsonNumber(fit, "reduced_chi2"), 3));
  data.set("fit_scaled", fit.value("covariance_scaled_by_reduced_chi2", false) ? "yes" : "no");
  data.set("fit_residual_rms", UncertaintyText(JsonNumber(fit, "residual_rms_deg")));
  data.set("fit_max_prediction_u", UncertaintyText(JsonNumber(fit, "max_prediction_u_deg")));

  // Per plateau, rounded per JCGM 100:2008 7.2.6 (the u of each point).
  mustache::data rows{mustache::data::type::list};
  for (size_t i = 0; i < points.size(); ++i) {
    const Point& p = points[i];
    const ordered_json& j = report["points"][i];
    const ordered_json& a = Member(j, "type_a");
    const RoundedResult e = RoundForStatement(p.error_deg, p.u_deg);
    const RoundedResult m = RoundForStatement(p.mean_deg, p.u_deg);
    mustache::data row;
    row.set("index", std::to_string(i + 1));
    row.set("reference", ShortNumber(p.reference_deg, 8));
    row.set("direction", p.direction);
    row.set("sweep", JsonString(j, "sweep"));
    row.set("n", JsonString(a, "n"));
    row.set("mean", m.value);
    row.set("error", e.value);
    row.set("u", e.uncertainty);
    row.set("n_eff", ShortNumber(JsonNumber(a, "n_eff"), 3));
    row.set("k", ShortNumber(p.k, 3));
    row.set("U", UncertaintyText(p.expanded_deg));
    row.set("t", fmt::format("{} .. {}", ShortNumber(JsonNumber(j, "t_start_s"), 6),
                             ShortNumber(JsonNumber(j, "t_end_s"), 6)));
    rows.push_back(row);
  }
  data.set("points", rows);

  // Systematic error and linearity.
  const ordered_json& se = Member(report, "systematic");
  const ordered_json& lin = Member(report, "linearity");
  data.set("sys_mean", ShortNumber(JsonNumber(se, "mean_error_deg"), 3));
  data.set("sys_std", UncertaintyText(JsonNumber(se, "std_error_deg")));
  data.set("sys_rms", UncertaintyText(JsonNumber(se, "rms_error_deg")));
  data.set("sys_max", ShortNumber(JsonNumber(se, "max_abs_error_deg"), 3));
  data.set("sys_at", ShortNumber(JsonNumber(se, "at_reference_deg"), 6));
  data.set("lin_max", ShortNumber(JsonNumber(lin, "max_abs_deviation_deg"), 3));
  data.set("lin_at", ShortNumber(JsonNumber(lin, "at_reference_deg"), 6));
  data.set("lin_rms", UncertaintyText(JsonNumber(lin, "rms_deviation_deg")));
  data.set("lin_percent", ShortNumber(JsonNumber(lin, "percent_of_span"), 3));

  // Hysteresis.
  const ordered_json& h = Member(report, "hysteresis");
  const bool h_available = h.value("available", false);
  data.set("hysteresis_available", h_available);
  data.set("hysteresis_note", JsonString(h, "note"));
  mustache::data h_rows{mustache::data::type::list};
  mustache::data h_figures{mustache::data::type::list};
  if (h_available) {
    const RoundedResult mean =
        RoundForStatement(JsonNumber(h, "mean_deg"), JsonNumber(h, "u_mean_deg"));
    const RoundedResult max =
        RoundForStatement(JsonNumber(h, "max_abs_deg"), JsonNumber(h, "u_max_abs_deg"));
    data.set("h_mean", mean.value);
    data.set("h_u_mean", mean.uncertainty);
    data.set("h_max", max.value);
    data.set("h_u_max", max.uncertainty);
    data.set("h_at", ShortNumber(JsonNumber(h, "at_reference_deg"), 6));
    PlotSeries bars;
    bars.style = SeriesStyle::kErrorBars;
    bars.color = PlotColor::kPurple;
    bars.label = "h = mean(up) - mean(down) +- U";
    for (const ordered_json& pair : Member(h, "pairs")) {
      const double ref = JsonNumber(pair, "reference_deg");
      const double value = JsonNumber(pair, "hysteresis_deg");
      const double u = JsonNumber(pair, "u_deg");
      const double dof = Dof(pair, "dof");
      const double k = CoverageK(coverage, dof);
      const RoundedResult r = RoundForStatement(value, u);
      mustache::data row;
      row.set("reference", ShortNumber(ref, 8));
      row.set("up", ShortNumber(JsonNumber(pair, "up_error_deg"), 4));
      row.set("down", ShortNumber(JsonNumber(pair, "down_error_deg"), 4));
      row.set("h", r.value);
      row.set("u", r.uncertainty);
      row.set("dof", DofText(dof));
      row.set("k", ShortNumber(k, 3));
      row.set("U", UncertaintyText(k * u));
      row.set("plateaus", fmt::format("{} / {}", JsonString(pair, "up_plateaus"),
                                      JsonString(pair, "down_plateaus")));
      h_rows.push_back(row);
      bars.x.push_back(ref);
      bars.y.push_back(value);
      bars.y_low.push_back(value - k * u);
      bars.y_high.push_back(value + k * u);
    }
    if (!bars.x.empty()) {
      XyPlot plot;
      plot.title = "Hysteresis at each angle visited both ways";
      plot.x_label = "reference angle [deg]";
      plot.y_label = "h [deg]";
      plot.series.push_back(std::move(bars));
      plot.hlines.push_back({"", 0.0, PlotColor::kGrey, false});
      plot.hlines.push_back({"weighted mean h", JsonNumber(h, "mean_deg"), PlotColor::kRed, true});
      h_figures.push_back(Figure(
          RenderXyPlot(plot),
          fmt::format("Hysteresis h = mean error turning up - mean error turning down with "
                      "U = k u, k = t_{{(1+p)/2}}(nu) (nu by Welch-Satterthwaite, JCGM 100:2008 "
                      "G.4.1); red dashed: the inverse-variance weighted mean.")));
    }
  }
  data.set("hysteresis_pairs", h_rows);
  data.set("hysteresis_figures", h_figures);

  // Repeatability.
  const ordered_json& rp = Member(report, "repeatability");
  data.set("repeatability_available", rp.value("available", false));
  data.set("s_r", UncertaintyText(JsonNumber(rp, "s_r_deg")));
  data.set("s_r_dof", ShortNumber(JsonNumber(rp, "dof"), 4));
  data.set("s_r_groups", JsonString(rp, "groups"));
  data.set("s_r_sweeps", JsonString(rp, "sweeps"));
  data.set("repeatability_note", JsonString(rp, "note"));

  // Cross-axis: the means of the two axes not turned, per plateau, with the fitted harmonic.
  mustache::data cross_rows{mustache::data::type::list};
  mustache::data cross_figures{mustache::data::type::list};
  const ordered_json& cross = Member(report, "cross_axis");
  for (const auto& [name, c] : cross.items()) {
    mustache::data row;
    row.set("quantity", name);
    row.set("mean", ShortNumber(JsonNumber(c, "mean_deg"), 4));
    row.set("span", ShortNumber(JsonNumber(c, "span_deg"), 3));
    const bool fitted = c.value("fitted", false);
    if (fitted) {
      const RoundedResult a =
          RoundForStatement(JsonNumber(c, "amplitude_deg"), JsonNumber(c, "u_amplitude_deg"));
      row.set("amplitude", fmt::format("{} +- {}", a.value, a.uncertainty));
    } else {
      row.set("amplitude", "not fitted (needs >= 5 distinct angles spanning >= 180 deg)");
    }
    cross_rows.push_back(row);
    PlotSeries means;
    means.style = SeriesStyle::kPoints;
    means.color = PlotColor::kGreen;
    means.label = fmt::format("plateau mean of {}", name);
    for (const ordered_json& p : report["points"]) {
      const double v = JsonNumber(Member(p, "other_axes_mean_deg"), name.c_str());
      if (!std::isfinite(v)) continue;
      means.x.push_back(JsonNumber(p, "reference_deg"));
      means.y.push_back(v);
    }
    if (means.x.empty()) continue;
    XyPlot plot;
    plot.title = fmt::format("Cross-axis: {} against the reference angle", name);
    plot.x_label = "reference angle [deg]";
    plot.y_label = fmt::format("{} [deg]", name);
    const double lo = *std::min_element(means.x.begin(), means.x.end());
    const double hi = *std::max_element(means.x.begin(), means.x.end());
    plot.series.push_back(std::move(means));
    const Curve harmonic = fitted ? ParseCurve(Member(c, "fit")) : Curve{};
    if (harmonic.ok) {
      PlotSeries line;
      line.style = SeriesStyle::kLine;
      line.color = PlotColor::kBlack;
      line.label = "fitted c0 + a1 cos(theta) + b1 sin(theta)";
      for (int i = 0; i < kCurvePoints; ++i) {
        const double theta = lo + (hi - lo) * i / (kCurvePoints - 1);
        line.x.push_back(theta);
        line.y.push_back(harmonic.Value(theta));
      }
      plot.series.push_back(std::move(line));
    }
    cross_figures.push_back(
        Figure(RenderXyPlot(plot),
               fmt::format("Mean of {} on each plateau while the table turns the {} axis{}.", name,
                           JsonString(input, "table_axis"),
                           harmonic.ok ? "; black: the fitted first harmonic (a tilt of the turned "
                                         "axis makes it vary once per turn)"
                                       : "")));
  }
  data.set("cross_rows", cross_rows);
  data.set("cross_figures", cross_figures);

  // Budgets.
  mustache::data budgets{mustache::data::type::list};
  const ordered_json& budget = report["budget"];
  if (budget.contains("corrected")) {
    budgets.push_back(BudgetData("Reading corrected by the fitted curve", budget["corrected"]));
  }
  if (budget.contains("uncorrected")) {
    budgets.push_back(BudgetData("Uncorrected reading", budget["uncorrected"]));
  }
  data.set("budgets", budgets);

  // Segmentation.
  const ordered_json& seg = Member(report, "segmentation");
  data.set("seg_plateaus", JsonString(seg, "plateaus"));
  data.set("seg_excluded_samples", JsonString(seg, "excluded_samples"));
  data.set("seg_excluded_s", ShortNumber(JsonNumber(seg, "excluded_s"), 4));
  data.set("seg_settle_samples", JsonString(seg, "settle_samples"));
  mustache::data excluded{mustache::data::type::list};
  const ordered_json& ex = Member(seg, "excluded");
  size_t shown = 0;
  for (const ordered_json& e : ex) {
    if (shown++ >= kMaxExcludedRows) break;
    mustache::data row;
    row.set("t", fmt::format("{} .. {}", ShortNumber(JsonNumber(e, "t_start_s"), 6),
                             ShortNumber(JsonNumber(e, "t_end_s"), 6)));
    row.set("samples", JsonString(e, "samples"));
    row.set("reason", JsonString(e, "reason"));
    excluded.push_back(row);
  }
  data.set("excluded", excluded);
  const bool more_excluded = ex.is_array() && ex.size() > kMaxExcludedRows;
  data.set("has_more_excluded", more_excluded);
  data.set("more_excluded", more_excluded ? fmt::format("... {} more excluded spans in the JSON.",
                                                        ex.size() - kMaxExcludedRows)
                                          : "");

  mustache::data warnings{mustache::data::type::list};
  for (const ordered_json& w : Member(report, "warnings")) {
    warnings.push_back(mustache::data(w.is_string() ? w.get<std::string>() : JsonText(w)));
  }
  data.set("warnings", warnings);

  Result<std::string> body = RenderTemplate("accuracy", std::move(data));
  if (!body.ok()) return body;
  const std::string session = JsonString(input, "session");
  const std::string name =
      std::filesystem::path(session.empty() ? json_path : session).filename().string();
  return RenderPage(fmt::format("Accuracy report: {}", name),
                    fmt::format("{} - tag {} {} against the table ({} axis), {} plateaus - "
                                "sha256 {}",
                                kAccuracyReportSchema, JsonString(input, "sensor"), quantity,
                                JsonString(input, "table_axis"), points.size(),
                                JsonString(input, "sha256").substr(0, 16)),
                    body.value());
}

}  // namespace metro::report_internal

namespace metro {

Result<std::string> RenderAccuracyReportHtml(const AccuracyReport& report,
                                             const std::string& json_path) {
  return report_internal::RenderAccuracyHtml(ToJsonValue(report), json_path);
}

Result<std::string> RenderAccuracyReportHtml(std::string_view json_text, const std::string& file) {
  Result<AccuracyReport> report = AccuracyReportFromJson(json_text, file);
  if (!report.ok()) return report.error();
  return RenderAccuracyReportHtml(report.value(), file);
}

}  // namespace metro
