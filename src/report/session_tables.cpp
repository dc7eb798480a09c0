#include "session_tables.hpp"

#include <fmt/format.h>

#include <cmath>

#include "html_common.hpp"
#include "metro/core/json_text.hpp"
#include "metro/core/rounding.hpp"

namespace metro::report_internal {

using nlohmann::ordered_json;
namespace mustache = kainjow::mustache;

namespace {

// Calls `f(sensor, tag name, quantity name, quantity)` for each quantity of each tag, in
// the report's order.
template <typename F>
void ForEachQuantity(const ordered_json& report, F f) {
  for (const ordered_json& s : report["sensors"]) {
    if (!s.contains("quantities") || !s["quantities"].is_object()) continue;
    const std::string sensor = std::to_string(static_cast<int>(JsonNumber(s, "sensor")));
    const std::string tag = JsonString(s, "name");
    for (const auto& item : s["quantities"].items()) f(sensor, tag, item.key(), item.value());
  }
}

// The rows of one quantity share these cells.
mustache::data QuantityRow(const std::string& sensor, const std::string& tag,
                           const std::string& qname, const ordered_json& q) {
  mustache::data row;
  row.set("sensor", sensor);
  row.set("tag", tag);
  row.set("quantity", qname);
  row.set("unit", JsonString(q, "unit"));
  return row;
}

bool Evaluated(const ordered_json& q) { return q.contains("type_a") && q["type_a"].is_object(); }

}  // namespace

mustache::data ResultRows(const ordered_json& report) {
  mustache::data rows{mustache::data::type::list};
  ForEachQuantity(report, [&rows](const std::string& sensor, const std::string& tag,
                                  const std::string& qname, const ordered_json& q) {
    if (!Evaluated(q)) return;
    const ordered_json& a = q["type_a"];
    const double expanded = JsonNumber(a, "U_mean");
    const double k = JsonNumber(a, "k");
    const double p = JsonNumber(a, "coverage");
    mustache::data row = QuantityRow(sensor, tag, qname, q);
    if (std::isfinite(expanded) && std::isfinite(k)) {
      // JCGM 100:2008 7.2.6: U to two significant digits, the mean to the same place.
      const RoundedResult r = RoundForStatement(JsonNumber(a, "mean"), expanded);
      row.set("value", r.value);
      row.set("U", r.uncertainty);
      row.set("k", ShortNumber(k, 3));
    } else {
      row.set("value", ShortNumber(JsonNumber(a, "mean"), 6));
      row.set("U", "-");
      row.set("k", "-");
      const double u = JsonNumber(a, "u_mean");
      const double dof = JsonNumber(a, "u_mean_dof");
      row.set("note", !a.contains("U_mean") ? std::string("the report states no U (written before "
                                                          "metro recorded it): run characterize "
                                                          "again")
                      : !std::isfinite(u)   ? std::string("no u(mean): a constant series")
                                            : fmt::format("no U: u(mean) = {} has {} degrees of "
                                                            "freedom, fewer than one",
                                                          UncertaintyText(u), ShortNumber(dof, 2)));
    }
    row.set("p", std::isfinite(p) ? fmt::format("{:g} %", 100.0 * p) : "-");
    rows.push_back(row);
  });
  return rows;
}

mustache::data TypeADetailRows(const ordered_json& report) {
  mustache::data rows{mustache::data::type::list};
  ForEachQuantity(report, [&rows](const std::string& sensor, const std::string& tag,
                                  const std::string& qname, const ordered_json& q) {
    if (!Evaluated(q)) return;
    const ordered_json& a = q["type_a"];
    const double u = JsonNumber(a, a.contains("u_mean") ? "u_mean" : "std_of_mean_autocorr");
    RoundedResult r = RoundForStatement(JsonNumber(a, "mean"), u);
    const double n = JsonNumber(a, "n");
    const double n_eff = JsonNumber(a, "n_eff");
    // Null in the report (a constant series, n <= 3): not computed, never "nan".
    const std::string not_computed = "not computed";
    if (!std::isfinite(u)) r.uncertainty = not_computed;
    mustache::data row = QuantityRow(sensor, tag, qname, q);
    row.set("n", ShortNumber(n, 12));
    row.set("mean", r.value);
    row.set("u_mean", r.uncertainty);
    row.set("std", ShortNumber(JsonNumber(a, "std"), 2));
    row.set("n_eff", std::isfinite(n_eff) ? fmt::format("{:.1f}", n_eff) : not_computed);
    row.set("n_eff_ratio",
            std::isfinite(n_eff) && n > 0 ? fmt::format("{:.3f}", n_eff / n) : not_computed);
    rows.push_back(row);
  });
  return rows;
}

mustache::data NoiseRows(const ordered_json& report) {
  mustache::data rows{mustache::data::type::list};
  ForEachQuantity(report, [&rows](const std::string& sensor, const std::string& tag,
                                  const std::string& qname, const ordered_json& q) {
    if (!q.contains("allan") || !q["allan"].contains("noise")) return;
    const ordered_json& white = q["allan"]["noise"].value("random_walk", ordered_json::object());
    const ordered_json& link = q.value("allan_type_a_link", ordered_json::object());
    mustache::data row = QuantityRow(sensor, tag, qname, q);
    // JCGM 100:2008 7.2.2 concise notation, u to two digits (7.2.6); the conventional form
    // with u scaled by the same unit factor.
    const double d = JsonNumber(white, "density_one_sided");
    const double u_d = JsonNumber(white, "u_density_one_sided");
    const double d_conv = JsonNumber(white, "density_one_sided_conventional");
    if (std::isfinite(d)) {
      row.set("density", ConciseNotation(d, u_d));
    } else {
      row.set("density", "not fitted");
    }
    row.set("unit_density", JsonString(white, "unit_density"));
    const std::string unit_conv = JsonString(white, "unit_density_conventional");
    const bool other_unit = unit_conv != JsonString(white, "unit_density");
    row.set("has_conventional", other_unit && std::isfinite(d_conv) && d != 0.0);
    if (other_unit && std::isfinite(d_conv) && d != 0.0) {
      row.set("density_conventional", ConciseNotation(d_conv, u_d * d_conv / d));
      row.set("unit_density_conventional", unit_conv);
    }
    const double min_dev = JsonNumber(link, "allan_min_dev");
    row.set("sigma_min", ShortNumber(min_dev, 3));
    row.set("tau_min_s", ShortNumber(JsonNumber(link, "allan_min_tau_s"), 3));
    row.set("min_at_end", link.value("allan_min_at_end", false));
    row.set("u_mean_allan", UncertaintyText(JsonNumber(link, "u_mean_allan")));
    row.set("u_mean", Evaluated(q) ? UncertaintyText(JsonNumber(q["type_a"], "u_mean")) : "-");
    row.set("dominant",
            JsonString(link, "dominant_term").empty() ? "-" : JsonString(link, "dominant_term"));
    row.set("duration_s", ShortNumber(JsonNumber(link, "duration_s"), 4));
    rows.push_back(row);
  });
  return rows;
}

}  // namespace metro::report_internal
