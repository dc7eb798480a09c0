// The stages of the session page ("metro.report/1", docs/reports.md), each from the report
// JSON; html_report.cpp puts them together in session.mustache's order: the result, the
// Type A details, the noise table, the input and its options, then per tag the plots.
// Private to src/report/.
#pragma once

#include <kainjow/mustache.hpp>
#include <nlohmann/json.hpp>
#include <string>

#include "metro/core/status.hpp"
#include "metro/io/session.hpp"
#include "metro/report/html_report.hpp"

namespace metro::report_internal {

// --- session_tables.cpp: the page's tables, the numbers first.

// "result_rows": per tag and evaluated quantity the statement of its mean, y +- U:
// {sensor, tag, quantity, unit, value, U, k, p}. Value and U from type_a.mean and
// type_a.U_mean, rounded per JCGM 100:2008 7.2.6 (RoundForStatement: U to two significant
// digits, the value to the same decimal place); k (type_a.k) to 3 significant digits; p
// (type_a.coverage) in percent. A quantity without U_mean (a constant series, a report
// written before metro stated U, u(mean) with fewer than one degree of freedom) shows "-"
// for U and k and says why in "note" (set only then).
kainjow::mustache::data ResultRows(const nlohmann::ordered_json& report);

// "summary_rows": the Type A details per tag and quantity: n, mean and u(mean) (rounded per
// 7.2.6), s, n_eff and n_eff/n.
kainjow::mustache::data TypeADetailRows(const nlohmann::ordered_json& report);

// "noise_rows": per tag and quantity with an Allan fit: the one-sided white-noise density
// d = sqrt(2) N (allan.noise.random_walk.density_one_sided, u_density_one_sided) in the
// concise notation of 7.2.2 (ConciseNotation, u to two digits) in its unit and, when it
// differs, its conventional unit (u scaled by the same factor), the Allan minimum sigma_min at tau
// (allan_type_a_link.allan_min_dev and allan_min_tau_s, 3 significant digits; "at the last
// tau" when the curve still falls there), the Allan-predicted u(mean) over the window
// (allan_type_a_link.u_mean_allan, two significant digits) and the Type A u(mean) used
// (type_a.u_mean, two significant digits).
kainjow::mustache::data NoiseRows(const nlohmann::ordered_json& report);

// --- session_plots.cpp: the figures.

// A list of figures {svg, caption} and notes on the plots that could not be drawn.
struct QuantityPlots {
  kainjow::mustache::data plots{kainjow::mustache::data::type::list};
  kainjow::mustache::data unavailable{kainjow::mustache::data::type::list};
};

// Time series (the part outside the window shaded), histogram with the normal density of
// the Type A result, and autocorrelation with the white-noise band, of quantity `qname` of
// `sensor` (the report's sensors[i]) drawn from the session's `tag` and column `q`. Each
// axis carries its scale and offset in the label (ChooseAxisScale), never a detached "x10^n".
void AddSeriesPlots(const nlohmann::ordered_json& sensor, const std::string& qname,
                    const nlohmann::ordered_json& quantity, const Tag& tag, const Quantity& q,
                    const HtmlReportOptions& options, QuantityPlots* out);

// The Allan deviation of one quantity with its confidence interval and the fitted IEEE 952
// terms; `terms_table` receives the table of the terms.
void AddAllanPlot(const std::string& qname, const nlohmann::ordered_json& quantity,
                  QuantityPlots* out, kainjow::mustache::data* terms_table);

// One plot per sensor group of `sensor` (the x, y and z axes of one sensor: ax_g ay_g az_g,
// gx_dps gy_dps gz_dps; names <letters><x|y|z>_<unit>, one unit) with two or more Allan
// curves: each axis's curve with its confidence interval and its fitted noise model, one
// colour per axis (x blue, y orange, z green).
void AddAllanGroupPlots(const nlohmann::ordered_json& sensor, QuantityPlots* out);

}  // namespace metro::report_internal
