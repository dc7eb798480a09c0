#include "metro/report/batch_page.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <utility>
#include <vector>

#include "html_common.hpp"
#include "html_templates.hpp"
#include "metro/core/rounding.hpp"
#include "metro/report/svg_plot.hpp"

namespace metro {
namespace {

using report_internal::EscapeHtml;
namespace mustache = kainjow::mustache;

std::string Link(const std::string& prefix, const std::string& name) {
  return prefix.empty() ? name : prefix + "/" + name;
}

// One point per session that evaluated the quantity.
struct SessionPoint {
  int session = 0;  // 1-based row of the sessions table.
  double mean = 0.0;
  double u = 0.0;
};

Result<std::string> SpreadPlot(const BatchQuantitySummary& q,
                               const std::vector<SessionPoint>& points) {
  const std::string& quantity = q.quantity;
  const std::string& unit = q.unit;
  const double center = q.mean_of_means;
  double lo = center, hi = center;
  for (const SessionPoint& p : points) {
    const double u = std::isfinite(p.u) ? p.u : 0.0;
    lo = std::min(lo, p.mean - u);
    hi = std::max(hi, p.mean + u);
  }
  const report_internal::AxisScale axis =
      report_internal::ChooseAxisScale(quantity, unit, lo, hi, center);
  XyPlot plot;
  plot.title = fmt::format("sensor {} {}: {}", q.sensor, q.name, quantity);
  plot.x_label = "session (row of the sessions table)";
  plot.y_label = axis.label;
  plot.width_px = 560;
  plot.height_px = 280;
  PlotSeries s;
  s.label = "session mean +- u_mean";
  s.style = SeriesStyle::kErrorBars;
  for (const SessionPoint& p : points) {
    const double u = std::isfinite(p.u) ? p.u : 0.0;
    s.x.push_back(p.session);
    s.y.push_back(axis.To(p.mean));
    s.y_low.push_back(axis.To(p.mean - u));
    s.y_high.push_back(axis.To(p.mean + u));
  }
  // Room either side of the first and last session.
  PlotSeries frame;
  frame.style = SeriesStyle::kPoints;
  frame.color = PlotColor::kGrey;
  frame.x = {points.front().session - 0.5, points.back().session + 0.5};
  frame.y = {std::nan(""), std::nan("")};
  plot.series.push_back(s);
  plot.series.push_back(frame);
  if (std::isfinite(center)) {
    PlotHLine h;
    h.label = q.statistics.value_or("") == "circular" ? "circular mean of the means"
                                                      : "mean of the means";
    h.y = axis.To(center);
    plot.hlines.push_back(h);
  }
  return RenderXyPlot(plot);
}

}  // namespace

Result<std::string> RenderBatchSummaryHtml(const BatchSummaryReport& summary,
                                           const BatchPageOptions& options) {
  mustache::data d;
  mustache::data rows{mustache::data::type::list};
  // (sensor, quantity) -> each session's mean and u_mean.
  std::map<std::pair<int64_t, std::string>, std::vector<SessionPoint>> points;
  size_t dead = 0;
  int row_number = 0;
  for (const BatchSessionEntry& s : summary.sessions) {
    ++row_number;
    const auto base_row = [&] {
      mustache::data row;
      row.set("number", std::to_string(row_number));
      row.set("input", s.input);
      const std::string page = s.ok ? s.page.value_or("") : "";
      row.set("has_page", !page.empty());
      row.set("page_href", Link(options.link_prefix, page));
      const std::string report = s.ok ? s.report : "";
      row.set("has_report", !report.empty());
      row.set("report_href", Link(options.link_prefix, report));
      return row;
    };
    const bool has_tags = s.ok && s.tags && !s.tags->empty();
    if (!has_tags) {
      mustache::data row = base_row();
      row.set("sensor", "-");
      row.set("tag", "-");
      for (const char* key : {"frames", "fresh", "stale", "never"}) row.set(key, "-");
      row.set("status", s.ok ? "analysed" : "FAILED: " + s.error);
      row.set("status_class", s.ok ? "" : "warn");
      rows.push_back(row);
    }
    if (!s.ok) continue;
    if (has_tags) {
      for (const BatchSessionTag& t : *s.tags) {
        mustache::data row = base_row();
        row.set("sensor", std::to_string(t.sensor));
        row.set("tag", t.name);
        row.set("frames", std::to_string(t.frames));
        row.set("fresh", std::to_string(t.fresh));
        row.set("stale", std::to_string(t.stale));
        row.set("never", std::to_string(t.never));
        dead += t.dead ? 1 : 0;
        row.set("status", t.dead ? "DEAD: frames but no fresh packet" : "ok");
        row.set("status_class", t.dead ? "warn" : "");
        rows.push_back(row);
      }
    }
    if (s.quantities) {
      for (const BatchSessionQuantity& q : *s.quantities) {
        if (!std::isfinite(q.mean)) continue;
        points[{q.sensor, q.quantity}].push_back({row_number, q.mean, q.u_mean});
      }
    }
  }
  d.set("rows", rows);
  d.set("sessions_total", std::to_string(summary.sessions_total));
  d.set("sessions_failed", std::to_string(summary.sessions_failed));
  d.set("dead", std::to_string(dead));
  mustache::data warnings{mustache::data::type::list};
  const std::vector<std::string> no_warnings;
  for (const std::string& w : summary.warnings.value_or(no_warnings)) {
    warnings.push_back(mustache::data(w));
  }
  d.set("has_warnings", summary.warnings && !summary.warnings->empty());
  d.set("warnings", warnings);

  // The quantities: a table row each; plots for those with the most sessions first.
  mustache::data quantities{mustache::data::type::list};
  std::vector<std::pair<const BatchQuantitySummary*, const std::vector<SessionPoint>*>> plotted;
  for (const BatchQuantitySummary& q : summary.quantities) {
    mustache::data row;
    row.set("sensor", std::to_string(q.sensor));
    row.set("tag", q.name);
    row.set("quantity", q.quantity);
    row.set("unit", q.unit);
    row.set("sessions", std::to_string(q.sessions));
    const double mean = q.mean_of_means;
    const double spread = q.std_of_means;
    const RoundedResult r = RoundForStatement(mean, std::isfinite(spread) ? spread : 0.0);
    row.set("mean", std::isfinite(mean) ? r.value : "-");
    row.set("std", std::isfinite(spread) ? r.uncertainty : "-");
    row.set("statistics", q.statistics.value_or(""));
    row.set("warning", q.warning.value_or(""));
    quantities.push_back(row);
    const auto it = points.find({q.sensor, q.quantity});
    if (it != points.end() && !it->second.empty()) plotted.push_back({&q, &it->second});
  }
  d.set("quantities", quantities);
  std::stable_sort(plotted.begin(), plotted.end(), [](const auto& a, const auto& b) {
    return a.second->size() > b.second->size();
  });
  const size_t shown =
      std::min(plotted.size(), static_cast<size_t>(std::max(0, options.max_plotted_quantities)));
  mustache::data plots{mustache::data::type::list};
  for (size_t i = 0; i < shown; ++i) {
    Result<std::string> svg = SpreadPlot(*plotted[i].first, *plotted[i].second);
    mustache::data p;
    p.set("svg", svg.ok()
                     ? svg.value()
                     : "<p class=\"note\">No plot: " + EscapeHtml(svg.error().message) + "</p>");
    plots.push_back(p);
  }
  d.set("plots", plots);
  d.set("plots_note",
        shown < plotted.size()
            ? fmt::format("{} of {} quantities are plotted (those evaluated in the most sessions "
                          "first); the rest are in the table below.",
                          shown, plotted.size())
            : "");
  Result<std::string> body = report_internal::RenderTemplate("batch_page", std::move(d));
  if (!body.ok()) return body;
  return report_internal::RenderPage(
      "Batch summary",
      fmt::format("{} sessions, {} failed, {} dead tag rows; {}", summary.sessions_total,
                  summary.sessions_failed, dead, summary.output_dir),
      body.value());
}

Result<std::string> RenderBatchSummaryHtml(std::string_view json_text, const std::string& file,
                                           const BatchPageOptions& options) {
  Result<BatchSummaryReport> summary = BatchSummaryFromJson(json_text, file);
  if (!summary.ok()) return summary.error();
  return RenderBatchSummaryHtml(summary.value(), options);
}

}  // namespace metro
