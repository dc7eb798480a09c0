#include "session_tables.hpp"

#include <fmt/format.h>

#include <cmath>

#include "html_common.hpp"
#include "metro/core/rounding.hpp"
#include "session_report_json.hpp"

namespace metro::report_internal {

namespace mustache = kainjow::mustache;

namespace {

// Calls `f(sensor, quantity)` for each quantity of each tag, in the report's order.
template <typename F>
void ForEachQuantity(const SessionReport& report, F f) {
  for (const SensorReport& s : report.sensors) {
    for (const QuantityReport& q : s.quantities) f(s, q);
  }
}

// The rows of one quantity share these cells.
mustache::data QuantityRow(const SensorReport& s, const QuantityReport& q) {
  mustache::data row;
  row.set("sensor", std::to_string(s.sensor));
  row.set("tag", s.name);
  row.set("quantity", q.name);
  row.set("unit", q.unit);
  return row;
}

}  // namespace

mustache::data ResultRows(const SessionReport& report) {
  mustache::data rows{mustache::data::type::list};
  ForEachQuantity(report, [&rows](const SensorReport& s, const QuantityReport& q) {
    if (!q.type_a) return;
    const TypeAReport& a = *q.type_a;
    const double expanded = a.U_mean;
    const double k = a.k;
    const double p = a.coverage.value_or(NAN);
    mustache::data row = QuantityRow(s, q);
    if (std::isfinite(expanded) && std::isfinite(k)) {
      // JCGM 100:2008 7.2.6: U to two significant digits, the mean to the same place.
      const RoundedResult r = RoundForStatement(a.mean, expanded);
      row.set("value", r.value);
      row.set("U", r.uncertainty);
      row.set("k", ShortNumber(k, 3));
    } else {
      row.set("value", ShortNumber(a.mean, 6));
      row.set("U", "-");
      row.set("k", "-");
      const double u = a.u_mean;
      const double dof = a.u_mean_dof;
      row.set("note", !a.coverage         ? std::string("the report states no U (written before "
                                                                "metro recorded it): run characterize "
                                                                "again")
                      : !std::isfinite(u) ? std::string("no u(mean): a constant series")
                                          : fmt::format("no U: u(mean) = {} has {} degrees of "
                                                        "freedom, fewer than one",
                                                        UncertaintyText(u), ShortNumber(dof, 2)));
    }
    row.set("p", std::isfinite(p) ? fmt::format("{:g} %", 100.0 * p) : "-");
    rows.push_back(row);
  });
  return rows;
}

mustache::data TypeADetailRows(const SessionReport& report) {
  mustache::data rows{mustache::data::type::list};
  ForEachQuantity(report, [&rows](const SensorReport& s, const QuantityReport& q) {
    if (!q.type_a) return;
    const TypeAReport& a = *q.type_a;
    const double u = a.has_u_mean ? a.u_mean : a.std_of_mean_autocorr;
    RoundedResult r = RoundForStatement(a.mean, u);
    const double n = static_cast<double>(a.n);
    const double n_eff = a.n_eff;
    // Null in the report (a constant series, n <= 3): not computed, never "nan".
    const std::string not_computed = "not computed";
    if (!std::isfinite(u)) r.uncertainty = not_computed;
    mustache::data row = QuantityRow(s, q);
    row.set("n", ShortNumber(n, 12));
    row.set("mean", r.value);
    row.set("u_mean", r.uncertainty);
    row.set("std", ShortNumber(a.std, 2));
    row.set("n_eff", std::isfinite(n_eff) ? fmt::format("{:.1f}", n_eff) : not_computed);
    row.set("n_eff_ratio",
            std::isfinite(n_eff) && n > 0 ? fmt::format("{:.3f}", n_eff / n) : not_computed);
    rows.push_back(row);
  });
  return rows;
}

mustache::data SpecRows(const SessionReport& report) {
  mustache::data rows = mustache::data::type::list;
  if (!report.spec) return rows;
  for (const SpecDecisionRow& r : report.spec->rows) {
    mustache::data row;
    row.set("quantity", r.quantity.empty() ? "-" : r.quantity);
    row.set("term", SpecTermSymbol(r.term));
    if (r.figure) {
      row.set("has_figure", true);
      row.set("figure", fmt::format("{} {}", ShortNumber(r.figure->value, 4), r.figure->unit));
      row.set("kind", SpecKindName(r.figure->kind));
      row.set("convention", SpecConventionName(r.figure->convention));
      row.set("document", r.document);
      row.set("measured", ShortNumber(r.measured, 4));
      row.set("u", ShortNumber(r.u, 2));
      row.set("ratio", ShortNumber(r.ratio, 3));
      row.set("e_n", ShortNumber(r.e_n, 3));
    }
    if (r.conformity) {
      row.set("decision",
              fmt::format("{} (p_c {:.3f})", ConformityDecisionName(r.conformity->decision),
                          r.conformity->p_conformance));
      row.set("pass", r.conformity->decision == ConformityDecision::kPass);
    } else {
      row.set("decision", r.note.empty() ? "-" : r.note);
      row.set("pass", true);
    }
    rows.push_back(row);
  }
  return rows;
}

mustache::data NoiseRows(const SessionReport& report) {
  mustache::data rows{mustache::data::type::list};
  ForEachQuantity(report, [&rows](const SensorReport& s, const QuantityReport& q) {
    if (!q.allan || !q.allan->ok()) return;
    const AllanNoiseTermReport& white_term = q.allan->term(NoiseTerm::kRandomWalk);
    const AllanDensityReport white = white_term.density.value_or(AllanDensityReport{});
    const AllanTypeALink link = q.allan_type_a_link.value_or(AllanTypeALink{});
    mustache::data row = QuantityRow(s, q);
    // JCGM 100:2008 7.2.2 concise notation, u to two digits (7.2.6); the conventional form
    // with u scaled by the same unit factor.
    const double d = white.density_one_sided;
    const double u_d = white.u_density_one_sided;
    const double d_conv = white.density_one_sided_conventional;
    if (std::isfinite(d)) {
      row.set("density", ConciseNotation(d, u_d));
    } else {
      row.set("density", "not fitted");
    }
    row.set("unit_density", white.unit_density);
    const std::string unit_conv = white.unit_density_conventional;
    const bool other_unit = unit_conv != white.unit_density;
    row.set("has_conventional", other_unit && std::isfinite(d_conv) && d != 0.0);
    if (other_unit && std::isfinite(d_conv) && d != 0.0) {
      row.set("density_conventional", ConciseNotation(d_conv, u_d * d_conv / d));
      row.set("unit_density_conventional", unit_conv);
    }
    row.set("sigma_min", ShortNumber(link.allan_min_dev, 3));
    row.set("tau_min_s", ShortNumber(link.allan_min_tau_s, 3));
    row.set("min_at_end", link.allan_min_at_end);
    row.set("u_mean_allan", UncertaintyText(link.u_mean_allan));
    row.set("u_mean", q.type_a ? UncertaintyText(q.type_a->u_mean) : "-");
    row.set("dominant", link.dominant_term.value_or("-"));
    row.set("duration_s", ShortNumber(link.duration_s, 4));
    // The goodness of fit of the IEEE 952 model (issue #36).
    std::string model = "-";
    bool model_ok = false;
    if (const std::optional<AllanModelCheckReport>& m = q.allan->model_check; m) {
      if (!m->tested) {
        model = "not tested";
      } else if (!m->rejected) {
        model = fmt::format("holds (p = {:.2g})", m->p_value);
        model_ok = true;
      } else {
        model = fmt::format("rejected (p = {:.2g})", m->p_value);
        if (m->tau_range_model_holds_s) {
          model += fmt::format("; holds for tau {}-{} s",
                               ShortNumber((*m->tau_range_model_holds_s)[0], 3),
                               ShortNumber((*m->tau_range_model_holds_s)[1], 3));
        }
      }
      row.set("model_summary", m->summary);
    }
    row.set("model", model);
    row.set("model_ok", model_ok);
    rows.push_back(row);
  });
  return rows;
}

mustache::data SessionOptionRows(const SessionReport& report) {
  return OptionRows(ToJsonValue(report)["options"]);
}

}  // namespace metro::report_internal
