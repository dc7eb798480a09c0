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
#include "metro/report/batch.hpp"
#include "metro/report/svg_plot.hpp"

namespace metro {
namespace {

using nlohmann::ordered_json;
using report_internal::EscapeHtml;
using report_internal::JsonNumber;
using report_internal::JsonString;
namespace mustache = kainjow::mustache;

std::string Link(const std::string& prefix, const std::string& name) {
  return prefix.empty() ? name : prefix + "/" + name;
}

std::string Count(const ordered_json& j, const char* key) {
  return j.contains(key) && j[key].is_number() ? JsonString(j, key) : "-";
}

// One point per session that evaluated the quantity.
struct SessionPoint {
  int session = 0;  // 1-based row of the sessions table.
  double mean = 0.0;
  double u = 0.0;
};

Result<std::string> SpreadPlot(const ordered_json& q, const std::vector<SessionPoint>& points) {
  const std::string quantity = JsonString(q, "quantity");
  const std::string unit = JsonString(q, "unit");
  const double center = JsonNumber(q, "mean_of_means");
  double lo = center, hi = center;
  for (const SessionPoint& p : points) {
    const double u = std::isfinite(p.u) ? p.u : 0.0;
    lo = std::min(lo, p.mean - u);
    hi = std::max(hi, p.mean + u);
  }
  const report_internal::AxisScale axis =
      report_internal::ChooseAxisScale(quantity, unit, lo, hi, center);
  XyPlot plot;
  plot.title =
      fmt::format("sensor {} {}: {}", JsonString(q, "sensor"), JsonString(q, "name"), quantity);
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
    h.label = JsonString(q, "statistics") == "circular" ? "circular mean of the means"
                                                        : "mean of the means";
    h.y = axis.To(center);
    plot.hlines.push_back(h);
  }
  return RenderXyPlot(plot);
}

}  // namespace

Result<std::string> RenderBatchSummaryHtml(const ordered_json& summary,
                                           const BatchPageOptions& options) {
  if (!summary.is_object() || JsonString(summary, "schema") != kBatchSummarySchema ||
      !summary.contains("sessions") || !summary["sessions"].is_array()) {
    return MakeError(fmt::format("not a {} summary with its 'sessions'", kBatchSummarySchema));
  }
  mustache::data d;
  mustache::data rows{mustache::data::type::list};
  // (sensor, quantity) -> each session's mean and u_mean.
  std::map<std::pair<int, std::string>, std::vector<SessionPoint>> points;
  size_t dead = 0;
  int row_number = 0;
  for (const ordered_json& s : summary["sessions"]) {
    ++row_number;
    const std::string input = JsonString(s, "input");
    const bool ok = s.contains("ok") && s["ok"].is_boolean() && s["ok"].get<bool>();
    const auto base_row = [&] {
      mustache::data row;
      row.set("number", std::to_string(row_number));
      row.set("input", input);
      const std::string page = JsonString(s, "page");
      row.set("has_page", !page.empty());
      row.set("page_href", Link(options.link_prefix, page));
      const std::string report = JsonString(s, "report");
      row.set("has_report", !report.empty());
      row.set("report_href", Link(options.link_prefix, report));
      return row;
    };
    const ordered_json empty = ordered_json::array();
    const ordered_json& tags = s.contains("tags") && s["tags"].is_array() ? s["tags"] : empty;
    if (!ok || tags.empty()) {
      mustache::data row = base_row();
      row.set("sensor", "-");
      row.set("tag", "-");
      for (const char* key : {"frames", "fresh", "stale", "never"}) row.set(key, "-");
      row.set("status", ok ? "analysed" : "FAILED: " + JsonString(s, "error"));
      row.set("status_class", ok ? "" : "warn");
      rows.push_back(row);
    }
    if (ok) {
      for (const ordered_json& t : tags) {
        mustache::data row = base_row();
        row.set("sensor", JsonString(t, "sensor"));
        row.set("tag", JsonString(t, "name"));
        for (const char* key : {"frames", "fresh", "stale", "never"}) row.set(key, Count(t, key));
        const bool is_dead = t.contains("dead") && t["dead"].is_boolean() && t["dead"].get<bool>();
        dead += is_dead ? 1 : 0;
        row.set("status", is_dead ? "DEAD: frames but no fresh packet" : "ok");
        row.set("status_class", is_dead ? "warn" : "");
        rows.push_back(row);
      }
      if (s.contains("quantities") && s["quantities"].is_array()) {
        for (const ordered_json& q : s["quantities"]) {
          const double mean = JsonNumber(q, "mean");
          if (!std::isfinite(mean) || !q.contains("sensor") || !q["sensor"].is_number_integer()) {
            continue;
          }
          points[{q["sensor"].get<int>(), JsonString(q, "quantity")}].push_back(
              {row_number, mean, JsonNumber(q, "u_mean")});
        }
      }
    }
  }
  d.set("rows", rows);
  d.set("sessions_total", JsonString(summary, "sessions_total"));
  d.set("sessions_failed", JsonString(summary, "sessions_failed"));
  d.set("dead", std::to_string(dead));
  mustache::data warnings{mustache::data::type::list};
  if (summary.contains("warnings") && summary["warnings"].is_array()) {
    for (const ordered_json& w : summary["warnings"]) {
      warnings.push_back(mustache::data(w.is_string() ? w.get<std::string>() : w.dump()));
    }
  }
  d.set("has_warnings", summary.contains("warnings") && summary["warnings"].is_array() &&
                            !summary["warnings"].empty());
  d.set("warnings", warnings);

  // The quantities: a table row each; plots for those with the most sessions first.
  mustache::data quantities{mustache::data::type::list};
  std::vector<std::pair<const ordered_json*, const std::vector<SessionPoint>*>> plotted;
  if (summary.contains("quantities") && summary["quantities"].is_array()) {
    for (const ordered_json& q : summary["quantities"]) {
      mustache::data row;
      row.set("sensor", JsonString(q, "sensor"));
      row.set("tag", JsonString(q, "name"));
      row.set("quantity", JsonString(q, "quantity"));
      row.set("unit", JsonString(q, "unit"));
      row.set("sessions", JsonString(q, "sessions"));
      const double mean = JsonNumber(q, "mean_of_means");
      const double spread = JsonNumber(q, "std_of_means");
      const RoundedResult r = RoundForStatement(mean, std::isfinite(spread) ? spread : 0.0);
      row.set("mean", std::isfinite(mean) ? r.value : "-");
      row.set("std", std::isfinite(spread) ? r.uncertainty : "-");
      row.set("statistics", JsonString(q, "statistics"));
      row.set("warning", JsonString(q, "warning"));
      quantities.push_back(row);
      if (!q.contains("sensor") || !q["sensor"].is_number_integer()) continue;
      const auto it = points.find({q["sensor"].get<int>(), JsonString(q, "quantity")});
      if (it != points.end() && !it->second.empty()) plotted.push_back({&q, &it->second});
    }
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
      fmt::format("{} sessions, {} failed, {} dead tag rows; {}",
                  JsonString(summary, "sessions_total"), JsonString(summary, "sessions_failed"),
                  dead, JsonString(summary, "output_dir")),
      body.value());
}

}  // namespace metro
