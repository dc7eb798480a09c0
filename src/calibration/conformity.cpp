// ParseConformitySpec reads a spec in these stages, in this order (docs/conformity.md):
//
//   rule        ParseRule        known keys; decision_rule with its coverage factor or risk
//   tolerances  ParseTolerance   each entry: constant (once), unit, lower and/or upper
//
// Every error at the value it is about (SpecErrorAt), with what was expected.
#include "metro/calibration/conformity.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <boost/math/distributions/normal.hpp>
#include <cmath>
#include <set>
#include <vector>

#include "calibration/calibration_json.hpp"
#include "core/json_reader.hpp"
#include "core/json_text.hpp"
#include "metro/calibration/named_constants.hpp"
#include "metro/core/file.hpp"
#include "metro/core/terminal_text.hpp"
#include "metro/core/units.hpp"

namespace metro {
namespace {

using nlohmann::json;

Error SpecError(const std::string& path, int64_t line, int64_t column, std::string message) {
  return MakeError(path, line, column, std::move(message));
}

const char* const kSpecShape =
    "expected {\"tolerances\": [{\"constant\": \"accel.b_x\", \"lower\": -300, \"upper\": 300, "
    "\"unit\": \"LSB\"}], \"decision_rule\": \"simple\"|\"guarded\"|\"risk\"[, "
    "\"coverage_factor\": 2][, \"max_consumer_risk\": 0.023]}";

// How a JSON value looks in a message: a string quoted, anything else as JSON, cut short.
std::string Shown(const json& value) {
  if (value.is_string()) return "'" + Excerpt(value.get<std::string>(), 0, 60) + "'";
  return Excerpt(JsonText(value), 0, 60);
}

// Levenshtein distance (insertions, deletions, substitutions of bytes).
size_t EditDistance(const std::string& a, const std::string& b) {
  std::vector<size_t> row(b.size() + 1);
  for (size_t k = 0; k <= b.size(); ++k) row[k] = k;
  for (size_t i = 1; i <= a.size(); ++i) {
    size_t diagonal = row[0];
    row[0] = i;
    for (size_t k = 1; k <= b.size(); ++k) {
      const size_t up = row[k];
      row[k] = std::min({row[k] + 1, row[k - 1] + 1, diagonal + (a[i - 1] != b[k - 1] ? 1 : 0)});
      diagonal = up;
    }
  }
  return row[b.size()];
}

// " (did you mean 'x'?)" for the name of `names` nearest to `name` when it is within a third
// of its length (a typo), else "".
std::string NearestName(const std::string& name, const std::set<std::string>& names) {
  std::string best;
  size_t best_distance = std::string::npos;
  for (const std::string& n : names) {
    const size_t d = EditDistance(name, n);
    if (d < best_distance) {
      best = n;
      best_distance = d;
    }
  }
  if (best.empty() || best_distance == 0 || 3 * best_distance > std::max<size_t>(name.size(), 3)) {
    return "";
  }
  return " (did you mean '" + best + "'?)";
}

bool IsLsbUnit(const std::string& unit) {
  return unit.find("LSB") != std::string::npos || unit.find("lsb") != std::string::npos;
}

}  // namespace

const char* DecisionRuleName(DecisionRule rule) {
  switch (rule) {
    case DecisionRule::kSimple:
      return "simple";
    case DecisionRule::kGuarded:
      return "guarded";
    case DecisionRule::kRisk:
      return "risk";
  }
  return "simple";
}

std::optional<DecisionRule> ParseDecisionRule(const std::string& name) {
  if (name == "simple") return DecisionRule::kSimple;
  if (name == "guarded") return DecisionRule::kGuarded;
  if (name == "risk") return DecisionRule::kRisk;
  return std::nullopt;
}

const char* ConformityDecisionName(ConformityDecision decision) {
  switch (decision) {
    case ConformityDecision::kPass:
      return "pass";
    case ConformityDecision::kFail:
      return "fail";
    case ConformityDecision::kInconclusive:
      return "inconclusive";
  }
  return "fail";
}

std::optional<ConformityDecision> ParseConformityDecision(const std::string& name) {
  if (name == "pass") return ConformityDecision::kPass;
  if (name == "fail") return ConformityDecision::kFail;
  if (name == "inconclusive") return ConformityDecision::kInconclusive;
  return std::nullopt;
}

bool ConformitySpec::IsValid(std::string* why) const {
  if (!(coverage_factor > 0.0) || !std::isfinite(coverage_factor)) {
    *why = "coverage_factor must be a finite number > 0";
    return false;
  }
  if (rule == DecisionRule::kRisk && !(max_consumer_risk > 0.0 && max_consumer_risk < 0.5)) {
    *why = "the risk rule needs max_consumer_risk in (0, 0.5)";
    return false;
  }
  for (const Tolerance& t : tolerances) {
    if (!t.lower && !t.upper) {
      *why = "tolerance of '" + t.constant + "' has no limit";
      return false;
    }
    if (t.lower && t.upper && *t.lower > *t.upper) {
      *why = "tolerance of '" + t.constant + "' has lower > upper";
      return false;
    }
  }
  return true;
}

namespace {

// ---- ParseConformitySpec's stages ---------------------------------------------------------

// An error at the value `where` is about (or the object that lacks it) in the spec's text.
Error SpecErrorAt(const std::string& text, const std::string& path,
                  const std::vector<JsonPathStep>& where, const std::string& message) {
  const auto [line, column] = TextLineColumn(text, JsonValueOffset(text, where));
  return SpecError(path, line, column, message);
}

// The top level: known keys, the decision rule, its coverage factor or consumer risk.
Status ParseRule(const json& j, const std::string& text, const std::string& path,
                 ConformitySpec* spec) {
  const auto at = [&](const std::vector<JsonPathStep>& where, const std::string& message) {
    return SpecErrorAt(text, path, where, message);
  };
  const auto shape = [](const std::string& message) { return message + "; " + kSpecShape; };
  static const std::set<std::string> kTop = {"tolerances", "decision_rule", "coverage_factor",
                                             "max_consumer_risk", "description"};
  for (auto it = j.begin(); it != j.end(); ++it) {
    if (!kTop.count(it.key())) {
      return at({it.key()}, fmt::format("unknown key '{}'; expected tolerances, decision_rule, "
                                        "coverage_factor, max_consumer_risk or description{}",
                                        it.key(), NearestName(it.key(), kTop)));
    }
  }
  if (!j.contains("decision_rule")) return at({}, shape("missing 'decision_rule'"));
  const std::optional<DecisionRule> rule =
      j["decision_rule"].is_string() ? ParseDecisionRule(j["decision_rule"].get<std::string>())
                                     : std::nullopt;
  if (!rule) {
    return at({"decision_rule"},
              fmt::format("decision_rule {} is not simple, guarded or risk; expected "
                          "\"decision_rule\": \"simple\" (or \"guarded\" with \"coverage_factor\": "
                          "2, or \"risk\" with \"max_consumer_risk\": 0.023)",
                          Shown(j["decision_rule"])));
  }
  spec->rule = *rule;
  if (j.contains("coverage_factor")) {
    const json& k = j["coverage_factor"];
    if (!k.is_number() || !std::isfinite(k.get<double>()) || !(k.get<double>() > 0.0)) {
      return at(
          {"coverage_factor"},
          fmt::format("coverage_factor {}: expected a number > 0, e.g. \"coverage_factor\": 2 "
                      "(w = k u, JCGM 106 8.3.2)",
                      Shown(k)));
    }
    spec->coverage_factor = k.get<double>();
  }
  if (j.contains("max_consumer_risk")) {
    const json& r = j["max_consumer_risk"];
    if (!r.is_number()) {
      return at({"max_consumer_risk"},
                fmt::format("max_consumer_risk {}: expected a number in (0, 0.5), e.g. "
                            "\"max_consumer_risk\": 0.023",
                            Shown(r)));
    }
    spec->max_consumer_risk = r.get<double>();
  }
  if (spec->rule == DecisionRule::kRisk &&
      !(spec->max_consumer_risk > 0.0 && spec->max_consumer_risk < 0.5)) {
    return at(j.contains("max_consumer_risk") ? std::vector<JsonPathStep>{"max_consumer_risk"}
                                              : std::vector<JsonPathStep>{"decision_rule"},
              "the risk rule needs max_consumer_risk in (0, 0.5); expected \"decision_rule\": "
              "\"risk\", \"max_consumer_risk\": 0.023");
  }
  return Status::Ok();
}

constexpr const char* kEntryShape =
    "expected {\"constant\": \"accel.b_x\", \"lower\": -300, \"upper\": 300, \"unit\": "
    "\"LSB\"} (one limit may be absent)";

// tolerances[i]: its constant (not in *names yet), unit and limits.
Result<Tolerance> ParseTolerance(const json& e, size_t i, const std::string& text,
                                 const std::string& path, std::set<std::string>* names) {
  const auto at = [&](const std::vector<JsonPathStep>& where, const std::string& message) {
    return SpecErrorAt(text, path, where, message);
  };
  static const std::set<std::string> kEntry = {"constant", "lower", "upper", "unit"};
  // A pair, not a structured binding: C++17 lambdas cannot capture those (clang refuses).
  const std::pair<int64_t, int64_t> entry = TopLevelArrayElementLineColumn(text, "tolerances", i);
  auto fail = [&](const std::string& what) {
    return SpecError(path, entry.first, entry.second, fmt::format("tolerances[{}]: {}", i, what));
  };
  auto fail_at = [&](const std::string& key, const std::string& what) {
    return at({"tolerances", i, key}, fmt::format("tolerances[{}]: {}", i, what));
  };
  if (!e.is_object()) {
    return at({"tolerances", i}, fmt::format("tolerances[{}] is {}: {}", i, Shown(e), kEntryShape));
  }
  for (auto it = e.begin(); it != e.end(); ++it) {
    if (!kEntry.count(it.key())) {
      return fail_at(it.key(), fmt::format("unknown key '{}'; an entry has constant, lower, "
                                           "upper, unit{}: {}",
                                           it.key(), NearestName(it.key(), kEntry), kEntryShape));
    }
  }
  Tolerance t;
  t.line = entry.first;
  t.column = entry.second;
  if (!e.contains("constant")) {
    return fail(fmt::format("missing 'constant' (a name such as \"accel.b_x\"): {}", kEntryShape));
  }
  if (!e["constant"].is_string()) {
    return fail_at("constant", fmt::format("'constant' is {}: expected a name such as "
                                           "\"accel.b_x\" (docs/conformity.md)",
                                           Shown(e["constant"])));
  }
  t.constant = e["constant"].get<std::string>();
  if (!names->insert(t.constant).second) {
    return fail_at("constant", fmt::format("'{}' is given twice; expected one entry per "
                                           "constant, with both limits",
                                           t.constant));
  }
  if (!e.contains("unit")) {
    return fail(fmt::format("'{}': missing 'unit' (e.g. \"LSB\", \"g_n/LSB\", \"rad\"): {}",
                            t.constant, kEntryShape));
  }
  if (!e["unit"].is_string()) {
    return fail_at("unit", fmt::format("'{}': 'unit' is {}: expected a unit such as \"LSB\", "
                                       "\"g_n/LSB\" or \"rad\"",
                                       t.constant, Shown(e["unit"])));
  }
  t.unit = e["unit"].get<std::string>();
  for (const char* key : {"lower", "upper"}) {
    if (!e.contains(key) || e[key].is_null()) continue;
    if (!e[key].is_number() || !std::isfinite(e[key].get<double>())) {
      return fail_at(key, fmt::format("'{}': '{}' is {}: expected a finite number (or null "
                                      "for no limit), e.g. \"{}\": {}",
                                      t.constant, key, Shown(e[key]), key,
                                      std::string(key) == "lower" ? "-300" : "300"));
    }
    (std::string(key) == "lower" ? t.lower : t.upper) = e[key].get<double>();
  }
  if (!t.lower && !t.upper) {
    return fail(fmt::format("'{}' has neither 'lower' nor 'upper': {}", t.constant, kEntryShape));
  }
  if (t.lower && t.upper && *t.lower > *t.upper) {
    return fail(fmt::format("'{}': lower {} > upper {}; expected lower <= upper", t.constant,
                            *t.lower, *t.upper));
  }
  return t;
}

}  // namespace

Result<ConformitySpec> ParseConformitySpec(const std::string& text, const std::string& path) {
  Result<json> parsed = ParseJsonText(text, path);
  if (!parsed.ok()) return parsed.error();
  const json& j = parsed.value();
  // Every error at the value it is about (or the object that lacks it), with what was expected
  // and the shape of a spec (docs/conformity.md).
  const auto at = [&](const std::vector<JsonPathStep>& where, const std::string& message) {
    return SpecErrorAt(text, path, where, message);
  };
  const auto shape = [](const std::string& message) { return message + "; " + kSpecShape; };
  if (!j.is_object()) return at({}, shape("a spec is a JSON object"));
  ConformitySpec spec;
  spec.path = path;
  if (Status s = ParseRule(j, text, path, &spec); !s.ok()) return s.error();
  if (!j.contains("tolerances")) return at({}, shape("missing 'tolerances'"));
  if (!j["tolerances"].is_array() || j["tolerances"].empty()) {
    return at({"tolerances"},
              shape(fmt::format("'tolerances' is {}: expected a non-empty array of entries",
                                Shown(j["tolerances"]))));
  }
  std::set<std::string> names;
  for (size_t i = 0; i < j["tolerances"].size(); ++i) {
    Result<Tolerance> t = ParseTolerance(j["tolerances"][i], i, text, path, &names);
    if (!t.ok()) return t.error();
    spec.tolerances.push_back(std::move(t).value());
  }
  std::string why;
  if (!spec.IsValid(&why)) return at({}, why);  // Checked above, field by field.
  return spec;
}

Result<ConformitySpec> LoadConformitySpec(const std::string& path) {
  Result<std::string> text = ReadFile(path);
  if (!text.ok()) return text.error();
  return ParseConformitySpec(text.value(), path);
}

double ConformanceProbability(double value, double u, std::optional<double> lower,
                              std::optional<double> upper) {
  METRO_CHECK(u >= 0.0);
  if (u == 0.0) {
    return (!lower || value >= *lower) && (!upper || value <= *upper) ? 1.0 : 0.0;
  }
  // JCGM 106:2012 7.3: p_c = Phi((T_U - y)/u) - Phi((T_L - y)/u), written with the upper tail
  // where it is small so that a p_c near 1 keeps its digits.
  const boost::math::normal n;
  const double below = lower ? boost::math::cdf(n, (*lower - value) / u) : 0.0;
  const double above =
      upper ? boost::math::cdf(boost::math::complement(n, (*upper - value) / u)) : 0.0;
  return std::max(0.0, 1.0 - below - above);
}

ConformityEntry DecideConformity(const std::string& constant, double value, double u,
                                 std::optional<double> lower, std::optional<double> upper,
                                 DecisionRule rule, double coverage_factor,
                                 double max_consumer_risk) {
  ConformityEntry e;
  e.constant = constant;
  e.value = value;
  e.u = u;
  e.lower = lower;
  e.upper = upper;
  e.p_conformance = ConformanceProbability(value, u, lower, upper);
  const bool inside = (!lower || value >= *lower) && (!upper || value <= *upper);
  switch (rule) {
    case DecisionRule::kSimple:
      // JCGM 106:2012 8.2: acceptance limits = tolerance limits.
      e.acceptance_lower = lower;
      e.acceptance_upper = upper;
      e.decision = inside ? ConformityDecision::kPass : ConformityDecision::kFail;
      break;
    case DecisionRule::kGuarded: {
      // JCGM 106:2012 8.3.2, guarded acceptance: A_L = T_L + w, A_U = T_U - w, w = U = k u
      // (ILAC G8:09/2019 4.2.2). Between an acceptance and a tolerance limit the statement is
      // inconclusive (ILAC G8 4.2.3, non-binary); outside the tolerance interval, fail.
      const double w = coverage_factor * u;
      if (lower) e.acceptance_lower = *lower + w;
      if (upper) e.acceptance_upper = *upper - w;
      const bool accepted = (!e.acceptance_lower || value >= *e.acceptance_lower) &&
                            (!e.acceptance_upper || value <= *e.acceptance_upper) &&
                            (!e.acceptance_lower || !e.acceptance_upper ||
                             *e.acceptance_lower <= *e.acceptance_upper);
      e.decision = accepted ? ConformityDecision::kPass
                   : inside ? ConformityDecision::kInconclusive
                            : ConformityDecision::kFail;
      break;
    }
    case DecisionRule::kRisk:
      // JCGM 106:2012 9.3: the specific consumer's risk of accepting this item is 1 - p_c.
      if (1.0 - e.p_conformance <= max_consumer_risk) {
        e.decision = ConformityDecision::kPass;
      } else if (e.p_conformance <= max_consumer_risk) {
        e.decision = ConformityDecision::kFail;
      } else {
        e.decision = ConformityDecision::kInconclusive;
      }
      break;
  }
  return e;
}

bool ConformityStatement::AnyFail() const {
  for (const ConformityEntry& e : entries) {
    if (e.decision == ConformityDecision::kFail) return true;
  }
  return false;
}

std::string ConformityStatement::DescribeRule() const {
  switch (rule) {
    case DecisionRule::kSimple:
      return "simple acceptance: the acceptance limits are the tolerance limits (binary "
             "statement, shared risk; JCGM 106:2012 8.2, ILAC G8:09/2019 4.2.1)";
    case DecisionRule::kGuarded:
      return fmt::format(
          "guarded acceptance with guard band w = U = {} u: pass inside the tolerance interval "
          "narrowed by w, fail outside the tolerance interval, inconclusive between (JCGM "
          "106:2012 8.3.2, ILAC G8:09/2019 4.2.2)",
          coverage_factor);
    case DecisionRule::kRisk:
      return fmt::format(
          "specific risk: pass when the specific consumer's risk 1 - p_c is at most {}, fail "
          "when p_c is at most {}, inconclusive otherwise (JCGM 106:2012 9.3)",
          max_consumer_risk, max_consumer_risk);
  }
  return "";
}

Result<ConformityStatement> EvaluateConformity(const Calibration& calibration,
                                               const ConformitySpec& spec) {
  std::string why;
  if (!spec.IsValid(&why)) return MakeError(spec.path, 0, why);
  ConformityStatement out;
  out.rule = spec.rule;
  out.coverage_factor = spec.coverage_factor;
  out.max_consumer_risk = spec.max_consumer_risk;
  for (const TagCalibration& tag : calibration.tags) {
    const std::vector<NamedConstant> constants = NamedConstants(tag);
    for (const Tolerance& t : spec.tolerances) {
      auto fail = [&](const std::string& what) {
        return SpecError(spec.path, t.line, t.column, what);
      };
      const NamedConstant* c = nullptr;
      for (const NamedConstant& n : constants) {
        if (n.name == t.constant) c = &n;
      }
      if (c == nullptr) {
        std::string have;
        std::set<std::string> known;
        for (const NamedConstant& n : constants) {
          have += (have.empty() ? "" : " ") + n.name;
          known.insert(n.name);
        }
        return fail(fmt::format("sensor {} has no constant '{}'{}; it has: {}", tag.sensor,
                                t.constant, NearestName(t.constant, known), have));
      }
      Result<PhysicalUnit> from = PhysicalUnit::Parse(c->unit);
      Result<PhysicalUnit> to = PhysicalUnit::Parse(t.unit);
      if (!to.ok()) {
        return fail(
            fmt::format("'{}': unit: {}; expected the constant's unit \"{}\" or one "
                        "convertible to it",
                        t.constant, to.error().message, c->unit));
      }
      if (!from.ok()) return from.error();
      const std::optional<UnitConversion> conv = from.value().ConversionTo(to.value());
      if (!conv || IsLsbUnit(c->unit) != IsLsbUnit(t.unit)) {
        return fail(
            fmt::format("'{}': unit '{}' does not match the constant's unit '{}'; "
                        "expected \"unit\": \"{}\" or a unit convertible to it",
                        t.constant, t.unit, c->unit, c->unit));
      }
      ConformityEntry e = DecideConformity(
          t.constant, conv->ConvertValue(c->value), std::abs(conv->ConvertDifference(c->u)),
          t.lower, t.upper, spec.rule, spec.coverage_factor, spec.max_consumer_risk);
      e.sensor = tag.sensor;
      e.unit = t.unit;
      out.entries.push_back(std::move(e));
    }
  }
  return out;
}

json ConformityEntriesToJson(const ConformityStatement& statement) {
  json list = json::array();
  for (const ConformityEntry& e : statement.entries) {
    json j;
    j["sensor"] = e.sensor;
    j["constant"] = e.constant;
    j["value"] = e.value;
    j["u"] = e.u;
    j["lower"] = e.lower ? json(*e.lower) : json(nullptr);
    j["upper"] = e.upper ? json(*e.upper) : json(nullptr);
    j["unit"] = e.unit;
    j["acceptance_lower"] = e.acceptance_lower ? json(*e.acceptance_lower) : json(nullptr);
    j["acceptance_upper"] = e.acceptance_upper ? json(*e.acceptance_upper) : json(nullptr);
    j["p_conformance"] = e.p_conformance;
    j["decision"] = ConformityDecisionName(e.decision);
    list.push_back(std::move(j));
  }
  return list;
}

json ConformityRuleToJson(const ConformityStatement& statement) {
  json j;
  j["decision_rule"] = DecisionRuleName(statement.rule);
  j["coverage_factor"] = statement.coverage_factor;
  if (statement.rule == DecisionRule::kRisk) j["max_consumer_risk"] = statement.max_consumer_risk;
  j["statement"] = statement.DescribeRule();
  return j;
}

ConformityStatement ConformityFromJsonValue(const JsonCursor& entries, const JsonCursor& rule) {
  ConformityStatement s;
  const std::string rule_name = rule["decision_rule"].String();
  if (!rule.ok()) return s;
  const std::optional<DecisionRule> parsed = ParseDecisionRule(rule_name);
  if (!parsed) {
    rule["decision_rule"].Fail("simple, guarded or risk");
    return s;
  }
  s.rule = *parsed;
  if (const std::optional<double> k = rule["coverage_factor"].OptionalNumber()) {
    s.coverage_factor = *k;
  }
  if (const std::optional<double> risk = rule["max_consumer_risk"].OptionalNumber()) {
    s.max_consumer_risk = *risk;
  }
  if (!entries.IsArray()) {
    entries.Fail("an array of conformity entries");
    return s;
  }
  for (size_t i = 0; i < entries.Size() && entries.ok(); ++i) {
    const JsonCursor j = entries[i];
    if (!j.IsObject()) {
      j.Fail("an object (a conformity entry)");
      break;
    }
    ConformityEntry e;
    e.sensor = static_cast<int>(j["sensor"].Integer());
    e.constant = j["constant"].String();
    e.unit = j["unit"].String();
    e.value = j["value"].Number();
    e.u = j["u"].Number();
    e.p_conformance = j["p_conformance"].Number();
    e.lower = j["lower"].OptionalNumber();
    e.upper = j["upper"].OptionalNumber();
    e.acceptance_lower = j["acceptance_lower"].OptionalNumber();
    e.acceptance_upper = j["acceptance_upper"].OptionalNumber();
    const std::string decision = j["decision"].String();
    if (!j.ok()) break;
    const std::optional<ConformityDecision> d = ParseConformityDecision(decision);
    if (!d) {
      j["decision"].Fail("pass, fail or inconclusive");
      break;
    }
    e.decision = *d;
    s.entries.push_back(std::move(e));
  }
  return s;
}

}  // namespace metro
