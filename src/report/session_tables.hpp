// The tables of the session page ("metro.report/1", docs/reports.md): the result, the Type A
// details and the noise table. html_report.cpp puts them together with the figures
// (session_plots.hpp) in session.mustache's order. Private to src/report/.
#pragma once

#include <kainjow/mustache.hpp>
#include <string>

#include "metro/report/session_report.hpp"

namespace metro::report_internal {

// "result_rows": per tag and evaluated quantity the statement of its mean, y +- U:
// {sensor, tag, quantity, unit, value, U, k, p}. Value and U from type_a.mean and
// type_a.U_mean, rounded per JCGM 100:2008 7.2.6 (RoundForStatement: U to two significant
// digits, the value to the same decimal place); k (type_a.k) to 3 significant digits; p
// (type_a.coverage) in percent. A quantity without U_mean (a constant series, a report
// written before metro stated U, u(mean) with fewer than one degree of freedom) shows "-"
// for U and k and says why in "note" (set only then).
kainjow::mustache::data ResultRows(const SessionReport& report);

// "summary_rows": the Type A details per tag and quantity: n, mean and u(mean) (rounded per
// 7.2.6), s, n_eff and n_eff/n.
kainjow::mustache::data TypeADetailRows(const SessionReport& report);

// "noise_rows": per tag and quantity with an Allan fit: the one-sided white-noise density
// d = sqrt(2) N (allan.noise.random_walk.density_one_sided, u_density_one_sided) in the
// concise notation of 7.2.2 (ConciseNotation, u to two digits) in its unit and, when it
// differs, its conventional unit (u scaled by the same factor), the Allan minimum sigma_min at tau
// (allan_type_a_link.allan_min_dev and allan_min_tau_s, 3 significant digits; "at the last
// tau" when the curve still falls there), the Allan-predicted u(mean) over the window
// (allan_type_a_link.u_mean_allan, two significant digits) and the Type A u(mean) used
// (type_a.u_mean, two significant digits), and the IEEE 952 model's goodness of fit
// (allan.model_check: "holds (p = ..)", "rejected (p = ..); holds for tau a-b s", "not
// tested"; its summary as the cell's title).
kainjow::mustache::data NoiseRows(const SessionReport& report);

// "spec_rows": with --spec-part, per quantity and term the datasheet figure (value, unit,
// kind, convention, document), the measured value in its convention with u, ratio, E_n and
// the JCGM 106 decision with p_c (max/min figures) or the note (spec_decision.hpp); empty
// without the report's "spec".
kainjow::mustache::data SpecRows(const SessionReport& report);

// "option_rows": the report's options as {option, value} rows (OptionRows of html_common).
kainjow::mustache::data SessionOptionRows(const SessionReport& report);

}  // namespace metro::report_internal
