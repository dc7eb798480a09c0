#include "metro/report/budget_page.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "html_common.hpp"
#include "html_templates.hpp"
#include "metro/core/rounding.hpp"
#include "metro/report/svg_plot.hpp"

namespace metro {
namespace {

using nlohmann::ordered_json;
using report_internal::JsonNumber;
using report_internal::JsonString;
using report_internal::NumberAt;
using report_internal::ShortNumber;
namespace mustache = kainjow::mustache;

const ordered_json& Member(const ordered_json& j, const char* key) {
  static const ordered_json kNull;
  return j.is_object() && j.contains(key) ? j[key] : kNull;
}

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
Result<std::string> HistogramSvg(const ordered_json& report, const std::string& measurand,
                                 const std::string& unit) {
  const ordered_json& result = Member(report, "result");
  const ordered_json& mc = Member(report, "monte_carlo");
  const ordered_json& h = Member(mc, "histogram");
  const ordered_json& edges = Member(h, "edges");
  const ordered_json& counts = Member(h, "counts");
  if (!edges.is_array() || !counts.is_array() || edges.size() != counts.size() + 1 ||
      counts.empty()) {
    return MakeError("the report has no Monte Carlo histogram (monte_carlo.histogram)");
  }
  const double value = JsonNumber(result, "value");
  const double u = JsonNumber(result, "u");
  const double dof = JsonNumber(result, "dof_eff");
  const double trials = JsonNumber(mc, "trials");
  if (!std::isfinite(value) || !(u > 0.0) || !(trials > 0.0)) {
    return MakeError("the report has no finite GUF value and u_c to draw against");
  }
  const double lo = NumberAt(edges, 0), hi = NumberAt(edges, edges.size() - 1);
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
  for (size_t i = 0; i < edges.size(); ++i) bins.x.push_back(to_x(NumberAt(edges, i)));
  for (size_t i = 0; i < counts.size(); ++i) {
    const double width = NumberAt(edges, i + 1) - NumberAt(edges, i);
    const double density = NumberAt(counts, i) / (trials * width) * u;
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
  const ordered_json& g = Member(result, "interval");
  const ordered_json& s = Member(mc, "interval_shortest");
  const double p = JsonNumber(result, "coverage");
  for (size_t end = 0; end < 2; ++end) {
    const double x_guf = NumberAt(g, end), x_mc = NumberAt(s, end);
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

bool IsBudgetDefinition(const ordered_json& document) {
  return document.is_object() && !document.contains("schema") && document.contains("measurand") &&
         document.contains("inputs");
}

Result<std::string> RenderBudgetReportHtml(const ordered_json& report) {
  if (!report.is_object() || JsonString(report, "schema") != kBudgetReportSchema) {
    return MakeError(fmt::format("not a {} report", kBudgetReportSchema));
  }
  const ordered_json& result = Member(report, "result");
  if (!result.is_object()) return MakeError("budget report: missing the 'result' object");
  Result<mustache::data> view = report_internal::BudgetViewData(report);
  if (!view.ok()) return view.error();
  mustache::data d = std::move(view).value();
  const ordered_json& measurand_json = Member(report, "measurand");
  const std::string measurand = JsonString(measurand_json, "name");
  const std::string unit = JsonString(measurand_json, "unit");
  const double value = JsonNumber(result, "value");
  const double u = JsonNumber(result, "u");
  const double k = JsonNumber(result, "k");
  const double expanded = JsonNumber(result, "U");
  const double dof = JsonNumber(result, "dof_eff");
  const double p = JsonNumber(result, "coverage");

  // JCGM 100:2008 7.2.4 (the wording of its example), value and U rounded per 7.2.6.
  const RoundedResult s = RoundForStatement(value, expanded);
  const RoundedResult uc = RoundForStatement(value, u);
  d.set("statement", fmt::format("{} = ({} \u00b1 {}){}", measurand, s.value, s.uncertainty,
                                 unit.empty() ? "" : " " + unit));
  d.set("statement_detail",
        fmt::format("where the number following \u00b1 is the expanded uncertainty U = k u_c, "
                    "determined from the combined standard uncertainty u_c = {} and the "
                    "coverage factor k = {:.2f} {}; it defines an interval estimated to have a "
                    "coverage probability of {}.",
                    WithUnit(uc.uncertainty, unit), k,
                    std::isfinite(dof)
                        ? fmt::format("from the t distribution with nu_eff = {:.3g} effective "
                                      "degrees of freedom",
                                      dof)
                        : "from the normal distribution",
                    Percent(p)));
  d.set("concise", fmt::format("{} = {}", measurand, WithUnit(ConciseNotation(value, u), unit)));
  d.set("unit", unit.empty() ? "(none)" : unit);
  d.set("model", JsonString(measurand_json, "model").empty()
                     ? "y = sum of c_i x_i (sensitivities given)"
                     : JsonString(measurand_json, "model"));
  d.set("budget_file", JsonString(report, "budget_file"));
  d.set("coverage", Percent(p));

  mustache::data rows{mustache::data::type::list};
  const ordered_json& gi = Member(result, "interval");
  rows.push_back(ResultRow("GUF (JCGM 100)", value, u, NumberAt(gi, 0), NumberAt(gi, 1),
                           fmt::format("y +- U, k = {:.2f}", k)));
  const ordered_json& mc = Member(report, "monte_carlo");
  const bool has_mc = mc.is_object();
  d.set("has_mc", has_mc);
  std::string verdict, verdict_class = "note";
  if (has_mc) {
    const double mc_value = JsonNumber(mc, "value");
    const double mc_u = JsonNumber(mc, "u");
    const ordered_json& sym = Member(mc, "interval_symmetric");
    const ordered_json& shortest = Member(mc, "interval_shortest");
    rows.push_back(ResultRow("Monte Carlo (JCGM 101), probabilistically symmetric", mc_value, mc_u,
                             NumberAt(sym, 0), NumberAt(sym, 1),
                             "7.7: quantiles (1-p)/2, (1+p)/2"));
    rows.push_back(ResultRow("Monte Carlo (JCGM 101), shortest", mc_value, mc_u,
                             NumberAt(shortest, 0), NumberAt(shortest, 1), "7.7: shortest"));
    const bool adaptive = Member(mc, "adaptive").is_boolean() && mc["adaptive"].get<bool>();
    d.set("mc_run",
          fmt::format(
              "M = {} trials{}, seed {}, numerical tolerance delta = {} (7.9.2){}",
              JsonString(mc, "trials"),
              adaptive ? fmt::format(" (adaptive, {} blocks)", JsonString(mc, "blocks")) : "",
              JsonString(mc, "seed"),
              WithUnit(ShortNumber(JsonNumber(mc, "numerical_tolerance"), 2), unit),
              Member(mc, "message").is_string() ? "; " + mc["message"].get<std::string>() : ""));
    if (Member(mc, "guf_validated").is_boolean()) {
      const bool validated = mc["guf_validated"].get<bool>();
      // JCGM 101:2008 8.2: d_low = |y - U_p - y_low|, d_high = |y + U_p - y_high| against the
      // numerical tolerance delta of u(y).
      verdict = fmt::format(
          "GUF {} by the Monte Carlo method (JCGM 101:2008 8.2): d_low = {} and d_high = {}, "
          "{} the numerical tolerance delta = {}{}",
          validated ? "validated" : "NOT validated",
          WithUnit(ShortNumber(JsonNumber(mc, "d_low"), 2), unit),
          WithUnit(ShortNumber(JsonNumber(mc, "d_high"), 2), unit),
          validated ? "both within" : "not both within",
          WithUnit(ShortNumber(JsonNumber(mc, "delta"), 2), unit),
          validated ? "." : ": state the Monte Carlo result and its interval instead.");
      verdict_class = validated ? "ok" : "note";
    } else {
      verdict = "No GUF validation in the report.";
    }
    Result<std::string> svg = HistogramSvg(report, measurand, unit);
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
      fmt::format("{} ({})", JsonString(report, "budget_file"), kBudgetReportSchema), body.value());
}

}  // namespace metro
