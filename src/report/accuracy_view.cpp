// RenderAccuracyHtml fills the "accuracy" template section by section, in the page's order:
//
//   headline      PageCoverage, SetHeadline        input, options, statements, U
//   fit           SetFit                           error plot, fitted parameters
//   points        SetPoints                        one row per plateau
//   analyses      SetSystematicAndLinearity,       systematic error, linearity, hysteresis
//                 SetHysteresis, SetRepeatability  (rows and plot), repeatability
//   cross-axis    SetCrossAxes                     the two other angles' rows and plots
//   the rest      SetBudgetsAndSegmentation        budgets, segmentation, warnings
//
// Each Set* reads the report alone and sets its own template keys.
#include "accuracy_view.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <vector>

#include "accuracy/accuracy_report_json.hpp"
#include "core/json_text.hpp"
#include "html_common.hpp"
#include "html_templates.hpp"
#include "metro/accuracy/error_fit.hpp"
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

// Coverage factor t_{(1+p)/2}(nu) (JCGM 100:2008 G.3.2, 6.2.1); NaN when nu is not > 0.
double CoverageK(double coverage, double dof) {
  if (std::isnan(dof) || dof <= 0.0 || !(coverage > 0.0 && coverage < 1.0)) return kNaN;
  return CoverageFactor(coverage, dof);
}

std::string DofText(double dof) {
  if (std::isinf(dof)) return "inf";
  return ShortNumber(dof, 3);
}

// The fitted curve of a fit: its terms, parameters and covariance.
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

// Drawn only with parameters, each finite; the band only with a covariance of their size.
Curve CurveOf(const HarmonicFit& fit) {
  Curve c;
  if (fit.terms.empty() || fit.params.size() != fit.terms.size()) return c;
  for (double value : fit.params) {
    if (!std::isfinite(value)) return c;
  }
  c.terms = fit.terms;
  c.beta = fit.params;
  if (fit.covariance.size() == fit.terms.size()) c.covariance = fit.covariance;
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

const char* DirectionText(int direction) {
  return direction > 0 ? "up" : direction < 0 ? "down" : "first";
}

Result<std::vector<Point>> PointsOf(const AccuracyReport& report, double coverage) {
  if (report.points.empty()) {
    return MakeError(
        fmt::format("{} report: 'points' is not a non-empty array", kAccuracyReportSchema));
  }
  std::vector<Point> out;
  for (size_t i = 0; i < report.points.size(); ++i) {
    const AccuracyPoint& p = report.points[i];
    Point q;
    q.reference_deg = p.reference_deg;
    q.mean_deg = p.mean_deg;
    q.error_deg = p.error_deg;
    q.u_deg = p.type_a.u_deg;
    q.dof = p.type_a.dof;
    q.direction = DirectionText(p.direction);
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
mustache::data BudgetData(const std::string& title, const ReadingBudget& b) {
  const GumResult& g = b.gum;
  mustache::data d;
  d.set("title", title);
  d.set("u_c", UncertaintyText(g.u));
  d.set("dof_eff", DofText(g.dof_eff));
  d.set("k", ShortNumber(g.k, 3));
  d.set("U", UncertaintyText(g.expanded));
  d.set("coverage", ShortNumber(100.0 * g.coverage, 3));
  d.set("dof_note", g.dof_note);
  std::vector<const BudgetLine*> lines;
  for (const BudgetLine& l : g.budget) lines.push_back(&l);
  // Largest share of u_c^2 first.
  std::stable_sort(lines.begin(), lines.end(), [](const BudgetLine* a, const BudgetLine* c) {
    return (std::isnan(c->percent) ? -1.0 : c->percent) <
           (std::isnan(a->percent) ? -1.0 : a->percent);
  });
  mustache::data rows{mustache::data::type::list};
  BarPlot bars;
  bars.title = fmt::format("{}: share of u_c^2", title);
  bars.x_label = "100 (c_i u_i)^2 / u_c^2 [%]";
  for (const BudgetLine* l : lines) {
    std::string note;
    for (size_t i = 0; i < b.input_names.size() && i < b.notes.size(); ++i) {
      if (b.input_names[i] == l->name) note = b.notes[i];
    }
    mustache::data row;
    row.set("name", l->name);
    row.set("u", UncertaintyText(l->u));
    row.set("distribution", l->distribution);
    row.set("sensitivity", ShortNumber(l->sensitivity, 4));
    row.set("contribution", UncertaintyText(std::fabs(l->contribution)));
    row.set("dof", DofText(l->dof));
    row.set("percent", std::isfinite(l->percent) ? fmt::format("{:.1f}", l->percent) : "-");
    row.set("note", note);
    rows.push_back(row);
    bars.labels.push_back(l->name);
    bars.values.push_back(std::isfinite(l->percent) && l->percent > 0.0 ? l->percent : 0.0);
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

mustache::data InputData(const AccuracyReport& report) {
  const AccuracyReportInput& input = report.input;
  mustache::data rows{mustache::data::type::list};
  auto add = [&rows](const std::string& key, const std::string& value) {
    mustache::data r;
    r.set("key", key);
    r.set("value", value);
    rows.push_back(r);
  };
  add("session", input.session);
  add("SHA-256", input.sha256);
  add("format", input.format);
  add("sensor", std::to_string(input.sensor));
  if (input.tag) {
    add("tag", input.tag->device_id && !input.tag->device_id->empty()
                   ? fmt::format("{}, device ID {}", input.tag->name, *input.tag->device_id)
                   : input.tag->name);
  }
  add("table axis", TableAxisName(input.table_axis));
  add("quantity", input.quantity);
  if (input.reference_log) {
    const Alignment& a = input.reference_log->alignment;
    add("reference log", input.reference_log->file);
    add("reference SHA-256", input.reference_log->sha256);
    add("alignment",
        fmt::format("{} offset {} s ({}); residual std {} deg (at zero offset {} deg); "
                    "{} observations overlap, {} outside",
                    a.method, ShortNumber(a.offset_s, 6), a.estimated ? "estimated" : "given",
                    ShortNumber(a.residual_std_deg, 3), ShortNumber(a.residual_std_at_zero_deg, 3),
                    a.overlap_samples, a.outside_samples));
  } else {
    add("reference", "the session's column table_angle_deg");
  }
  return rows;
}

// ---- headline -----------------------------------------------------------------------------

// The coverage the page states: the corrected budget's, else the options', else 95 %.
double PageCoverage(const AccuracyReport& report) {
  double coverage = report.corrected.gum.coverage;
  if (!(coverage > 0.0 && coverage < 1.0)) coverage = report.options.coverage;
  if (!(coverage > 0.0 && coverage < 1.0)) coverage = 0.95;
  return coverage;
}

// The input, the options and the two statements with their U.
void SetHeadline(const AccuracyReport& report, double coverage, mustache::data* data) {
  const AccuracyReportResult& result = report.result;
  data->set("input_rows", InputData(report));
  // The options as a table, one row per option (as the session page), not a JSON string.
  const mustache::data option_rows = OptionRows(AccuracyOptionsToJsonValue(report.options));
  data->set("option_rows", option_rows);
  data->set("has_options", !option_rows.is_empty_list());
  data->set("statement_corrected", result.statement_corrected);
  data->set("statement_uncorrected", result.statement_uncorrected);
  data->set("result_ok", true);
  data->set("U_corrected", UncertaintyText(report.corrected.gum.expanded));
  data->set("k_corrected", ShortNumber(report.corrected.gum.k, 3));
  data->set("U_uncorrected", UncertaintyText(report.uncorrected.gum.expanded));
  data->set("k_uncorrected", ShortNumber(report.uncorrected.gum.k, 3));
  data->set("U_random", UncertaintyText(result.U_random_deg));
  data->set("U_max_abs", UncertaintyText(result.U_uncorrected_max_abs_deg));
  data->set("coverage", ShortNumber(100.0 * coverage, 3));
  data->set("has_which_u", !result.which_u.empty());
  data->set("which_u", result.which_u);
}

// ---- fit ----------------------------------------------------------------------------------

// The error plot and the fit.
void SetFit(const AccuracyReport& report, const std::vector<Point>& points, double coverage,
            mustache::data* data) {
  const std::string& quantity = report.input.quantity;
  const HarmonicFit& fit = report.fit.fit;
  const std::string fit_model = ErrorModelName(report.fit.model);
  const Curve curve = CurveOf(fit);
  const double fit_dof = static_cast<double>(fit.dof);
  const double k_fit = CoverageK(coverage, fit_dof);
  mustache::data figures{mustache::data::type::list};
  figures.push_back(Figure(
      ErrorPlot(points, curve, k_fit, quantity),
      fmt::format("Plateau errors e_i = mean reading - reference with their expanded "
                  "uncertainty U_i = k_i u_i, k_i = t_{{(1+p)/2}}(nu_i), p = {} % (bars); grey: "
                  "first plateau, blue: the table turning up, orange: turning down. Black: the "
                  "fitted error curve ({}); red dashed: e(theta) +- k u_fit(theta), "
                  "u_fit = sqrt(g^T C g), k = t(nu = {}) = {}.",
                  ShortNumber(100.0 * coverage, 3), fit_model, ShortNumber(fit_dof, 4),
                  ShortNumber(k_fit, 3))));
  data->set("error_figures", figures);
  data->set("has_fit_note", !curve.ok);
  data->set("fit_note", "The report has no usable fitted parameters: the curve is not drawn.");
  mustache::data params{mustache::data::type::list};
  for (size_t i = 0; i < fit.terms.size() && i < fit.params.size() && i < fit.u.size(); ++i) {
    const RoundedResult r = RoundForStatement(fit.params[i], fit.u[i]);
    mustache::data row;
    row.set("name", ErrorTermName(fit.terms[i]));
    row.set("value", r.value);
    row.set("u", r.uncertainty);
    row.set("unit", fit.terms[i] == ErrorTerm::kScale ? "deg/deg" : "deg");
    params.push_back(row);
  }
  data->set("fit_params", params);
  data->set("fit_model", fit_model);
  data->set("fit_equation", report.fit.equation);
  data->set("fit_order_rule", report.fit.order_rule);
  data->set("fit_chi2", ShortNumber(fit.chi2, 4));
  data->set("fit_dof", ShortNumber(fit_dof, 4));
  data->set("fit_reduced_chi2", ShortNumber(fit.reduced_chi2, 3));
  data->set("fit_scaled", fit.covariance_scaled ? "yes" : "no");
  data->set("fit_residual_rms", UncertaintyText(fit.residual_rms_deg));
  data->set("fit_max_prediction_u", UncertaintyText(report.fit.max_prediction_u_deg));
}

// ---- points -------------------------------------------------------------------------------

// Per plateau, rounded per JCGM 100:2008 7.2.6 (the u of each point).
void SetPoints(const AccuracyReport& report, const std::vector<Point>& points,
               mustache::data* data) {
  mustache::data rows{mustache::data::type::list};
  for (size_t i = 0; i < points.size(); ++i) {
    const Point& p = points[i];
    const AccuracyPoint& a = report.points[i];
    const RoundedResult e = RoundForStatement(p.error_deg, p.u_deg);
    const RoundedResult m = RoundForStatement(p.mean_deg, p.u_deg);
    mustache::data row;
    row.set("index", std::to_string(i + 1));
    row.set("reference", ShortNumber(p.reference_deg, 8));
    row.set("direction", p.direction);
    row.set("sweep", std::to_string(a.sweep));
    row.set("n", std::to_string(a.type_a.n));
    row.set("mean", m.value);
    row.set("error", e.value);
    row.set("u", e.uncertainty);
    row.set("n_eff", ShortNumber(a.type_a.n_eff, 3));
    row.set("k", ShortNumber(p.k, 3));
    row.set("U", UncertaintyText(p.expanded_deg));
    row.set("t", fmt::format("{} .. {}", ShortNumber(a.t_start_s, 6), ShortNumber(a.t_end_s, 6)));
    rows.push_back(row);
  }
  data->set("points", rows);
}

// ---- systematic error, linearity, hysteresis, repeatability --------------------------------

void SetSystematicAndLinearity(const AccuracyReport& report, mustache::data* data) {
  const SystematicError& se = report.systematic;
  const Linearity& lin = report.linearity;
  data->set("sys_mean", ShortNumber(se.mean_deg, 3));
  data->set("sys_std", UncertaintyText(se.std_deg));
  data->set("sys_rms", UncertaintyText(se.rms_deg));
  data->set("sys_max", ShortNumber(se.max_abs_deg, 3));
  data->set("sys_at", ShortNumber(se.at_reference_deg, 6));
  data->set("lin_max", ShortNumber(lin.max_abs_deviation_deg, 3));
  data->set("lin_at", ShortNumber(lin.at_reference_deg, 6));
  data->set("lin_rms", UncertaintyText(lin.rms_deviation_deg));
  data->set("lin_percent", ShortNumber(lin.percent_of_span, 3));
}

void SetHysteresis(const AccuracyReport& report, double coverage, mustache::data* data) {
  const Hysteresis& h = report.hysteresis;
  data->set("hysteresis_available", h.available);
  data->set("hysteresis_note", h.note);
  mustache::data h_rows{mustache::data::type::list};
  mustache::data h_figures{mustache::data::type::list};
  if (h.available) {
    const RoundedResult mean = RoundForStatement(h.mean_deg, h.u_mean_deg);
    const RoundedResult max = RoundForStatement(h.max_abs_deg, h.u_max_abs_deg);
    data->set("h_mean", mean.value);
    data->set("h_u_mean", mean.uncertainty);
    data->set("h_max", max.value);
    data->set("h_u_max", max.uncertainty);
    data->set("h_at", ShortNumber(h.at_reference_deg, 6));
    PlotSeries bars;
    bars.style = SeriesStyle::kErrorBars;
    bars.color = PlotColor::kPurple;
    bars.label = "h = mean(up) - mean(down) +- U";
    for (const HysteresisPair& pair : h.pairs) {
      const double k = CoverageK(coverage, pair.dof);
      const RoundedResult r = RoundForStatement(pair.hysteresis_deg, pair.u_deg);
      mustache::data row;
      row.set("reference", ShortNumber(pair.reference_deg, 8));
      row.set("up", ShortNumber(pair.up_error_deg, 4));
      row.set("down", ShortNumber(pair.down_error_deg, 4));
      row.set("h", r.value);
      row.set("u", r.uncertainty);
      row.set("dof", DofText(pair.dof));
      row.set("k", ShortNumber(k, 3));
      row.set("U", UncertaintyText(k * pair.u_deg));
      row.set("plateaus", fmt::format("{} / {}", pair.up_count, pair.down_count));
      h_rows.push_back(row);
      bars.x.push_back(pair.reference_deg);
      bars.y.push_back(pair.hysteresis_deg);
      bars.y_low.push_back(pair.hysteresis_deg - k * pair.u_deg);
      bars.y_high.push_back(pair.hysteresis_deg + k * pair.u_deg);
    }
    if (!bars.x.empty()) {
      XyPlot plot;
      plot.title = "Hysteresis at each angle visited both ways";
      plot.x_label = "reference angle [deg]";
      plot.y_label = "h [deg]";
      plot.series.push_back(std::move(bars));
      plot.hlines.push_back({"", 0.0, PlotColor::kGrey, false});
      plot.hlines.push_back({"weighted mean h", h.mean_deg, PlotColor::kRed, true});
      h_figures.push_back(Figure(
          RenderXyPlot(plot),
          fmt::format("Hysteresis h = mean error turning up - mean error turning down with "
                      "U = k u, k = t_{{(1+p)/2}}(nu) (nu by Welch-Satterthwaite, JCGM 100:2008 "
                      "G.4.1); red dashed: the inverse-variance weighted mean.")));
    }
  }
  data->set("hysteresis_pairs", h_rows);
  data->set("hysteresis_figures", h_figures);
}

void SetRepeatability(const AccuracyReport& report, mustache::data* data) {
  const Repeatability& rp = report.repeatability;
  data->set("repeatability_available", rp.available);
  data->set("s_r", UncertaintyText(rp.available ? rp.s_r_deg : kNaN));
  data->set("s_r_dof", ShortNumber(rp.dof, 4));
  data->set("s_r_groups", std::to_string(rp.groups));
  data->set("s_r_sweeps", std::to_string(rp.sweeps));
  data->set("repeatability_note", rp.note);
}

// ---- cross-axis ---------------------------------------------------------------------------

// Cross-axis: the means of the two axes not turned, per plateau, with the fitted harmonic.
void SetCrossAxes(const AccuracyReport& report, mustache::data* data) {
  const AccuracyReportInput& input = report.input;
  mustache::data cross_rows{mustache::data::type::list};
  mustache::data cross_figures{mustache::data::type::list};
  for (size_t k = 0; k < 2; ++k) {
    const CrossAxis& c = report.cross_axis[k];
    const std::string& name = c.quantity;
    const bool evaluated = report.cross_axis_available;
    mustache::data row;
    row.set("quantity", name);
    row.set("mean", ShortNumber(evaluated ? c.mean_deg : kNaN, 4));
    row.set("span", ShortNumber(evaluated ? c.span_deg : kNaN, 3));
    const bool fitted = evaluated && c.fitted;
    if (fitted) {
      const RoundedResult a = RoundForStatement(c.amplitude_deg, c.u_amplitude_deg);
      row.set("amplitude", fmt::format("{} +- {}", a.value, a.uncertainty));
    } else {
      row.set("amplitude", "not fitted (needs >= 5 distinct angles spanning >= 180 deg)");
    }
    cross_rows.push_back(row);
    PlotSeries means;
    means.style = SeriesStyle::kPoints;
    means.color = PlotColor::kGreen;
    means.label = fmt::format("plateau mean of {}", name);
    for (const AccuracyPoint& p : report.points) {
      const double v = evaluated ? p.other_mean_deg[k] : kNaN;
      if (!std::isfinite(v)) continue;
      means.x.push_back(p.reference_deg);
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
    const Curve harmonic = fitted ? CurveOf(c.fit) : Curve{};
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
                           TableAxisName(input.table_axis),
                           harmonic.ok ? "; black: the fitted first harmonic (a tilt of the turned "
                                         "axis makes it vary once per turn)"
                                       : "")));
  }
  data->set("cross_rows", cross_rows);
  data->set("cross_figures", cross_figures);
}

// ---- budgets, segmentation, warnings --------------------------------------------------------

void SetBudgetsAndSegmentation(const AccuracyReport& report, mustache::data* data) {
  mustache::data budgets{mustache::data::type::list};
  budgets.push_back(BudgetData("Reading corrected by the fitted curve", report.corrected));
  budgets.push_back(BudgetData("Uncorrected reading", report.uncorrected));
  data->set("budgets", budgets);

  // Segmentation.
  const AccuracyReportSegmentation& seg = report.segmentation;
  data->set("seg_plateaus", std::to_string(seg.plateaus));
  data->set("seg_excluded_samples", std::to_string(seg.excluded_samples));
  data->set("seg_excluded_s", ShortNumber(seg.excluded_s, 4));
  data->set("seg_settle_samples", std::to_string(seg.settle_samples));
  mustache::data excluded{mustache::data::type::list};
  size_t shown = 0;
  for (const AccuracyExcludedSpan& e : seg.excluded) {
    if (shown++ >= kMaxExcludedRows) break;
    mustache::data row;
    row.set("t", fmt::format("{} .. {}", ShortNumber(e.t_start_s, 6), ShortNumber(e.t_end_s, 6)));
    row.set("samples", std::to_string(e.samples));
    row.set("reason", e.reason);
    excluded.push_back(row);
  }
  data->set("excluded", excluded);
  const bool more_excluded = seg.excluded.size() > kMaxExcludedRows;
  data->set("has_more_excluded", more_excluded);
  data->set("more_excluded", more_excluded ? fmt::format("... {} more excluded spans in the JSON.",
                                                         seg.excluded.size() - kMaxExcludedRows)
                                           : "");

  mustache::data warnings{mustache::data::type::list};
  for (const std::string& w : report.warnings) warnings.push_back(mustache::data(w));
  data->set("warnings", warnings);
}

}  // namespace

Result<std::string> RenderAccuracyHtml(const AccuracyReport& report, const std::string& json_path) {
  const double coverage = PageCoverage(report);
  Result<std::vector<Point>> parsed = PointsOf(report, coverage);
  if (!parsed.ok()) return parsed.error();
  const std::vector<Point>& points = parsed.value();
  const AccuracyReportInput& input = report.input;
  const std::string& quantity = input.quantity;

  mustache::data data;
  SetHeadline(report, coverage, &data);
  SetFit(report, points, coverage, &data);
  SetPoints(report, points, &data);
  SetSystematicAndLinearity(report, &data);
  SetHysteresis(report, coverage, &data);
  SetRepeatability(report, &data);
  SetCrossAxes(report, &data);
  SetBudgetsAndSegmentation(report, &data);

  Result<std::string> body = RenderTemplate("accuracy", std::move(data));
  if (!body.ok()) return body;
  const std::string name =
      std::filesystem::path(input.session.empty() ? json_path : input.session).filename().string();
  return RenderPage(
      fmt::format("Accuracy report: {}", name),
      fmt::format("{} - tag {} {} against the table ({} axis), {} plateaus - "
                  "sha256 {}",
                  kAccuracyReportSchema, input.sensor, quantity, TableAxisName(input.table_axis),
                  points.size(), input.sha256.substr(0, 16)),
      body.value());
}

}  // namespace metro::report_internal

namespace metro {

Result<std::string> RenderAccuracyReportHtml(const AccuracyReport& report,
                                             const std::string& json_path) {
  return report_internal::RenderAccuracyHtml(report, json_path);
}

Result<std::string> RenderAccuracyReportHtml(std::string_view json_text, const std::string& file) {
  Result<AccuracyReport> report = AccuracyReportFromJson(json_text, file);
  if (!report.ok()) return report.error();
  Result<std::string> html = RenderAccuracyReportHtml(report.value(), file);
  if (!html.ok() && html.error().file.empty()) {
    Error e = html.error();
    e.file = file;  // A report that reads but cannot be drawn: name the file it came from.
    return e;
  }
  return html;
}

}  // namespace metro
