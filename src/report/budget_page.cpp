#include "metro/report/budget_page.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "budget_view.hpp"
#include "core/json_text.hpp"
#include "html_common.hpp"
#include "html_templates.hpp"
#include "metro/core/rounding.hpp"
#include "metro/report/svg_plot.hpp"

namespace metro {
namespace {

using nlohmann::ordered_json;
using report_internal::EscapeHtml;
using report_internal::ShortNumber;
namespace mustache = kainjow::mustache;

// As the JSON statement writes p: 0.99 -> "99 %", 0.9545 -> "95.45 %".
std::string Percent(double p) { return fmt::format("{:g} %", std::round(p * 1e6) / 1e4); }

std::string WithUnit(const std::string& number, const std::string& unit) {
  return unit.empty() ? number : number + " " + unit;
}

// Density of the distribution the GUF assigns to Y (JCGM 101:2008 5.6 and 6.4.9): the
// t distribution with nu_eff degrees of freedom shifted to y and scaled by u_c; normal for
// an infinite (null) nu_eff.
double GufDensity(double y, double value, double u, double dof) {
  const double z = (y - value) / u;
  if (!std::isfinite(dof)) return std::exp(-0.5 * z * z) / (std::sqrt(2.0 * M_PI) * u);
  const double log_norm = std::lgamma(0.5 * (dof + 1.0)) - std::lgamma(0.5 * dof) -
                          0.5 * std::log(dof * M_PI) - std::log(u);
  return std::exp(log_norm - 0.5 * (dof + 1.0) * std::log1p(z * z / dof));
}

// A vertical line from 0 to `height` at x, as a two-point series.
PlotSeries VerticalLine(const std::string& label, double x, double height, PlotColor color,
                        bool dashed) {
  PlotSeries s;
  s.label = label;
  s.style = SeriesStyle::kLine;
  s.color = color;
  s.dashed = dashed;
  s.x = {x, x};
  s.y = {0.0, height};
  return s;
}

// The histogram of the Monte Carlo values as a probability density times u_c (a
// dimensionless scale, so the axis needs no multiplier), against y - y_ref in the
// measurand's unit scaled by a power of 1000 written in the axis label.
Result<std::string> HistogramSvg(const BudgetReport& report) {
  const std::string& measurand = report.measurand.name;
  const std::string& unit = report.measurand.unit;
  const BudgetReportResult& result = report.result;
  const BudgetReportMonteCarlo& mc = *report.monte_carlo;
  if (!mc.histogram || mc.histogram->counts.empty() ||
      mc.histogram->edges.size() != mc.histogram->counts.size() + 1) {
    return MakeError("the report has no Monte Carlo histogram (monte_carlo.histogram)");
  }
  const std::vector<double>& edges = mc.histogram->edges;
  const std::vector<int64_t>& counts = mc.histogram->counts;
  const double value = result.value;
  const double u = result.u;
  const double dof = result.dof_eff;
  const double trials = static_cast<double>(mc.trials);
  if (!std::isfinite(value) || !(u > 0.0) || !(trials > 0.0)) {
    return MakeError("the report has no finite GUF value and u_c to draw against");
  }
  const double lo = edges.front(), hi = edges.back();
  const report_internal::AxisScale axis =
      report_internal::ChooseAxisScale(measurand, unit, lo, hi, value);
  const auto to_x = [&](double y) { return axis.To(y); };

  XyPlot plot;
  plot.title = fmt::format("Distribution for {}: Monte Carlo histogram and GUF density", measurand);
  plot.x_label = axis.label;
  plot.y_label = "probability density x u_c";
  PlotSeries bins;
  bins.label = fmt::format("Monte Carlo, M = {:.0f}", trials);
  bins.style = SeriesStyle::kBins;
  bins.color = PlotColor::kBlue;
  double peak = 0.0;
  for (double edge : edges) bins.x.push_back(to_x(edge));
  for (size_t i = 0; i < counts.size(); ++i) {
    const double width = edges[i + 1] - edges[i];
    const double density = static_cast<double>(counts[i]) / (trials * width) * u;
    bins.y.push_back(density);
    peak = std::max(peak, density);
  }
  PlotSeries guf;
  guf.label = std::isfinite(dof) ? fmt::format("GUF: t, nu_eff = {:.3g}, scale u_c", dof)
                                 : "GUF: normal, u_c";
  guf.color = PlotColor::kRed;
  constexpr int kPoints = 400;
  for (int i = 0; i <= kPoints; ++i) {
    const double y = lo + (hi - lo) * i / kPoints;
    guf.x.push_back(to_x(y));
    guf.y.push_back(GufDensity(y, value, u, dof) * u);
    peak = std::max(peak, guf.y.back());
  }
  plot.series.push_back(bins);
  plot.series.push_back(guf);
  const double top = 1.05 * peak;
  const double p = result.coverage;
  for (size_t end = 0; end < 2; ++end) {
    const double x_guf = end == 0 ? result.interval.low : result.interval.high;
    const double x_mc = end == 0 ? mc.shortest.low : mc.shortest.high;
    if (std::isfinite(x_guf)) {
      plot.series.push_back(VerticalLine(end == 0 ? fmt::format("GUF {} interval", Percent(p)) : "",
                                         to_x(x_guf), top, PlotColor::kOrange, true));
    }
    if (std::isfinite(x_mc)) {
      plot.series.push_back(
          VerticalLine(end == 0 ? fmt::format("MC shortest {} interval", Percent(p)) : "",
                       to_x(x_mc), top, PlotColor::kGreen, false));
    }
  }
  plot.height_px = 380;
  return RenderXyPlot(plot);
}

// Infinite degrees of freedom (null in the JSON) print as "-", as NaN does.
double FiniteOrNaN(double x) {
  return std::isfinite(x) ? x : std::numeric_limits<double>::quiet_NaN();
}

// One row of the results table: a method, y, u(y) and an interval.
mustache::data ResultRow(const std::string& method, double value, double u, double low, double high,
                         const std::string& note) {
  mustache::data row;
  row.set("method", method);
  const RoundedResult r = RoundForStatement(value, u);
  row.set("value", std::isfinite(value) ? r.value : "undefined");
  row.set("u", std::isfinite(u) ? r.uncertainty : "undefined");
  const RoundedInterval iv = RoundInterval(low, high);
  row.set("low", iv.low);
  row.set("high", iv.high);
  row.set("note", note);
  return row;
}

}  // namespace

namespace report_internal {

Result<mustache::data> BudgetViewData(const BudgetReport& budget) {
  mustache::data d;
  d.set("measurand", budget.measurand.name);
  // The stated result (BudgetReportStated): the Monte Carlo one when the GUF failed its
  // validation, with the GUF statement after it.
  d.set("statement", budget.stated.method == kStatedMonteCarlo
                         ? fmt::format("{}. Stated because {}. GUF: {}", budget.stated.statement,
                                       budget.stated.reason, budget.result.statement)
                         : budget.result.statement);
  // Lines sorted by their share of the variance, largest first.
  std::vector<const BudgetReportLine*> lines;
  for (const BudgetReportLine& l : budget.budget) lines.push_back(&l);
  std::stable_sort(lines.begin(), lines.end(),
                   [](const BudgetReportLine* a, const BudgetReportLine* b) {
                     return (std::isnan(b->percent) ? -1.0 : b->percent) <
                            (std::isnan(a->percent) ? -1.0 : a->percent);
                   });
  mustache::data rows{mustache::data::type::list};
  BarPlot bars;
  bars.title = "Uncertainty budget: share of u_c^2";
  bars.x_label = "100 (c_i u_i)^2 / u_c^2 [%]";
  for (const BudgetReportLine* l : lines) {
    const RoundedResult r = RoundForStatement(l->value, l->u);
    mustache::data row;
    row.set("name", l->name);
    row.set("value", r.value);
    row.set("u", r.uncertainty);
    row.set("distribution", l->distribution);
    row.set("sensitivity", ShortNumber(l->sensitivity, 4));
    row.set("contribution", ShortNumber(l->contribution, 2));
    row.set("dof", ShortNumber(FiniteOrNaN(l->dof), 4));
    row.set("percent", std::isnan(l->percent) ? "-" : fmt::format("{:.1f}", l->percent));
    rows.push_back(row);
    bars.labels.push_back(l->name);
    bars.values.push_back(std::isfinite(l->percent) && l->percent > 0.0 ? l->percent : 0.0);
  }
  d.set("lines", rows);
  Result<std::string> svg =
      bars.labels.empty() ? Result<std::string>(MakeError("no inputs")) : RenderBarPlot(bars);
  d.set("bars_svg", svg.ok()
                        ? svg.value()
                        : "<p class=\"note\">No bars: " + EscapeHtml(svg.error().message) + "</p>");
  d.set("has_monte_carlo", budget.monte_carlo.has_value());
  if (budget.monte_carlo) {
    const BudgetReportMonteCarlo& mc = *budget.monte_carlo;
    const RoundedResult r = RoundForStatement(mc.value, mc.u);
    d.set("monte_carlo",
          fmt::format("y = {}, u(y) = {}, {} trials, shortest {} % interval [{}, {}]", r.value,
                      r.uncertainty, mc.trials, ShortNumber(100.0 * mc.coverage, 3),
                      ShortNumber(mc.shortest.low, 6), ShortNumber(mc.shortest.high, 6)));
  } else {
    d.set("monte_carlo", "");
  }
  return d;
}

}  // namespace report_internal

bool IsBudgetDefinition(const ordered_json& document) {
  return document.is_object() && !document.contains("schema") && document.contains("measurand") &&
         document.contains("inputs");
}

Result<std::string> RenderBudgetReportHtml(const BudgetReport& report) {
  Result<mustache::data> view = report_internal::BudgetViewData(report);
  if (!view.ok()) return view.error();
  mustache::data d = std::move(view).value();
  const std::string& measurand = report.measurand.name;
  const std::string& unit = report.measurand.unit;
  const BudgetReportResult& result = report.result;
  const double value = result.value;
  const double u = result.u;
  const double k = result.k;
  const double expanded = result.expanded;
  const double dof = result.dof_eff;
  const double p = result.coverage;

  // The headline is the stated result (BudgetReportStated): the GUF one when the Monte Carlo
  // method validated it or none ran, the Monte Carlo one otherwise (JCGM 101:2008 8.2);
  // both stay in the table below it.
  const BudgetReportStated& stated = report.stated;
  const bool mc_stated = stated.method == kStatedMonteCarlo && report.monte_carlo.has_value();
  // JCGM 100:2008 7.2.4 (the wording of its example), value and U rounded per 7.2.6.
  const RoundedResult s = RoundForStatement(value, expanded);
  const RoundedResult uc = RoundForStatement(value, u);
  const std::string guf_statement = fmt::format("{} = ({} \u00b1 {}){}", measurand, s.value,
                                                s.uncertainty, unit.empty() ? "" : " " + unit);
  const std::string guf_detail = fmt::format(
      "where the number following \u00b1 is the expanded uncertainty U = k u_c, determined "
      "from the combined standard uncertainty u_c = {} and the coverage factor k = {:.2f} {}; "
      "it defines an interval estimated to have a coverage probability of {}.",
      WithUnit(uc.uncertainty, unit), k,
      std::isfinite(dof) ? fmt::format("from the t distribution with nu_eff = {:.3g} effective "
                                       "degrees of freedom",
                                       dof)
                         : "from the normal distribution",
      Percent(p));
  const std::string guf_concise =
      fmt::format("{} = {}", measurand, WithUnit(ConciseNotation(value, u), unit));
  d.set("guf_below", mc_stated);
  if (mc_stated) {
    // The JSON's stated.statement, then what its numbers are; the GUF statement below it.
    d.set("statement", stated.statement);
    d.set("statement_detail",
          fmt::format("the Monte Carlo result: the mean and standard deviation of M = {} model "
                      "values and the shortest interval holding {} of them.",
                      report.monte_carlo->trials, Percent(stated.coverage)));
    d.set("concise", fmt::format("{} = {}", measurand,
                                 std::isfinite(stated.value) && std::isfinite(stated.u)
                                     ? WithUnit(ConciseNotation(stated.value, stated.u), unit)
                                     : "undefined"));
    d.set("guf_statement", guf_statement);
    d.set("guf_detail", guf_detail + " In concise notation " + guf_concise + ".");
  } else {
    d.set("statement", guf_statement);
    d.set("statement_detail", guf_detail);
    d.set("concise", guf_concise);
  }
  d.set("stated_basis",
        fmt::format("Why this result: {}.", stated.reason.empty() ? "-" : stated.reason));
  d.set("unit", unit.empty() ? "(none)" : unit);
  d.set("model", report.measurand.model.empty() ? "y = sum of c_i x_i (sensitivities given)"
                                                : report.measurand.model);
  d.set("budget_file", report.budget_file);
  d.set("coverage", Percent(p));

  mustache::data rows{mustache::data::type::list};
  rows.push_back(ResultRow(mc_stated ? "GUF (JCGM 100)" : "GUF (JCGM 100), stated", value, u,
                           result.interval.low, result.interval.high,
                           fmt::format("y +- U, k = {:.2f}", k)));
  d.set("has_mc", report.monte_carlo.has_value());
  std::string verdict, verdict_class = "note";
  if (report.monte_carlo) {
    const BudgetReportMonteCarlo& mc = *report.monte_carlo;
    rows.push_back(ResultRow("Monte Carlo (JCGM 101), probabilistically symmetric", mc.value, mc.u,
                             mc.symmetric.low, mc.symmetric.high,
                             "7.7: quantiles (1-p)/2, (1+p)/2"));
    rows.push_back(ResultRow(
        mc_stated ? "Monte Carlo (JCGM 101), shortest, stated" : "Monte Carlo (JCGM 101), shortest",
        mc.value, mc.u, mc.shortest.low, mc.shortest.high, "7.7: shortest"));
    d.set(
        "mc_run",
        fmt::format("M = {} trials{}, seed {}, numerical tolerance delta = {} (7.9.2){}", mc.trials,
                    mc.adaptive ? fmt::format(" (adaptive, {} blocks)", mc.blocks) : "", mc.seed,
                    WithUnit(ShortNumber(mc.numerical_tolerance, 2), unit),
                    mc.message.empty() ? "" : "; " + mc.message));
    if (mc.validation) {
      const GufValidation& v = *mc.validation;
      // JCGM 101:2008 8.2: d_low = |y - U_p - y_low|, d_high = |y + U_p - y_high| against the
      // numerical tolerance delta of u(y).
      verdict = fmt::format(
          "GUF {} by the Monte Carlo method (JCGM 101:2008 8.2): d_low = {} and d_high = {}, "
          "{} the numerical tolerance delta = {}{}",
          v.validated ? "validated" : "NOT validated", WithUnit(ShortNumber(v.d_low, 2), unit),
          WithUnit(ShortNumber(v.d_high, 2), unit), v.validated ? "both within" : "not both within",
          WithUnit(ShortNumber(v.delta, 2), unit),
          v.validated ? "." : ": the Monte Carlo result and its interval are stated above.");
      verdict_class = v.validated ? "ok" : "note";
    } else {
      verdict = "No GUF validation in the report.";
    }
    Result<std::string> svg = HistogramSvg(report);
    d.set("histogram_svg", svg.ok()
                               ? svg.value()
                               : "<p class=\"note\">No histogram: " +
                                     report_internal::EscapeHtml(svg.error().message) + "</p>");
  } else {
    verdict =
        "The GUF result is not validated: the budget ran no Monte Carlo method "
        "(monte_carlo disabled, JCGM 101:2008 8.2 needs one).";
    d.set("mc_run", "");
    d.set("histogram_svg", "");
  }
  d.set("results", rows);
  d.set("verdict", verdict);
  d.set("verdict_class", verdict_class);
  Result<std::string> body = report_internal::RenderTemplate("budget_page", std::move(d));
  if (!body.ok()) return body;
  return report_internal::RenderPage(
      fmt::format("Uncertainty budget: {}", measurand),
      fmt::format("{} ({})", report.budget_file, kBudgetReportSchema), body.value());
}

Result<std::string> RenderBudgetReportHtml(std::string_view json_text, const std::string& file) {
  Result<BudgetReport> report = BudgetReportFromJson(json_text, file);
  if (!report.ok()) return report.error();
  Result<std::string> html = RenderBudgetReportHtml(report.value());
  if (!html.ok() && html.error().file.empty()) {
    Error e = html.error();
    e.file = file;  // A report that reads but cannot be drawn: name the file it came from.
    return e;
  }
  return html;
}

}  // namespace metro
