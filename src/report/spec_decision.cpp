#include "metro/report/spec_decision.hpp"

#include <fmt/format.h>

#include <algorithm>

#include "metro/io/columns.hpp"
#include "report/spec_decision_json.hpp"

namespace metro {
namespace {}  // namespace

const char* SpecTermSymbol(NoiseTerm t) {
  return t == NoiseTerm::kRandomWalk ? "N" : t == NoiseTerm::kBiasInstability ? "B" : "K";
}

std::string SpecRulesText(const SpecDecisions& d) {
  ConformityStatement rule{d.rule, d.coverage_factor, d.max_consumer_risk, {}};
  return fmt::format(
      "N as a one-sided density is sqrt(2) N; an in-run bias stability is the Allan deviation's "
      "minimum.\nmax/min figures are specification limits: {}.\ntyp/unstated figures are not "
      "limits: ratio and E_n = (measured - figure) / (2 u) only (ISO 13528:2015 9.7).\n",
      rule.DescribeRule());
}

namespace {

// z with P(|Z| <= z) = confidence for a standard normal Z, by bisection on erf
// (P(|Z| <= z) = erf(z / sqrt(2))).
double TwoSidedNormalQuantile(double confidence) {
  double lo = 0.0, hi = 10.0;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (std::erf(mid / std::sqrt(2.0)) < confidence ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

const SpecFigure* DatasheetFigure(const SpecPart& part, SensorKind sensor, NoiseTerm term) {
  for (const SpecFigure& f : part.figures) {
    if (f.sensor == sensor && f.term() == term && f.kind != SpecKind::kConfig) return &f;
  }
  return nullptr;
}

// The measured coefficient of `term` in SI (N, the Allan minimum for B, K) with its u, or why
// there is none.
Result<std::pair<double, double>> MeasuredSi(const NoiseExportAxis& axis, NoiseTerm term,
                                             double to_si) {
  const AllanReport& a = axis.allan;
  if (!a.ok()) return MakeError("the Allan analysis failed: " + a.error);
  if (term == NoiseTerm::kBiasInstability) {
    // The datasheet's "in-run bias stability" is the curve's minimum, not the fitted B.
    if (a.adev.empty()) return MakeError("no Allan curve");
    const size_t i =
        static_cast<size_t>(std::min_element(a.adev.begin(), a.adev.end()) - a.adev.begin());
    const double z = TwoSidedNormalQuantile(a.confidence);
    const double u = (a.ci_high[i] - a.ci_low[i]) / (2.0 * z);
    if (!std::isfinite(u)) return MakeError("the Allan minimum has no confidence interval");
    return std::make_pair(a.adev[i] * to_si, u * to_si);
  }
  if (a.fit_error) return MakeError("the noise terms could not be fitted: " + *a.fit_error);
  const AllanNoiseTermReport& t = a.term(term);
  if (!t.supported || std::isnan(t.value) || !(t.u >= 0.0)) {
    return MakeError("the fit does not support the term (value null, supported false)");
  }
  if (t.model_rejected.value_or(false)) {
    return MakeError("the IEEE 952 model was rejected over the fitted range (model_rejected)");
  }
  return std::make_pair(t.value * to_si, t.u * to_si);
}

std::string DocumentLine(const SpecPart& part, const SpecFigure& f) {
  const SpecDocument* d = part.Document(f.source);
  return fmt::format("{} rev. {} page {}", d->number, d->revision, f.page);
}

SpecDecisionRow JudgeAxis(const SpecPart& part, const NoiseExportAxis& axis, SensorKind sensor,
                          const SpecFigure& f, double to_si, const SpecDecisionOptions& o) {
  SpecDecisionRow r;
  r.quantity = axis.quantity;
  r.sensor = sensor;
  r.term = f.term();
  r.figure = f;
  r.document = DocumentLine(part, f);
  Result<std::pair<double, double>> m = MeasuredSi(axis, f.term(), to_si);
  if (!m.ok()) {
    r.note = "not resolved by the record: " + m.error().message + "; nothing filled in";
    return r;
  }
  // Into the figure's convention (one-sided density: sqrt(2) N) and unit.
  const double scale = (f.convention == SpecConvention::kOneSidedDensity ? std::sqrt(2.0) : 1.0) /
                       SpecUnitOf(f.unit)->si_factor;
  r.measured = m.value().first * scale;
  r.u = m.value().second * scale;
  r.ratio = r.measured / f.value;
  r.e_n = (r.measured - f.value) / (2.0 * r.u);  // ISO 13528:2015 9.7, U_x = 0.
  if (f.kind == SpecKind::kMax || f.kind == SpecKind::kMin) {
    const std::optional<double> lower =
        f.kind == SpecKind::kMin ? std::optional<double>(f.value) : std::nullopt;
    const std::optional<double> upper =
        f.kind == SpecKind::kMax ? std::optional<double>(f.value) : std::nullopt;
    r.conformity = DecideConformity(axis.quantity + "." + NoiseTermKey(f.term()), r.measured, r.u,
                                    lower, upper, o.rule, o.coverage_factor, o.max_consumer_risk);
    r.conformity->unit = f.unit;
  } else {
    r.note = fmt::format(
        "{} is not a specification limit: ratio and E_n only, no conformity "
        "decision",
        SpecKindName(f.kind));
  }
  return r;
}

}  // namespace

Result<SpecDecisions> DecideAgainstSpec(const NoiseExportInput& input, const SpecPart& part,
                                        const std::string& library_file,
                                        const SpecDecisionOptions& o) {
  if (std::none_of(part.figures.begin(), part.figures.end(),
                   [](const SpecFigure& f) { return f.kind != SpecKind::kConfig; })) {
    return MakeError(
        fmt::format("{}: the spec library holds no datasheet figure of {} (only "
                    "published configurations: compare them with noise-compare "
                    "--spec-part); see datasets/specs/SOURCE.md",
                    library_file, part.part));
  }
  SpecDecisions out;
  out.part = part.part;
  out.library = library_file;
  out.rule = o.rule;
  out.coverage_factor = o.coverage_factor;
  out.max_consumer_risk = o.max_consumer_risk;
  for (SensorKind sensor : {SensorKind::kAccelerometer, SensorKind::kGyroscope}) {
    const char* target = sensor == SensorKind::kGyroscope ? "rad/s" : "m/s^2";
    // The axes with an SI scale, one quantity per axis (a session's raw `_lsb` columns beside
    // the scaled ones are skipped); an error only when the sensor has none.
    std::vector<std::pair<const NoiseExportAxis*, double>> axes;
    std::string unscaled;
    for (const NoiseExportAxis& a : input.axes) {
      const ColumnInfo info = ClassifyColumn(a.quantity);
      if (info.sensor != sensor) continue;
      const Unit* unit = UnitBySymbol(a.unit);
      const std::optional<double> to_si =
          unit != nullptr ? ConversionFactor(*unit, *UnitBySymbol(target)) : std::nullopt;
      if (!to_si) {
        unscaled = fmt::format("{} is in {}", a.quantity, a.unit.empty() ? "no unit" : a.unit);
        continue;
      }
      if (std::none_of(axes.begin(), axes.end(), [&](const auto& p) {
            return ClassifyColumn(p.first->quantity).axis == info.axis;
          })) {
        axes.push_back({&a, *to_si});
      }
    }
    if (axes.empty() && !unscaled.empty()) {
      return MakeError(
          fmt::format("{}: a datasheet figure needs an SI scale ({})", unscaled, target));
    }
    if (axes.empty()) continue;
    for (NoiseTerm term :
         {NoiseTerm::kRandomWalk, NoiseTerm::kBiasInstability, NoiseTerm::kRateRandomWalk}) {
      const SpecFigure* f = DatasheetFigure(part, sensor, term);
      if (f == nullptr) {
        SpecDecisionRow r;
        r.sensor = sensor;
        r.term = term;
        r.note = fmt::format("{} {}: the datasheet gives no figure; not judged",
                             sensor == SensorKind::kGyroscope ? "gyroscope" : "accelerometer",
                             SpecTermSymbol(term));
        out.rows.push_back(std::move(r));
        continue;
      }
      for (const auto& [a, to_si] : axes)
        out.rows.push_back(JudgeAxis(part, *a, sensor, *f, to_si, o));
    }
  }
  if (out.rows.empty()) {
    return MakeError("the record has no accelerometer or gyroscope axis with --allan");
  }
  return out;
}

std::string SpecDecisionsTable(const SpecDecisions& d) {
  std::string s = fmt::format("{} against the datasheet ({}):\n", d.part, d.library);
  s += fmt::format("{:<10} {:<2} {:>12} {:<18} {:>12} {:>9} {:>8} {:>7}  {}\n", "quantity", "term",
                   "figure", "unit", "measured", "u", "ratio", "E_n", "decision");
  for (const SpecDecisionRow& r : d.rows) {
    if (!r.figure) {
      s += fmt::format("{:<10} {:<2}  {}\n", "-", SpecTermSymbol(r.term), r.note);
      continue;
    }
    const std::string decision =
        r.conformity
            ? fmt::format("{} (p_c {:.3f})", ConformityDecisionName(r.conformity->decision),
                          r.conformity->p_conformance)
            : r.note;
    s += fmt::format(
        "{:<10} {:<2} {:>8.4g} {:<3} {:<18} {:>12.4g} {:>9.2g} {:>8.4g} {:>7.3g}  {}\n", r.quantity,
        SpecTermSymbol(r.term), r.figure->value, SpecKindName(r.figure->kind), r.figure->unit,
        r.measured, r.u, r.ratio, r.e_n, decision);
  }
  return s + SpecRulesText(d);
}

nlohmann::ordered_json SpecDecisionsJson(const SpecDecisions& d) {
  nlohmann::ordered_json rows = nlohmann::ordered_json::array();
  for (const SpecDecisionRow& r : d.rows) {
    nlohmann::ordered_json j;
    j["quantity"] =
        r.quantity.empty() ? nlohmann::ordered_json() : nlohmann::ordered_json(r.quantity);
    j["sensor"] = r.sensor == SensorKind::kGyroscope ? "gyroscope" : "accelerometer";
    j["term"] = NoiseTermKey(r.term);
    if (r.figure) {
      const SpecFigure& f = *r.figure;
      j["figure"] = {{"value", f.value},
                     {"unit", f.unit},
                     {"printed", f.printed},
                     {"kind", SpecKindName(f.kind)},
                     {"convention", SpecConventionName(f.convention)},
                     {"document", r.document},
                     {"table", f.table},
                     {"conditions", f.conditions}};
      j["measured"] = r.measured;
      j["u"] = r.u;
      j["ratio"] = r.ratio;
      j["e_n"] = r.e_n;
    }
    if (r.conformity) {
      j["p_conformance"] = r.conformity->p_conformance;
      j["decision"] = ConformityDecisionName(r.conformity->decision);
    }
    if (!r.note.empty()) j["note"] = r.note;
    rows.push_back(std::move(j));
  }
  ConformityStatement rule{d.rule, d.coverage_factor, d.max_consumer_risk, {}};
  return {{"part", d.part},
          {"library", d.library},
          {"decision_rule", DecisionRuleName(d.rule)},
          {"statement", rule.DescribeRule()},
          {"typ_figures", "not specification limits: ratio and E_n only"},
          {"rows", std::move(rows)}};
}

}  // namespace metro
