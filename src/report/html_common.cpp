#include "html_common.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <unordered_set>

#include "core/json_text.hpp"
#include "html_templates.hpp"
#include "metro/core/rounding.hpp"
#include "metro/report/svg_plot.hpp"

namespace metro::report_internal {

using nlohmann::ordered_json;
namespace mustache = kainjow::mustache;

namespace {

double AsNumber(const ordered_json& v) {
  if (v.is_number()) return v.get<double>();
  if (v.is_string()) {
    const std::string s = v.get<std::string>();
    if (s == "inf") return std::numeric_limits<double>::infinity();
    if (s == "-inf") return -std::numeric_limits<double>::infinity();
  }
  return std::numeric_limits<double>::quiet_NaN();
}

// Arrays longer than this are shown as their first elements and a count.
constexpr size_t kMaxArrayShown = 24;
constexpr int kMaxDepth = 6;
// An array of objects is one table when the union of their keys is at most this many columns.
constexpr size_t kMaxTableColumns = 32;

std::string ScalarHtml(const ordered_json& v) {
  if (v.is_string()) return EscapeHtml(v.get<std::string>());
  if (v.is_number_float()) return EscapeHtml(ShortNumber(v.get<double>(), 10));
  return EscapeHtml(JsonText(v));
}

bool IsScalar(const ordered_json& v) { return !v.is_object() && !v.is_array(); }

std::string ValueHtml(const ordered_json& v, int depth);

std::string ObjectHtml(const ordered_json& obj, int depth) {
  std::string out = "<table>\n";
  for (const auto& [key, value] : obj.items()) {
    out += fmt::format("<tr><th>{}</th><td>{}</td></tr>\n", EscapeHtml(key),
                       ValueHtml(value, depth + 1));
  }
  return out + "</table>\n";
}

std::string ArrayHtml(const ordered_json& arr, int depth) {
  if (arr.empty()) return "[]";
  const bool all_scalar = std::all_of(arr.begin(), arr.end(), IsScalar);
  if (all_scalar) {
    std::string out;
    for (size_t i = 0; i < std::min(arr.size(), kMaxArrayShown); ++i) {
      out += (i == 0 ? "" : ", ") + ScalarHtml(arr[i]);
    }
    if (arr.size() > kMaxArrayShown) {
      out += fmt::format(", ... ({} values in all)", arr.size());
    }
    return "<code>" + out + "</code>";
  }
  // Array of objects with scalar members: one table, one row per element.
  bool rows = std::all_of(arr.begin(), arr.end(), [](const ordered_json& e) {
    return e.is_object() && std::all_of(e.begin(), e.end(), IsScalar);
  });
  // Columns: the union of the members' keys in first-seen order, when they are few enough
  // for a table; else (objects with many distinct keys) one nested table per element, so the
  // page stays linear in the document (a table of every row by every key is not).
  std::vector<std::string> columns;
  if (rows) {
    std::unordered_set<std::string> seen;
    for (const auto& e : arr) {
      for (const auto& [key, value] : e.items()) {
        if (seen.insert(key).second) columns.push_back(key);
      }
      if (columns.size() > kMaxTableColumns) {
        rows = false;
        break;
      }
    }
  }
  if (rows) {
    std::string out = "<table>\n<tr>";
    for (const std::string& c : columns) out += "<th>" + EscapeHtml(c) + "</th>";
    out += "</tr>\n";
    for (const auto& e : arr) {
      out += "<tr>";
      for (const std::string& c : columns) {
        out += "<td>" + (e.contains(c) ? ScalarHtml(e[c]) : std::string()) + "</td>";
      }
      out += "</tr>\n";
    }
    return out + "</table>\n";
  }
  std::string out = "<table>\n";
  for (size_t i = 0; i < arr.size(); ++i) {
    out += fmt::format("<tr><th>[{}]</th><td>{}</td></tr>\n", i, ValueHtml(arr[i], depth + 1));
  }
  return out + "</table>\n";
}

std::string ValueHtml(const ordered_json& v, int depth) {
  if (IsScalar(v)) return ScalarHtml(v);
  if (depth >= kMaxDepth) return "<code>" + EscapeHtml(JsonText(v)) + "</code>";
  return v.is_object() ? ObjectHtml(v, depth) : ArrayHtml(v, depth);
}

}  // namespace

double JsonNumber(const ordered_json& j, const char* key) {
  if (!j.is_object() || !j.contains(key)) return std::numeric_limits<double>::quiet_NaN();
  return AsNumber(j[key]);
}

double NumberAt(const ordered_json& a, size_t i) {
  if (!a.is_array() || i >= a.size()) return std::numeric_limits<double>::quiet_NaN();
  return AsNumber(a[i]);
}

std::string JsonString(const ordered_json& j, const char* key) {
  if (!j.is_object() || !j.contains(key) || j[key].is_null()) return "";
  return j[key].is_string() ? j[key].get<std::string>() : JsonText(j[key]);
}

std::string ShortNumber(double x, int significant) {
  if (std::isnan(x)) return "-";
  return fmt::format("{:.{}g}", x, significant);
}

std::string UncertaintyText(double u) {
  if (!std::isfinite(u)) return "-";
  return RoundForStatement(0.0, u).uncertainty;
}

AxisScale ChooseAxisScale(const std::string& name, const std::string& unit_symbol, double lo,
                          double hi, double offset) {
  AxisScale a;
  const std::string unit = unit_symbol == "1" ? "" : unit_symbol;  // Dimensionless.
  const double span = hi - lo;
  std::string offset_text;
  if (std::isfinite(offset) && span > 0.0 && std::fabs(lo) > 10.0 * span &&
      std::fabs(hi) > 10.0 * span) {
    offset_text = RoundForStatement(offset, span).value;
    a.offset = std::strtod(offset_text.c_str(), nullptr);  // No throw.
  }
  const double extent = std::max(std::fabs(lo - a.offset), std::fabs(hi - a.offset));
  int exponent3 = 0;
  if (std::isfinite(extent) && extent > 0.0) {
    exponent3 = 3 * static_cast<int>(std::floor(std::log10(extent) / 3.0));
  }
  a.scale = std::pow(10.0, exponent3);
  const std::string scaled_unit = exponent3 == 0 ? unit
                                  : unit.empty() ? fmt::format("1e{}", exponent3)
                                                 : fmt::format("1e{} {}", exponent3, unit);
  a.label =
      (offset_text.empty()
           ? name
           : fmt::format("{} - {}", name, unit.empty() ? offset_text : offset_text + " " + unit)) +
      (scaled_unit.empty() ? "" : " [" + scaled_unit + "]");
  return a;
}

namespace {

void AddOptionRows(const std::string& prefix, const ordered_json& value, mustache::data* rows) {
  if (value.is_object()) {
    for (const auto& item : value.items()) {
      AddOptionRows(prefix.empty() ? item.key() : prefix + "." + item.key(), item.value(), rows);
    }
    return;
  }
  std::string text;
  if (value.is_null()) {
    text = "not set";
  } else if (value.is_array()) {
    for (const ordered_json& e : value) {
      text += (text.empty() ? "" : ", ") + (e.is_string() ? e.get<std::string>() : JsonText(e));
    }
    if (text.empty()) text = "empty list";
  } else {
    text = value.is_string() ? value.get<std::string>() : JsonText(value);
  }
  mustache::data row;
  row.set("key", prefix);
  row.set("value", text);
  rows->push_back(row);
}

}  // namespace

mustache::data OptionRows(const ordered_json& options) {
  mustache::data rows{mustache::data::type::list};
  AddOptionRows("", options, &rows);
  return rows;
}

bool AnyAllan(const ordered_json& report) {
  if (!report.contains("sensors") || !report["sensors"].is_array()) return false;
  for (const auto& s : report["sensors"]) {
    if (!s.contains("quantities") || !s["quantities"].is_object()) continue;
    for (const auto& [name, q] : s["quantities"].items()) {
      if (q.contains("allan")) return true;
    }
  }
  return false;
}

Result<mustache::data> BudgetViewData(const ordered_json& budget) {
  if (!budget.is_object() || !budget.contains("budget") || !budget["budget"].is_array()) {
    return MakeError("budget report: missing the 'budget' array of input lines");
  }
  mustache::data d;
  const ordered_json empty = ordered_json::object();
  const ordered_json& measurand = budget.contains("measurand") ? budget["measurand"] : empty;
  const ordered_json& result = budget.contains("result") ? budget["result"] : empty;
  d.set("measurand", JsonString(measurand, "name"));
  d.set("statement", JsonString(result, "statement"));
  // Lines sorted by their share of the variance, largest first.
  std::vector<const ordered_json*> lines;
  for (const auto& l : budget["budget"]) lines.push_back(&l);
  std::stable_sort(lines.begin(), lines.end(), [](const ordered_json* a, const ordered_json* b) {
    const double pa = JsonNumber(*a, "percent"), pb = JsonNumber(*b, "percent");
    return (std::isnan(pb) ? -1.0 : pb) < (std::isnan(pa) ? -1.0 : pa);
  });
  mustache::data rows{mustache::data::type::list};
  BarPlot bars;
  bars.title = "Uncertainty budget: share of u_c^2";
  bars.x_label = "100 (c_i u_i)^2 / u_c^2 [%]";
  for (const ordered_json* l : lines) {
    const double value = JsonNumber(*l, "value");
    const double u = JsonNumber(*l, "u");
    const RoundedResult r = RoundForStatement(value, u);
    const double percent = JsonNumber(*l, "percent");
    mustache::data row;
    row.set("name", JsonString(*l, "name"));
    row.set("value", r.value);
    row.set("u", r.uncertainty);
    row.set("distribution", JsonString(*l, "distribution"));
    row.set("sensitivity", ShortNumber(JsonNumber(*l, "sensitivity"), 4));
    row.set("contribution", ShortNumber(JsonNumber(*l, "contribution"), 2));
    row.set("dof", ShortNumber(JsonNumber(*l, "dof"), 4));
    row.set("percent", std::isnan(percent) ? "-" : fmt::format("{:.1f}", percent));
    rows.push_back(row);
    bars.labels.push_back(JsonString(*l, "name"));
    bars.values.push_back(std::isfinite(percent) && percent > 0.0 ? percent : 0.0);
  }
  d.set("lines", rows);
  Result<std::string> svg =
      bars.labels.empty() ? Result<std::string>(MakeError("no inputs")) : RenderBarPlot(bars);
  d.set("bars_svg", svg.ok()
                        ? svg.value()
                        : "<p class=\"note\">No bars: " + EscapeHtml(svg.error().message) + "</p>");
  const bool has_mc = budget.contains("monte_carlo") && budget["monte_carlo"].is_object();
  d.set("has_monte_carlo", has_mc);
  if (has_mc) {
    const ordered_json& mc = budget["monte_carlo"];
    const RoundedResult r = RoundForStatement(JsonNumber(mc, "value"), JsonNumber(mc, "u"));
    d.set("monte_carlo",
          fmt::format("y = {}, u(y) = {}, {} trials, shortest {} % interval [{}, {}]", r.value,
                      r.uncertainty, JsonString(mc, "trials"),
                      ShortNumber(100.0 * JsonNumber(mc, "coverage"), 3),
                      ShortNumber(NumberAt(mc.value("interval_shortest", ordered_json()), 0), 6),
                      ShortNumber(NumberAt(mc.value("interval_shortest", ordered_json()), 1), 6)));
  } else {
    d.set("monte_carlo", "");
  }
  return d;
}

Result<std::string> RenderGenericHtml(const ordered_json& document, const std::string& json_path,
                                      const std::string& schema) {
  mustache::data data;
  data.set("schema", schema.empty() ? "(none)" : schema);
  mustache::data sections{mustache::data::type::list};
  bool budget_view = false;
  if (document.is_object()) {
    const bool is_budget = schema == "metro.budget-report/1";
    const ordered_json* budget = is_budget ? &document
                                 : document.contains("budget") && document["budget"].is_object()
                                     ? &document["budget"]
                                     : nullptr;
    if (budget != nullptr) {
      Result<mustache::data> b = BudgetViewData(*budget);
      if (b.ok()) {
        data.set("budget", b.value());
        budget_view = true;
      }
    }
    for (const auto& [key, value] : document.items()) {
      mustache::data s;
      s.set("key", key);
      s.set("html", ValueHtml(value, 0));
      sections.push_back(s);
    }
  } else {
    mustache::data s;
    s.set("key", "document");
    s.set("html", ValueHtml(document, 0));
    sections.push_back(s);
  }
  if (!budget_view) data.set("budget", false);
  data.set("sections", sections);
  Result<std::string> body = RenderTemplate("generic", std::move(data));
  if (!body.ok()) return body;
  return RenderPage(fmt::format("Report: {}", std::filesystem::path(json_path).filename().string()),
                    schema.empty() ? "JSON document without a schema key" : schema, body.value());
}

}  // namespace metro::report_internal
