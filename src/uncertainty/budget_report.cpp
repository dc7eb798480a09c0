#include "metro/uncertainty/budget_report.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/json_reader.hpp"
#include "core/json_text.hpp"
#include "metro/core/rounding.hpp"
#include "metro/core/terminal_text.hpp"
#include "uncertainty/budget_report_json.hpp"
#include "uncertainty/model_quote.hpp"

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

// A report written before "stated" existed took its derivatives exactly unless it says
// otherwise.
bool DerivativesExact(const BudgetReportResult& result) {
  return result.derivatives.find("central differences") == std::string::npos;
}

// See BudgetReportStated.
BudgetReportStated DecideStated(const BudgetReport& r, bool derivatives_exact) {
  const BudgetReportResult& g = r.result;
  BudgetReportStated s;
  s.coverage = g.coverage;
  const auto guf = [&](std::string reason) {
    s.method = kStatedGuf;
    s.reason = std::move(reason);
    s.value = g.value;
    s.u = g.u;
    s.interval = g.interval;
    s.statement = g.statement;
  };
  if (!r.monte_carlo) {
    guf("no Monte Carlo run: the GUF result is stated without validation (JCGM 101:2008 8.2 "
        "needs one)");
    return s;
  }
  const BudgetReportMonteCarlo& m = *r.monte_carlo;
  std::string why;
  if (!derivatives_exact) {
    why = "the GUF sensitivity coefficients were taken by central differences (" + g.derivatives +
          ")";
  } else if (m.validation && !m.validation->validated) {
    why = fmt::format(
        "the GUF result is not validated (JCGM 101:2008 8.2): d_low = {}, d_high = {}, "
        "delta = {}",
        Short(m.validation->d_low), Short(m.validation->d_high), Short(m.validation->delta));
  } else if (m.validation) {
    guf("the GUF result is validated by the Monte Carlo method (JCGM 101:2008 8.2)");
    return s;
  } else {
    guf("the report holds no GUF validation");
    return s;
  }
  s.method = kStatedMonteCarlo;
  s.reason = why + ": the Monte Carlo result is stated (JCGM 101:2008 8.2, 7.7)";
  s.value = m.mean_defined ? m.value : std::numeric_limits<double>::quiet_NaN();
  s.u = m.u_defined ? m.u : std::numeric_limits<double>::quiet_NaN();
  s.interval = m.shortest;
  s.coverage = m.coverage;
  const std::string unit = r.measurand.unit.empty() ? "" : " " + r.measurand.unit;
  const RoundedResult v = RoundForStatement(s.value, s.u);
  // The ends to the decimal place of the value (u to two significant digits, 7.2.6).
  RoundedInterval iv = RoundInterval(s.interval.low, s.interval.high);
  if (std::isfinite(s.u) && s.u > 0.0) {
    iv = {RoundForStatement(s.interval.low, s.u).value,
          RoundForStatement(s.interval.high, s.u).value};
  }
  s.statement =
      fmt::format("{} = {}, u({}) = {}, shortest {} coverage interval [{}, {}]{} (JCGM 101 7.7)",
                  r.measurand.name, m.mean_defined ? v.value + unit : "undefined (no mean)",
                  r.measurand.name, m.u_defined ? v.uncertainty + unit : "undefined (no variance)",
                  Percent(s.coverage), iv.low, iv.high, unit);
  return s;
}

}  // namespace

Result<BudgetEvaluation> EvaluateBudget(const Budget& budget, ProgressSink* progress) {
  BudgetEvaluation e;
  e.budget = budget;
  auto gum = EvaluateGum(budget);
  if (!gum.ok()) return gum.error();
  e.gum = std::move(gum).value();
  if (!e.gum.derivatives_exact && !budget.monte_carlo.enabled) {
    // Central differences are never the stated basis (issue #36): without a Monte Carlo run
    // there is nothing sound to state.
    return internal::ModelError(
        budget, "no exact derivatives (" + e.gum.derivatives +
                    "), and monte_carlo is disabled: the GUF result would rest on central "
                    "differences; enable monte_carlo, whose result is then stated");
  }
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

BudgetReport MakeBudgetReport(const BudgetEvaluation& e) {
  BudgetReport r;
  r.budget_file = e.budget.file;
  r.measurand.name = e.budget.measurand;
  r.measurand.unit = e.budget.unit;
  r.measurand.model = e.budget.model;
  // The unit check (docs/budget-format.md, "Units"); the budget was validated, so it passes.
  Result<BudgetUnits> units = CheckBudgetUnits(e.budget);
  if (units.ok()) {
    r.measurand.unit_check = std::move(units).value();
    if (!r.measurand.unit_check->checked) r.measurand.unit_check->model_unit.clear();
  }
  const GumResult& g = e.gum;
  BudgetReportResult& result = r.result;
  result.value = g.value;
  result.u = g.u;
  result.dof_eff = g.dof_eff;
  result.k = g.k;
  result.expanded = g.expanded;
  result.coverage = g.coverage;
  result.interval = {g.interval_low, g.interval_high};
  result.u_first_order = g.u_first_order;
  result.second_order = g.second_order;
  result.dof_policy = g.dof_policy;
  result.correlated = g.correlated;
  result.dof_note = g.dof_note;
  result.derivatives = g.derivatives;
  const RoundedResult s = RoundForStatement(g.value, g.expanded);
  const std::string unit = e.budget.unit.empty() ? "" : " " + e.budget.unit;
  result.statement = fmt::format("{} = ({} +- {}){}, k = {:.2f}, p = {}", e.budget.measurand,
                                 s.value, s.uncertainty, unit, g.k, Percent(g.coverage));
  for (const BudgetLine& line : g.budget) {
    BudgetReportLine l;
    l.name = line.name;
    l.value = line.value;
    l.u = line.u;
    l.distribution = line.distribution;
    l.sensitivity = line.sensitivity;
    l.contribution = line.contribution;
    l.dof = line.dof;
    l.percent = line.percent;
    const auto it = std::find_if(e.budget.inputs.begin(), e.budget.inputs.end(),
                                 [&](const BudgetInput& in) { return in.name == line.name; });
    if (it != e.budget.inputs.end()) {
      l.unit = it->unit;
      l.note = it->note;
      if (it->unit_conversion) {
        const UnitConversion& c = *it->unit_conversion;
        l.unit_conversion = BudgetLineConversion{
            c.from, c.to, c.factor, c.offset, it->value_before_conversion, it->u_before_conversion};
      }
      if (it->session) {
        l.session = BudgetLineSession{it->session->session, it->session->sensor,
                                      it->session->quantity, it->n};
      }
    }
    r.budget.push_back(std::move(l));
  }
  r.correlations = e.budget.correlations;
  if (e.monte_carlo) {
    const McResult& m = *e.monte_carlo;
    BudgetReportMonteCarlo mc;
    mc.trials = m.trials;
    mc.seed = m.seed;
    mc.generator = m.generator;
    mc.threads = m.threads;
    mc.adaptive = m.adaptive;
    mc.converged = m.converged;
    mc.blocks = m.blocks;
    mc.ndig = e.budget.monte_carlo.ndig;
    mc.coverage = m.coverage;
    mc.value = m.value;
    mc.u = m.u;
    mc.u_defined = m.u_defined;
    mc.mean_defined = m.mean_defined;
    mc.inputs_without_variance = m.inputs_without_variance;
    mc.symmetric = m.symmetric;
    mc.shortest = m.shortest;
    mc.shortest_discrete = m.shortest_discrete;
    mc.numerical_tolerance = m.delta;
    if (m.adaptive) mc.stability = m.stability;
    mc.validation = e.validation;
    mc.histogram = e.histogram;
    mc.message = m.message;
    r.monte_carlo = std::move(mc);
  }
  r.stated = DecideStated(r, e.gum.derivatives_exact);
  return r;
}

namespace {

ordered_json Interval(const CoverageInterval& i) { return {Number(i.low), Number(i.high)}; }

CoverageInterval ReadInterval(const JsonCursor& c) {
  const std::vector<double> v = c.NumbersOrNaN();
  if (!c.ok()) return {};
  if (v.size() != 2) {
    c.Fail("an array of 2 numbers or nulls [low, high]");
    return {};
  }
  return {v[0], v[1]};
}

}  // namespace

ordered_json ToJsonValue(const BudgetReport& r) {
  ordered_json j;
  j["schema"] = kBudgetReportSchema;
  j["budget_file"] = r.budget_file;
  j["measurand"] = {
      {"name", r.measurand.name},
      {"unit", r.measurand.unit},
      {"model", r.measurand.model.empty() ? ordered_json() : ordered_json(r.measurand.model)}};
  if (r.measurand.unit_check) {
    const BudgetUnits& u = *r.measurand.unit_check;
    j["measurand"]["unit_check"] = {
        {"checked", u.checked},
        {"model_unit", u.checked ? ordered_json(u.model_unit) : ordered_json()},
        {"scale_known", u.scale_known},
        {"note", u.note}};
  }
  const BudgetReportResult& g = r.result;
  ordered_json result;
  result["value"] = Number(g.value);
  result["u"] = Number(g.u);
  result["dof_eff"] = Dof(g.dof_eff);
  result["k"] = Number(g.k);
  result["U"] = Number(g.expanded);
  result["coverage"] = g.coverage;
  result["interval"] = Interval(g.interval);
  result["u_first_order"] = Number(g.u_first_order);
  result["second_order"] = g.second_order;
  result["dof_policy"] = CorrelatedDofPolicyName(g.dof_policy);
  result["correlated"] = g.correlated;
  result["dof_note"] = g.dof_note;
  result["derivatives"] = g.derivatives;
  result["statement"] = g.statement;
  j["result"] = result;
  ordered_json lines = ordered_json::array();
  for (const BudgetReportLine& line : r.budget) {
    ordered_json l;
    l["name"] = line.name;
    l["value"] = line.value;
    l["u"] = line.u;
    l["distribution"] = line.distribution;
    l["sensitivity"] = line.sensitivity;
    l["contribution"] = line.contribution;
    l["dof"] = Dof(line.dof);
    l["percent"] = line.percent;
    if (!line.unit.empty()) l["unit"] = line.unit;
    if (!line.note.empty()) l["note"] = line.note;
    if (line.unit_conversion) {
      const BudgetLineConversion& c = *line.unit_conversion;
      l["unit_conversion"] = {{"from", c.from},
                              {"to", c.to},
                              {"factor", c.factor},
                              {"offset", c.offset},
                              {"value_from", c.value_from},
                              {"u_from", c.u_from}};
    }
    if (line.session) {
      l["session"] = {{"file", line.session->file},
                      {"sensor", line.session->sensor},
                      {"quantity", line.session->quantity},
                      {"n", line.session->n}};
    }
    lines.push_back(l);
  }
  j["budget"] = lines;
  ordered_json corr = ordered_json::array();
  for (const Correlation& c : r.correlations) corr.push_back({{"a", c.a}, {"b", c.b}, {"r", c.r}});
  j["correlations"] = corr;
  if (r.monte_carlo) {
    const BudgetReportMonteCarlo& m = *r.monte_carlo;
    ordered_json mc;
    mc["trials"] = m.trials;
    mc["seed"] = m.seed;
    mc["generator"] = m.generator;
    mc["threads"] = m.threads;
    mc["adaptive"] = m.adaptive;
    mc["converged"] = m.converged;
    mc["blocks"] = m.blocks;
    mc["ndig"] = m.ndig;
    mc["coverage"] = m.coverage;
    mc["value"] = Number(m.value);
    mc["u"] = Number(m.u);
    // JCGM 101 6.4.9.4: with an input of nu <= 2, u (and for nu <= 1 the mean) is undefined.
    mc["u_defined"] = m.u_defined;
    mc["mean_defined"] = m.mean_defined;
    mc["inputs_without_variance"] = m.inputs_without_variance;
    mc["interval_symmetric"] = Interval(m.symmetric);
    mc["interval_shortest"] = Interval(m.shortest);
    // JCGM 101 7.7 as written, beside the fitted minimum reported above (docs/uncertainty.md).
    mc["interval_shortest_discrete"] = Interval(m.shortest_discrete);
    // The MCM's own numerical tolerance (7.9.2) and, adaptive, the 95 % half-widths that met it.
    mc["numerical_tolerance"] = Number(m.numerical_tolerance);
    if (m.stability) {
      const McStability& st = *m.stability;
      mc["stability_half_width"] = {
          {"value", Number(st.value)},
          {"u", Number(st.u)},
          {"interval_symmetric", {Number(st.symmetric_low), Number(st.symmetric_high)}},
          {"interval_shortest", {Number(st.shortest_low), Number(st.shortest_high)}},
          {"groups", st.groups}};
    }
    if (m.validation) {
      mc["delta"] = Number(m.validation->delta);
      mc["d_low"] = Number(m.validation->d_low);
      mc["d_high"] = Number(m.validation->d_high);
      mc["guf_validated"] = m.validation->validated;
    }
    if (m.histogram) {
      mc["histogram"] = {{"edges", m.histogram->edges},
                         {"counts", m.histogram->counts},
                         {"below", m.histogram->below},
                         {"above", m.histogram->above}};
    }
    if (!m.message.empty()) mc["message"] = m.message;
    j["monte_carlo"] = mc;
  } else {
    j["monte_carlo"] = nullptr;
  }
  const BudgetReportStated& st = r.stated;
  j["stated"] = {{"method", st.method},
                 {"reason", st.reason},
                 {"value", Number(st.value)},
                 {"u", Number(st.u)},
                 {"interval", Interval(st.interval)},
                 {"coverage", Number(st.coverage)},
                 {"statement", st.statement}};
  return j;
}

BudgetReport BudgetReportFromJsonValue(const JsonCursor& j) {
  BudgetReport r;
  if (!j.IsObject()) {
    j.Fail(fmt::format("a {} object", kBudgetReportSchema));
    return r;
  }
  if (j["schema"].String() != kBudgetReportSchema && j.ok()) {
    j["schema"].Fail(fmt::format("\"{}\"", kBudgetReportSchema));
  }
  r.budget_file = j["budget_file"].String();
  const JsonCursor measurand = j["measurand"];
  r.measurand.name = measurand["name"].String();
  r.measurand.unit = measurand["unit"].String();
  r.measurand.model = measurand["model"].OptionalString().value_or("");
  if (measurand.Has("unit_check")) {
    const JsonCursor c = measurand["unit_check"];
    BudgetUnits u;
    u.checked = c["checked"].Bool();
    u.model_unit = c["model_unit"].OptionalString().value_or("");
    u.scale_known = c["scale_known"].Bool();
    u.note = c["note"].String();
    r.measurand.unit_check = u;
  }
  const JsonCursor result = j["result"];
  BudgetReportResult& g = r.result;
  g.value = result["value"].NumberOrNaN();
  g.u = result["u"].NumberOrNaN();
  g.dof_eff = result["dof_eff"].NumberOrInfinity();
  g.k = result["k"].NumberOrNaN();
  g.expanded = result["U"].NumberOrNaN();
  g.coverage = result["coverage"].NumberOrNaN();
  g.interval = ReadInterval(result["interval"]);
  g.u_first_order = result["u_first_order"].NumberOrNaN();
  g.second_order = result["second_order"].Bool();
  const JsonCursor policy = result["dof_policy"];
  const std::string policy_name = policy.String();
  bool known_policy = false;
  for (CorrelatedDofPolicy p :
       {CorrelatedDofPolicy::kGroup, CorrelatedDofPolicy::kIgnore, CorrelatedDofPolicy::kReject}) {
    if (policy_name == CorrelatedDofPolicyName(p)) {
      g.dof_policy = p;
      known_policy = true;
    }
  }
  if (!known_policy && policy.ok()) policy.Fail("one of \"group\", \"ignore\", \"reject\"");
  g.correlated = result["correlated"].Bool();
  g.dof_note = result["dof_note"].String();
  // Reports before 2026-11-27 have no derivatives, no interval_shortest_discrete,
  // numerical_tolerance, u_defined, mean_defined or inputs_without_variance
  // (docs/budget-format.md).
  if (result.Has("derivatives")) g.derivatives = result["derivatives"].String();
  g.statement = result["statement"].String();
  const JsonCursor lines = j["budget"];
  if (!lines.IsArray()) lines.Fail("an array of input lines");
  for (size_t i = 0; i < lines.Size(); ++i) {
    const JsonCursor l = lines[i];
    BudgetReportLine line;
    line.name = l["name"].String();
    line.value = l["value"].NumberOrNaN();
    line.u = l["u"].NumberOrNaN();
    line.distribution = l["distribution"].String();
    line.sensitivity = l["sensitivity"].NumberOrNaN();
    line.contribution = l["contribution"].NumberOrNaN();
    line.dof = l["dof"].NumberOrInfinity();
    line.percent = l["percent"].NumberOrNaN();
    if (l.Has("unit")) line.unit = l["unit"].String();
    if (l.Has("note")) line.note = l["note"].String();
    if (l.Has("unit_conversion")) {
      const JsonCursor c = l["unit_conversion"];
      line.unit_conversion = BudgetLineConversion{c["from"].String(),       c["to"].String(),
                                                  c["factor"].Number(),     c["offset"].Number(),
                                                  c["value_from"].Number(), c["u_from"].Number()};
    }
    if (l.Has("session")) {
      const JsonCursor c = l["session"];
      line.session = BudgetLineSession{c["file"].String(), c["sensor"].Integer(),
                                       c["quantity"].String(), c["n"].Integer()};
    }
    r.budget.push_back(std::move(line));
  }
  const JsonCursor correlations = j["correlations"];
  if (!correlations.IsArray()) correlations.Fail("an array of correlations {a, b, r}");
  for (size_t i = 0; i < correlations.Size(); ++i) {
    const JsonCursor c = correlations[i];
    r.correlations.push_back({c["a"].String(), c["b"].String(), c["r"].Number()});
  }
  const JsonCursor mc = j["monte_carlo"];
  if (!mc.IsNull()) {
    BudgetReportMonteCarlo m;
    m.trials = mc["trials"].Integer();
    // Seeds are unsigned 64-bit: above 2^63 - 1 the JSON integer is unsigned.
    const JsonCursor seed = mc["seed"];
    if (seed.Raw().is_number_unsigned()) {
      m.seed = seed.Raw().get<uint64_t>();
    } else {
      const int64_t s = seed.Integer();
      if (s < 0 && seed.ok()) seed.Fail("an integer >= 0");
      m.seed = static_cast<uint64_t>(s);
    }
    m.generator = mc["generator"].String();
    m.threads = mc["threads"].Integer();
    m.adaptive = mc["adaptive"].Bool();
    m.converged = mc["converged"].Bool();
    m.blocks = mc["blocks"].Integer();
    m.ndig = mc["ndig"].Integer();
    m.coverage = mc["coverage"].NumberOrNaN();
    m.value = mc["value"].NumberOrNaN();
    m.u = mc["u"].NumberOrNaN();
    if (mc.Has("u_defined")) m.u_defined = mc["u_defined"].Bool();
    if (mc.Has("mean_defined")) m.mean_defined = mc["mean_defined"].Bool();
    if (mc.Has("inputs_without_variance")) {
      m.inputs_without_variance = mc["inputs_without_variance"].Strings();
    }
    m.symmetric = ReadInterval(mc["interval_symmetric"]);
    m.shortest = ReadInterval(mc["interval_shortest"]);
    if (mc.Has("interval_shortest_discrete")) {
      m.shortest_discrete = ReadInterval(mc["interval_shortest_discrete"]);
    }
    if (mc.Has("numerical_tolerance")) {
      m.numerical_tolerance = mc["numerical_tolerance"].NumberOrNaN();
    }
    if (mc.Has("stability_half_width")) {
      const JsonCursor st = mc["stability_half_width"];
      McStability s;
      s.value = st["value"].NumberOrNaN();
      s.u = st["u"].NumberOrNaN();
      const CoverageInterval sym = ReadInterval(st["interval_symmetric"]);
      const CoverageInterval shortest = ReadInterval(st["interval_shortest"]);
      s.symmetric_low = sym.low;
      s.symmetric_high = sym.high;
      s.shortest_low = shortest.low;
      s.shortest_high = shortest.high;
      s.groups = st["groups"].Integer();
      m.stability = s;
    }
    if (mc.Has("guf_validated")) {
      GufValidation v;
      v.delta = mc["delta"].NumberOrNaN();
      v.d_low = mc["d_low"].NumberOrNaN();
      v.d_high = mc["d_high"].NumberOrNaN();
      v.validated = mc["guf_validated"].Bool();
      m.validation = v;
    }
    if (mc.Has("histogram")) {
      const JsonCursor h = mc["histogram"];
      McHistogram histogram;
      histogram.edges = h["edges"].Numbers();
      histogram.counts = h["counts"].Integers();
      histogram.below = h["below"].Integer();
      histogram.above = h["above"].Integer();
      if (h.ok() && histogram.edges.size() != histogram.counts.size() + 1) {
        h["edges"].Fail(fmt::format("{} edges (one more than the {} counts)",
                                    histogram.counts.size() + 1, histogram.counts.size()));
      }
      m.histogram = std::move(histogram);
    }
    if (mc.Has("message")) m.message = mc["message"].String();
    r.monte_carlo = std::move(m);
  }
  if (j.Has("stated")) {
    const JsonCursor st = j["stated"];
    const std::string method = st["method"].String();
    if (method != kStatedGuf && method != kStatedMonteCarlo && st.ok()) {
      st["method"].Fail(fmt::format("\"{}\" or \"{}\"", kStatedGuf, kStatedMonteCarlo));
    }
    r.stated.method = method;
    r.stated.reason = st["reason"].String();
    r.stated.value = st["value"].NumberOrNaN();
    r.stated.u = st["u"].NumberOrNaN();
    r.stated.interval = ReadInterval(st["interval"]);
    r.stated.coverage = st["coverage"].NumberOrNaN();
    r.stated.statement = st["statement"].String();
  } else {
    r.stated = DecideStated(r, DerivativesExact(r.result));  // Written before 2026-12-02.
  }
  return r;
}

std::string ToJson(const BudgetReport& report) { return JsonText(ToJsonValue(report), 2); }

Result<BudgetReport> BudgetReportFromJson(std::string_view text, const std::string& file) {
  return ReadJsonText<BudgetReport>(text, file, BudgetReportFromJsonValue);
}

ordered_json BudgetReportJson(const BudgetEvaluation& e) {
  return ToJsonValue(MakeBudgetReport(e));
}

namespace {

// `report` with every string it holds from the budget (names, units, the model, statements
// that quote them) escaped for a console table: one record per line whatever the budget's
// strings hold (a name "x\nResult ..." must not print a line of its own).
BudgetReport EscapedForConsole(BudgetReport report) {
  auto escape = [](std::string* text) { *text = EscapeControlChars(*text); };
  for (std::string* text : {&report.measurand.name, &report.measurand.unit, &report.measurand.model,
                            &report.result.dof_note, &report.result.statement,
                            &report.stated.reason, &report.stated.statement}) {
    escape(text);
  }
  for (BudgetReportLine& l : report.budget) {
    escape(&l.name);
    escape(&l.distribution);
    if (l.unit_conversion) {
      escape(&l.unit_conversion->from);
      escape(&l.unit_conversion->to);
    }
  }
  if (report.monte_carlo) escape(&report.monte_carlo->message);
  return report;
}

}  // namespace

std::string BudgetReportTable(const BudgetReport& report) {
  const BudgetReport r = EscapedForConsole(report);
  const BudgetReportResult& g = r.result;
  const std::string& measurand = r.measurand.name;
  const std::string unit = r.measurand.unit.empty() ? "" : " " + r.measurand.unit;
  std::string out;
  out += fmt::format("Measurand {}{}", measurand,
                     r.measurand.unit.empty() ? "" : " [" + r.measurand.unit + "]");
  out += r.measurand.model.empty() ? "  (y = sum c_i x_i)\n" : "  = " + r.measurand.model + "\n\n";
  if (r.measurand.model.empty()) out += "\n";
  out += fmt::format("{:<14} {:>14} {:>12} {:<12} {:>12} {:>12} {:>8} {:>7}\n", "input", "value",
                     "u", "distribution", "c_i", "u_i(y)", "dof", "%");
  for (const BudgetReportLine& l : r.budget) {
    out +=
        fmt::format("{:<14} {:>14} {:>12} {:<12} {:>12} {:>12} {:>8} {:>7.2f}\n", l.name,
                    Long(l.value), Short(l.u), l.distribution, Short(l.sensitivity),
                    Short(l.contribution), std::isfinite(l.dof) ? Short(l.dof) : "inf", l.percent);
  }
  for (const BudgetReportLine& l : r.budget) {
    if (!l.unit_conversion) continue;
    const BudgetLineConversion& c = *l.unit_conversion;
    out += fmt::format("unit: {} converted from {} to {}: {} {} -> {} {}, u {} -> {} (x {}{})\n",
                       l.name, c.from, c.to, Long(c.value_from), c.from, Long(l.value), c.to,
                       Short(c.u_from), Short(l.u), Long(c.factor),
                       c.offset != 0.0 ? " + " + Long(c.offset) : "");
  }
  out += "\n";
  out += fmt::format("GUM (JCGM 100): y = {}{}, u_c = {}{}{}, nu_eff = {}, k = {:.3f}, U = {}{}\n",
                     Long(g.value), unit, Short(g.u), unit, g.second_order ? " (second order)" : "",
                     std::isfinite(g.dof_eff) ? fmt::format("{:.2f}", g.dof_eff) : "inf", g.k,
                     Short(g.expanded), unit);
  if (g.correlated) out += "  dof: " + g.dof_note + "\n";
  const RoundedResult s = RoundForStatement(g.value, g.expanded);
  out += fmt::format("Result (JCGM 100 7.2.6): {} = ({} +- {}){}, k = {:.2f}, p = {}\n", measurand,
                     s.value, s.uncertainty, unit, g.k, Percent(g.coverage));
  if (r.monte_carlo) {
    const BudgetReportMonteCarlo& m = *r.monte_carlo;
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
    if (m.stability) {
      const McStability& st = *m.stability;
      out += fmt::format(
          "  stable to delta = {} (7.9.2): 95 % half-widths y {}, u {}, symmetric [{}, {}], "
          "shortest [{}, {}]\n",
          Short(m.numerical_tolerance), Short(st.value), Short(st.u), Short(st.symmetric_low),
          Short(st.symmetric_high), Short(st.shortest_low), Short(st.shortest_high));
    }
    if (m.validation) {
      out += fmt::format("  GUF validation (clause 8): d_low = {}, d_high = {}, delta = {} -> {}\n",
                         Short(m.validation->d_low), Short(m.validation->d_high),
                         Short(m.validation->delta),
                         m.validation->validated ? "validated" : "NOT validated");
    }
    if (!m.message.empty()) out += "  " + m.message + "\n";
  }
  out += fmt::format("\nStated ({}): {}\n  {}\n",
                     r.stated.method == kStatedGuf ? "GUF, JCGM 100" : "Monte Carlo, JCGM 101",
                     r.stated.statement, r.stated.reason);
  return out;
}

std::string BudgetReportTable(const BudgetEvaluation& e) {
  return BudgetReportTable(MakeBudgetReport(e));
}

}  // namespace metro
