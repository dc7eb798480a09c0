// Statements of conformity of calibration constants with tolerance limits (JCGM 106:2012
// "The role of measurement uncertainty in conformity assessment"; ILAC G8:09/2019; ISO/IEC
// 17025:2017 7.8.6). Specified in docs/conformity.md.
//
// A spec (SPEC.json) gives tolerance limits per named constant (named_constants.hpp):
//
//   {"tolerances": [{"constant": "accel.b_x", "lower": -300, "upper": 300, "unit": "LSB"}],
//    "decision_rule": "simple" | "guarded" | "risk",
//    "coverage_factor": 2,          (guarded: w = U = k u; default 2)
//    "max_consumer_risk": 0.023}    (risk: required)
//
// Either limit may be omitted (a one-sided tolerance interval, JCGM 106 7.3).
//
// The measurand's state of knowledge is the normal PDF N(y, u^2) of the constant's value and
// standard uncertainty (JCGM 106 7.3: the GUM's "best estimate and standard uncertainty",
// maximum-entropy PDF). The conformance probability (JCGM 106 7.3, normal PDFs):
//
//   p_c = Phi((T_U - y)/u) - Phi((T_L - y)/u)
//
// (one-sided: one term; u = 0: 1 inside [T_L, T_U], else 0).
//
// Decision rules (JCGM 106 clause 8; ILAC G8:09/2019 4.2):
//   simple  : acceptance interval = tolerance interval (JCGM 106 8.2 "simple acceptance",
//             shared risk; ILAC G8 4.2.1 binary statement): pass if T_L <= y <= T_U, else fail.
//   guarded : guard band w = U = k u (JCGM 106 8.3.2, 8.4; ILAC G8 4.2.2 w = U): pass if
//             T_L + w <= y <= T_U - w; fail if y outside [T_L, T_U]; otherwise inconclusive
//             (ILAC G8 4.2.3 non-binary statement). With k = 2 and a normal PDF the specific
//             consumer's risk of a pass is at most 2.3 % (one-sided, JCGM 106 8.3.2 NOTE).
//   risk    : specific consumer's risk R_c* = 1 - p_c (JCGM 106 9.3, specific risks): pass if
//             1 - p_c <= max_consumer_risk; fail if p_c <= max_consumer_risk (non-conformity
//             as certain as conformity must be for a pass); otherwise inconclusive.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "metro/core/status.hpp"

namespace metro {

struct Calibration;  // calibrate.hpp, which holds a ConformityStatement.

enum class DecisionRule { kSimple, kGuarded, kRisk };
const char* DecisionRuleName(DecisionRule rule);  // "simple", "guarded", "risk"
std::optional<DecisionRule> ParseDecisionRule(const std::string& name);

enum class ConformityDecision { kPass, kFail, kInconclusive };
const char* ConformityDecisionName(ConformityDecision decision);  // "pass", "fail", "inconclusive"
std::optional<ConformityDecision> ParseConformityDecision(const std::string& name);

struct Tolerance {
  std::string constant;         // "accel.b_x"
  std::optional<double> lower;  // T_L, in `unit`
  std::optional<double> upper;  // T_U, in `unit`
  std::string unit;             // UDUNITS-2 text, convertible to the constant's unit
  int64_t line = 0;             // Where the entry is in the spec file (1-based; 0 unknown).
  int64_t column = 0;
};

struct ConformitySpec {
  std::string path;  // For messages.
  std::vector<Tolerance> tolerances;
  DecisionRule rule = DecisionRule::kSimple;
  double coverage_factor = 2.0;    // k of the guard band w = k u (guarded).
  double max_consumer_risk = 0.0;  // Largest specific consumer's risk of a pass (risk).

  bool IsValid(std::string* why) const;
};

// Parses SPEC.json. Errors `path:line:column: ...` at the offending entry: not JSON, an unknown
// key (naming the supported ones), a missing constant or unit, no limit, lower > upper, an
// unknown decision rule, a risk rule without max_consumer_risk in (0, 0.5), a coverage factor
// <= 0. Constant names and units are checked against a calibration by EvaluateConformity.
Result<ConformitySpec> ParseConformitySpec(const std::string& text, const std::string& path);
Result<ConformitySpec> LoadConformitySpec(const std::string& path);

// p_c of N(value, u^2) in [lower, upper] (JCGM 106 7.3); an absent limit is infinite.
// u must be >= 0; u = 0 gives 1 or 0.
double ConformanceProbability(double value, double u, std::optional<double> lower,
                              std::optional<double> upper);

struct ConformityEntry {
  int sensor = 0;  // Tag number.
  std::string constant;
  double value = 0.0;  // In `unit` (the tolerance's unit).
  double u = 0.0;
  std::optional<double> lower;
  std::optional<double> upper;
  std::string unit;
  double p_conformance = 0.0;
  // The acceptance interval the rule compared the value with (simple: the tolerance limits;
  // guarded: narrowed by w; risk: absent, the rule compares p_c).
  std::optional<double> acceptance_lower;
  std::optional<double> acceptance_upper;
  ConformityDecision decision = ConformityDecision::kFail;
};

struct ConformityStatement {
  DecisionRule rule = DecisionRule::kSimple;
  double coverage_factor = 2.0;
  double max_consumer_risk = 0.0;
  std::vector<ConformityEntry> entries;  // Per tag, in spec order.

  bool AnyFail() const;
  // "guarded acceptance, guard band w = U = 2 u (JCGM 106:2012 8.3.2; ILAC G8:09/2019 4.2.2)"
  std::string DescribeRule() const;
};

// Decides every tolerance for every tag of `calibration`. Errors (`spec.path:line:column`): a
// constant the calibration does not have (naming those it has), a unit not convertible to the
// constant's (naming it), a raw-count (LSB) constant with a tolerance not in LSB or vice versa.
Result<ConformityStatement> EvaluateConformity(const Calibration& calibration,
                                               const ConformitySpec& spec);

// The decision for one value (exposed for tests and the registry).
ConformityEntry DecideConformity(const std::string& constant, double value, double u,
                                 std::optional<double> lower, std::optional<double> upper,
                                 DecisionRule rule, double coverage_factor,
                                 double max_consumer_risk);

}  // namespace metro
