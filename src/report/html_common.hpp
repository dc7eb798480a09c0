// Helpers shared by the HTML views (private to src/report/).
#pragma once

#include <kainjow/mustache.hpp>
#include <nlohmann/json.hpp>
#include <string>

#include "metro/core/status.hpp"

namespace metro::report_internal {

// j[key] as a number; NaN when missing, null or not a number (the JSON writers store
// non-finite numbers as null or as strings "nan"/"inf").
double JsonNumber(const nlohmann::ordered_json& j, const char* key);
// a[i] as a number; NaN as above.
double NumberAt(const nlohmann::ordered_json& a, size_t i);
// j[key] as text: strings as is, other values dumped, "" when missing.
std::string JsonString(const nlohmann::ordered_json& j, const char* key);
// `significant` digits (fmt "{:.Ng}"), "-" for NaN.
std::string ShortNumber(double x, int significant);
// An uncertainty alone, two significant digits (JCGM 100:2008 7.2.6, RoundForStatement);
// "-" when not finite.
std::string UncertaintyText(double u);

// A plot axis for values of `name` in `unit` spanning [lo, hi]: plotted as (x - offset) /
// scale, scale a power of 1000 chosen so the ticks need no detached multiplier, both stated
// in the label: "az_g [g]", "l - 50000838 nm [nm]", "ax_g - 0.0123 g [1e-6 g]". `offset` is
// used when the values sit far from zero (|lo|, |hi| > 10 (hi - lo)), rounded per JCGM 100
// 7.2.6 to the span; else 0.
struct AxisScale {
  double offset = 0.0;
  double scale = 1.0;
  std::string label;
  double To(double x) const { return (x - offset) / scale; }
};
AxisScale ChooseAxisScale(const std::string& name, const std::string& unit, double lo, double hi,
                          double offset);

// A report's "options" (session and accuracy pages) as rows {key, value}, one per leaf: nested
// objects by dotted keys
// ("autocorrelation.method"), arrays as their elements joined by ", " ("empty list" when empty),
// null as "not set".
kainjow::mustache::data OptionRows(const nlohmann::ordered_json& options);

// True when any quantity of the report has an "allan" object.
bool AnyAllan(const nlohmann::ordered_json& report);

// Data for budget.mustache from a "metro.budget-report/1" object: the statement, the lines
// rounded per GUM 7.2.6 and the sorted contribution bars.
Result<kainjow::mustache::data> BudgetViewData(const nlohmann::ordered_json& budget);

// The generic view (generic.mustache): the JSON as nested tables.
Result<std::string> RenderGenericHtml(const nlohmann::ordered_json& document,
                                      const std::string& json_path, const std::string& schema);

}  // namespace metro::report_internal
