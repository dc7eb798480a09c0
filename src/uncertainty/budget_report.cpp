#include "metro/uncertainty/budget_report.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "metro/core/rounding.hpp"

namespace metro {
namespace {

using nlohmann::ordered_json;

ordered_json Dof(double dof) { return std::isfinite(dof) ? ordered_json(dof) : ordered_json(); }
ordered_json Number(double x) { return std::isfinite(x) ? ordered_json(x) : ordered_json(); }

std::string Short(double x) {
  if (!std::isfinite(x)) return std::isnan(x) ? "nan" : (x > 0 ? "inf" : "-inf");
  return fmt::format("{:.6g}", x);
}

// Estimates keep more digits than uncertainties (a 50 mm gauge in nm needs 8).
std::string Long(double x) {
  if (!std::isfinite(x)) return Short(x);
  return fmt::format("{:.10g}", x);
}

std::string Percent(double p) { return fmt::format("{:g} %", std::round(p * 1e6) / 1e4); }

// See McHistogram. `values` is reordered (partially sorted for the quantiles).
std::optional<McHistogram> BinValues(std::vector<double>* values, double include_low,
                                     double include_high) {
  const size_t m = values->size();
  if (m < 2) return std::nullopt;
  const auto quantile = [&](double p) {
    const size_t k = std::min(m - 1, static_cast<size_t>(p * static_cast<double>(m)));
    std::nth_element(values->begin(), values->begin() + static_cast<std::ptrdiff_t>(k),
                     values->end());
    return (*values)[k];
  };
  const double q_low = quantile(0.0005);
  const double q_high = quantile(0.9995);
  if (!std::isfinite(q_low) || !std::isfinite(q_high) || !(q_high > q_low)) return std::nullopt;
  double low = q_low - 0.05 * (q_high - q_low);
  double high = q_high + 0.05 * (q_high - q_low);
  if (std::isfinite(include_low)) low = std::min(low, include_low);
  if (std::isfinite(include_high)) high = std::max(high, include_high);
  const int bins =
      static_cast<int>(std::clamp(std::round(std::sqrt(static_cast<double>(m))), 10.0, 60.0));
  McHistogram h;
  h.edges.resize(static_cast<size_t>(bins) + 1);
  for (int i = 0; i <= bins; ++i) h.edges[i] = low + (high - low) * i / bins;
  h.counts.assign(static_cast<size_t>(bins), 0);
  const double scale = bins / (high - low);
  for (double y : *values) {
    if (y < low) {
      ++h.below;
    } else if (y > high) {
      ++h.above;
    } else {
      h.counts[std::min(bins - 1, static_cast<int>((y - low) * scale))] += 1;
    }
  }
  return h;
}

}  // namespace

Result<BudgetEvaluation> EvaluateBudget(const Budget& budget, ProgressSink* progress) {
  BudgetEvaluation e;
  e.budget = budget;
  auto gum = EvaluateGum(budget);
  if (!gum.ok()) return gum.error();
  e.gum = std::move(gum).value();
  e.ok = true;
  if (budget.monte_carlo.enabled) {
    McOptions options = budget.monte_carlo;
    if (progress != nullptr) {
      // Adaptive runs stop by their rule (JCGM 101 7.9): the total is not known ahead.
      progress->BeginPhase("Monte Carlo", options.adaptive ? 0 : options.trials, "trials");
      options.on_trials_done = [progress](int64_t n) { progress->Advance(n); };
    }
    auto mc = RunMonteCarlo(budget, options, /*keep_samples=*/true);
    if (!mc.ok()) return mc.error();
    e.monte_carlo = std::move(mc).value();
    std::vector<double> samples = std::move(e.monte_carlo->samples);
    e.monte_carlo->samples = {};
    const McResult& m = *e.monte_carlo;
    e.histogram =
        BinValues(&samples, std::min({e.gum.interval_low, m.symmetric.low, m.shortest.low}),
                  std::max({e.gum.interval_high, m.symmetric.high, m.shortest.high}));
    e.validation = ValidateGuf(e.gum, *e.monte_carlo, budget.monte_carlo.ndig);
    e.ok = e.monte_carlo->ok;
  }
  return e;
}

nlohmann::ordered_json BudgetReportJson(const BudgetEvaluation& e) {
  ordered_json j;
  j["schema"] = "metro.budget-report/1";
  j["budget_file"] = e.budget.file;
  j["measurand"] = {
      {"name", e.budget.measurand},
      {"unit", e.budget.unit},
      {"model", e.budget.model.empty() ? ordered_json() : ordered_json(e.budget.model)}};
  // The unit check (docs/budget-format.md, "Units"); the budget was validated, so it passes.
  const Result<BudgetUnits> units = CheckBudgetUnits(e.budget);
  if (units.ok()) {
    j["measurand"]["unit_check"] = {
        {"checked", units.value().checked},
        {"model_unit",
         units.value().checked ? ordered_json(units.value().model_unit) : ordered_json()},
        {"scale_known", units.value().scale_known},
        {"note", units.value().note}};
  }
  const GumResult& g = e.gum;
  ordered_json result;
  result["value"] = Number(g.value);
  result["u"] = Number(g.u);
  result["dof_eff"] = Dof(g.dof_eff);
  result["k"] = Number(g.k);
  result["U"] = Number(g.expanded);
  result["coverage"] = g.coverage;
  result["interval"] = {Number(g.interval_low), Number(g.interval_high)};
  result["u_first_order"] = Number(g.u_first_order);
  result["second_order"] = g.second_order;
  result["dof_policy"] = CorrelatedDofPolicyName(g.dof_policy);
  result["correlated"] = g.correlated;
  result["dof_note"] = g.dof_note;
  result["derivatives"] = g.derivatives;  // exact (symbolic, GiNaC), stated, or differences
  const RoundedResult s = RoundForStatement(g.value, g.expanded);
  const std::string unit = e.budget.unit.empty() ? "" : " " + e.budget.unit;
  result["statement"] = fmt::format("{} = ({} +- {}){}, k = {:.2f}, p = {}", e.budget.measurand,
                                    s.value, s.uncertainty, unit, g.k, Percent(g.coverage));
  j["result"] = result;
  ordered_json lines = ordered_json::array();
  for (const BudgetLine& line : g.budget) {
    ordered_json l;
    l["name"] = line.name;
    l["value"] = line.value;
    l["u"] = line.u;
    l["distribution"] = line.distribution;
    l["sensitivity"] = line.sensitivity;
    l["contribution"] = line.contribution;
    l["dof"] = Dof(line.dof);
    l["percent"] = line.percent;
    const auto it = std::find_if(e.budget.inputs.begin(), e.budget.inputs.end(),
                                 [&](const BudgetInput& in) { return in.name == line.name; });
    if (it != e.budget.inputs.end()) {
      if (!it->unit.empty()) l["unit"] = it->unit;
      if (!it->note.empty()) l["note"] = it->note;
      if (it->unit_conversion) {
        const UnitConversion& c = *it->unit_conversion;
        l["unit_conversion"] = {{"from", c.from},
                                {"to", c.to},
                                {"factor", c.factor},
                                {"offset", c.offset},
                                {"value_from", it->value_before_conversion},
                                {"u_from", it->u_before_conversion}};
      }
      if (it->session) {
        l["session"] = {{"file", it->session->session},
                        {"sensor", it->session->sensor},
                        {"quantity", it->session->quantity},
                        {"n", it->n}};
      }
    }
    lines.push_back(l);
  }
  j["budget"] = lines;
  ordered_json corr = ordered_json::array();
  for (const Correlation& c : e.budget.correlations)
    corr.push_back({{"a", c.a}, {"b", c.b}, {"r", c.r}});
  j["correlations"] = corr;
  if (e.monte_carlo) {
    const McResult& m = *e.monte_carlo;
    ordered_json mc;
    mc["trials"] = m.trials;
    mc["seed"] = m.seed;
    mc["generator"] = m.generator;
    mc["threads"] = m.threads;
    mc["adaptive"] = m.adaptive;
    mc["converged"] = m.converged;
    mc["blocks"] = m.blocks;
    mc["ndig"] = e.budget.monte_carlo.ndig;
    mc["coverage"] = m.coverage;
    mc["value"] = Number(m.value);
    mc["u"] = Number(m.u);
    // JCGM 101 6.4.9.4: with an input of nu <= 2, u (and for nu <= 1 the mean) is undefined.
    mc["u_defined"] = m.u_defined;
    mc["mean_defined"] = m.mean_defined;
    mc["inputs_without_variance"] = m.inputs_without_variance;
    mc["interval_symmetric"] = {Number(m.symmetric.low), Number(m.symmetric.high)};
    mc["interval_shortest"] = {Number(m.shortest.low), Number(m.shortest.high)};
    // JCGM 101 7.7 as written, beside the fitted minimum reported above (docs/uncertainty.md).
    mc["interval_shortest_discrete"] = {Number(m.shortest_discrete.low),
                                        Number(m.shortest_discrete.high)};
    // The MCM's own numerical tolerance (7.9.2) and, adaptive, the 95 % half-widths that met it.
    mc["numerical_tolerance"] = Number(m.delta);
    if (m.adaptive) {
      const McStability& st = m.stability;
      mc["stability_half_width"] = {
          {"value", Number(st.value)},
          {"u", Number(st.u)},
          {"interval_symmetric", {Number(st.symmetric_low), Number(st.symmetric_high)}},
          {"interval_shortest", {Number(st.shortest_low), Number(st.shortest_high)}},
          {"groups", st.groups}};
    }
    if (e.validation) {
      mc["delta"] = Number(e.validation->delta);
      mc["d_low"] = Number(e.validation->d_low);
      mc["d_high"] = Number(e.validation->d_high);
      mc["guf_validated"] = e.validation->validated;
    }
    if (e.histogram) {
      mc["histogram"] = {{"edges", e.histogram->edges},
                         {"counts", e.histogram->counts},
                         {"below", e.histogram->below},
                         {"above", e.histogram->above}};
    }
    if (!m.message.empty()) mc["message"] = m.message;
    j["monte_carlo"] = mc;
  } else {
    j["monte_carlo"] = nullptr;
  }
  return j;
}

std::string BudgetReportTable(const BudgetEvaluation& e) {
  const GumResult& g = e.gum;
  const std::string unit = e.budget.unit.empty() ? "" : " " + e.budget.unit;
  std::string out;
  out += fmt::format("Measurand {}{}", e.budget.measurand,
                     e.budget.unit.empty() ? "" : " [" + e.budget.unit + "]");
  out += e.budget.model.empty() ? "  (y = sum c_i x_i)\n" : "  = " + e.budget.model + "\n\n";
  if (e.budget.model.empty()) out += "\n";
  out += fmt::format("{:<14} {:>14} {:>12} {:<12} {:>12} {:>12} {:>8} {:>7}\n", "input", "value",
                     "u", "distribution", "c_i", "u_i(y)", "dof", "%");
  for (const BudgetLine& l : g.budget) {
    out +=
        fmt::format("{:<14} {:>14} {:>12} {:<12} {:>12} {:>12} {:>8} {:>7.2f}\n", l.name,
                    Long(l.value), Short(l.u), l.distribution, Short(l.sensitivity),
                    Short(l.contribution), std::isfinite(l.dof) ? Short(l.dof) : "inf", l.percent);
  }
  for (const BudgetInput& in : e.budget.inputs) {
    if (!in.unit_conversion) continue;
    const UnitConversion& c = *in.unit_conversion;
    out += fmt::format("unit: {} converted from {} to {}: {} {} -> {} {}, u {} -> {} (x {}{})\n",
                       in.name, c.from, c.to, Long(in.value_before_conversion), c.from,
                       Long(in.value), c.to, Short(in.u_before_conversion), Short(in.u),
                       Long(c.factor), c.offset != 0.0 ? " + " + Long(c.offset) : "");
  }
  out += "\n";
  out += fmt::format("GUM (JCGM 100): y = {}{}, u_c = {}{}{}, nu_eff = {}, k = {:.3f}, U = {}{}\n",
                     Long(g.value), unit, Short(g.u), unit, g.second_order ? " (second order)" : "",
                     std::isfinite(g.dof_eff) ? fmt::format("{:.2f}", g.dof_eff) : "inf", g.k,
                     Short(g.expanded), unit);
  if (g.correlated) out += "  dof: " + g.dof_note + "\n";
  const RoundedResult s = RoundForStatement(g.value, g.expanded);
  out += fmt::format("Result (JCGM 100 7.2.6): {} = ({} +- {}){}, k = {:.2f}, p = {}\n",
                     e.budget.measurand, s.value, s.uncertainty, unit, g.k, Percent(g.coverage));
  if (e.monte_carlo) {
    const McResult& m = *e.monte_carlo;
    out += fmt::format(
        "\nMonte Carlo (JCGM 101): M = {}{}, seed {}, y = {}{}, u = {}{}\n", m.trials,
        m.adaptive ? fmt::format(" (adaptive, {} blocks, {})", m.blocks,
                                 m.converged ? "settled" : "NOT settled")
                   : "",
        m.seed, m.mean_defined ? Long(m.value) : "undefined (no mean)", m.mean_defined ? unit : "",
        m.u_defined ? Short(m.u) : "undefined (an input has no variance)", m.u_defined ? unit : "");
    out += fmt::format("  {} interval: shortest [{}, {}], symmetric [{}, {}]{}\n",
                       Percent(m.coverage), Long(m.shortest.low), Long(m.shortest.high),
                       Long(m.symmetric.low), Long(m.symmetric.high), unit);
    if (m.adaptive) {
      const McStability& st = m.stability;
      out += fmt::format(
          "  stable to delta = {} (7.9.2): 95 % half-widths y {}, u {}, symmetric [{}, {}], "
          "shortest [{}, {}]\n",
          Short(m.delta), Short(st.value), Short(st.u), Short(st.symmetric_low),
          Short(st.symmetric_high), Short(st.shortest_low), Short(st.shortest_high));
    }
    if (e.validation) {
      out += fmt::format("  GUF validation (clause 8): d_low = {}, d_high = {}, delta = {} -> {}\n",
                         Short(e.validation->d_low), Short(e.validation->d_high),
                         Short(e.validation->delta),
                         e.validation->validated ? "validated" : "NOT validated");
    }
    if (!m.message.empty()) out += "  " + m.message + "\n";
  }
  return out;
}

}  // namespace metro
