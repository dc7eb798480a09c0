// Conformity of calibration constants with tolerance limits (JCGM 106:2012, docs/conformity.md).
#include "metro/calibration/conformity.hpp"

#include <catch2/catch.hpp>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "metro/calibration/calibration_io.hpp"
#include "metro/calibration/named_constants.hpp"
#include "support/temp_file.hpp"
#include "support/text_position.hpp"

namespace metro {
namespace {

const std::string kGolden =
    std::string(METRO_SOURCE_DIR) + "/datasets/golden/calibration_sensor2.json";

// The standard normal CDF written independently of the code under test (Boost.Math there).
double Phi(double z) { return 0.5 * std::erfc(-z / std::sqrt(2.0)); }

TEST_CASE("Conformity: one-sided p_c is Phi of z at the standard normal quantiles",
          "[calibration][conformity]") {
  // JCGM 106:2012 7.3 (Table 1 gives z = (T_U - y)/u for one-sided intervals and normal
  // PDFs): p_c = Phi(z). The standard normal quantiles to two decimals: p_c = 0.80, 0.90, 0.95,
  // 0.99, 0.999 at z = 0.84, 1.28, 1.64, 2.33, 3.09 (so p_c within Phi'(z) * 0.005).
  const double pc[] = {0.80, 0.90, 0.95, 0.99, 0.999};
  const double z[] = {0.84, 1.28, 1.64, 2.33, 3.09};
  for (int i = 0; i < 5; ++i) {
    const double y = 10.0;
    const double u = 0.5;
    const double tu = y + z[i] * u;
    const double p = ConformanceProbability(y, u, std::nullopt, tu);
    // z rounded to 0.005: p_c within Phi'(z) * 0.005.
    CHECK(std::abs(p - pc[i]) < 0.005 * std::exp(-z[i] * z[i] / 2) / std::sqrt(2 * M_PI) + 1e-12);
    CHECK(p == Approx(Phi(z[i])).epsilon(1e-12));
    // A lower limit at the mirror image gives the same p_c.
    CHECK(ConformanceProbability(y, u, y - z[i] * u, std::nullopt) == Approx(p).epsilon(1e-12));
  }
}

TEST_CASE("Conformity: two-sided p_c equals Phi(z_U) + Phi(z_L) - 1 and a Monte Carlo count",
          "[calibration][conformity]") {
  // JCGM 106:2012 7.3 (two-sided tolerance interval): p_c = Phi(z_U) + Phi(z_L) - 1 with
  // z_U = (T_U - y)/u and z_L = (y - T_L)/u.
  const double y = 0.3;
  const double u = 0.2;
  const double tl = -0.1;
  const double tu = 0.5;
  const double expected = Phi((tu - y) / u) + Phi((y - tl) / u) - 1.0;
  CHECK(ConformanceProbability(y, u, tl, tu) == Approx(expected).epsilon(1e-12));
  // Symmetric interval +-1.959964 u about y: p_c = 0.95.
  CHECK(ConformanceProbability(0.0, 1.0, -1.959964, 1.959964) == Approx(0.95).margin(1e-6));
  // The probability by counting draws from N(y, u^2): within 5 binomial standard errors.
  std::mt19937_64 rng(106);
  std::normal_distribution<double> d(y, u);
  const int n = 400000;
  int in = 0;
  for (int i = 0; i < n; ++i) {
    const double x = d(rng);
    if (x >= tl && x <= tu) ++in;
  }
  const double frac = static_cast<double>(in) / n;
  CHECK(std::abs(frac - ConformanceProbability(y, u, tl, tu)) <
        5.0 * std::sqrt(expected * (1 - expected) / n));
  // u = 0: certainty.
  CHECK(ConformanceProbability(0.4, 0.0, tl, tu) == 1.0);
  CHECK(ConformanceProbability(0.6, 0.0, tl, tu) == 0.0);
}

TEST_CASE("Conformity: guarded acceptance w = 2u bounds the specific consumer's risk at 2.3 %",
          "[calibration][conformity]") {
  // JCGM 106:2012 8.3.2: with w = U = 2u an item accepted at the acceptance limit A_U = T_U - w
  // has p_c = Phi(2) = 0.9772 (one-sided), a specific consumer's risk of 2.28 %.
  const double u = 1.0;
  ConformityEntry at =
      DecideConformity("c", 8.0, u, std::nullopt, 10.0, DecisionRule::kGuarded, 2.0, 0.0);
  CHECK(at.decision == ConformityDecision::kPass);
  CHECK(*at.acceptance_upper == 8.0);
  CHECK(at.p_conformance == Approx(0.97725).margin(5e-6));
  CHECK(1.0 - at.p_conformance < 0.023);
  // Inside the tolerance but inside the guard band: inconclusive; beyond the limit: fail.
  CHECK(DecideConformity("c", 8.5, u, std::nullopt, 10.0, DecisionRule::kGuarded, 2.0, 0.0)
            .decision == ConformityDecision::kInconclusive);
  CHECK(DecideConformity("c", 10.01, u, std::nullopt, 10.0, DecisionRule::kGuarded, 2.0, 0.0)
            .decision == ConformityDecision::kFail);
  // A tolerance interval narrower than 2w accepts nothing.
  CHECK(DecideConformity("c", 0.0, u, -3.0, 3.0, DecisionRule::kGuarded, 2.0, 0.0).decision ==
        ConformityDecision::kPass);
  CHECK(DecideConformity("c", 0.0, u, -1.5, 1.5, DecisionRule::kGuarded, 2.0, 0.0).decision ==
        ConformityDecision::kInconclusive);
}

TEST_CASE("Conformity: simple acceptance and the specific-risk rule", "[calibration][conformity]") {
  // Simple acceptance (JCGM 106:2012 8.2): the value alone decides; at the limit p_c = 0.5.
  ConformityEntry s =
      DecideConformity("c", 10.0, 1.0, std::nullopt, 10.0, DecisionRule::kSimple, 2.0, 0.0);
  CHECK(s.decision == ConformityDecision::kPass);
  CHECK(s.p_conformance == Approx(0.5).epsilon(1e-12));
  CHECK(DecideConformity("c", 10.001, 1.0, std::nullopt, 10.0, DecisionRule::kSimple, 2.0, 0.0)
            .decision == ConformityDecision::kFail);
  // Risk rule with R_max = 0.05: pass needs p_c >= 0.95, i.e. y <= T_U - 1.6449 u.
  const double r = 0.05;
  CHECK(DecideConformity("c", 10.0 - 1.65, 1.0, std::nullopt, 10.0, DecisionRule::kRisk, 2.0, r)
            .decision == ConformityDecision::kPass);
  CHECK(DecideConformity("c", 10.0 - 1.64, 1.0, std::nullopt, 10.0, DecisionRule::kRisk, 2.0, r)
            .decision == ConformityDecision::kInconclusive);
  CHECK(DecideConformity("c", 10.0 + 1.64, 1.0, std::nullopt, 10.0, DecisionRule::kRisk, 2.0, r)
            .decision == ConformityDecision::kInconclusive);
  CHECK(DecideConformity("c", 10.0 + 1.65, 1.0, std::nullopt, 10.0, DecisionRule::kRisk, 2.0, r)
            .decision == ConformityDecision::kFail);
}

TEST_CASE("Conformity: a spec evaluated on the golden calibration, with unit conversion",
          "[calibration][conformity]") {
  Result<Calibration> cal = LoadCalibration(kGolden);
  REQUIRE(cal.ok());
  const TagCalibration& tag = cal.value().tags[0];
  // b_x = 68.619 LSB, u = 0.9769 LSB; a_yz = -0.011981 rad = -0.6865 deg, u = 0.0075 deg.
  testing::TempFile spec(R"({
  "decision_rule": "guarded",
  "tolerances": [
    {"constant": "accel.b_x", "lower": -70, "upper": 70, "unit": "LSB"},
    {"constant": "accel.a_yz", "lower": -1, "upper": 1, "unit": "deg"},
    {"constant": "accel.k_x", "upper": 0.0618, "unit": "mg_n/LSB"}
  ]
})",
                         ".json");
  Result<ConformitySpec> s = LoadConformitySpec(spec.path());
  REQUIRE(s.ok());
  Result<ConformityStatement> st = EvaluateConformity(cal.value(), s.value());
  REQUIRE(st.ok());
  REQUIRE(st.value().entries.size() == 3);
  const ConformityEntry& b = st.value().entries[0];
  CHECK(b.sensor == tag.sensor);
  CHECK(b.value == tag.accel->model.bias[0]);
  // 70 - 68.619 = 1.381 LSB < w = 2 * 0.977: inside the guard band.
  CHECK(b.decision == ConformityDecision::kInconclusive);
  CHECK(b.p_conformance == Approx(Phi((70 - b.value) / b.u) - Phi((-70 - b.value) / b.u)));
  const ConformityEntry& a = st.value().entries[1];
  CHECK(a.value == Approx(tag.accel->model.misalignment[0] * 180.0 / M_PI).epsilon(1e-12));
  CHECK(a.u == Approx(tag.accel->misalignment_u[0] * 180.0 / M_PI).epsilon(1e-12));
  CHECK(a.decision == ConformityDecision::kPass);
  const ConformityEntry& k = st.value().entries[2];
  // k_x = 6.1765e-5 g/LSB = 0.061765 mg/LSB, u = 5.6e-6 mg/LSB: 0.0618 is 6 u above: pass.
  CHECK(k.value == Approx(tag.accel->model.scale[0] * 1000.0).epsilon(1e-12));
  CHECK(k.decision == ConformityDecision::kPass);
  CHECK_FALSE(st.value().AnyFail());

  // Written into calibration.json and read back.
  Calibration with = cal.value();
  with.conformity = st.value();
  Result<Calibration> back = CalibrationFromJson(ToJson(with), "x.json");
  REQUIRE(back.ok());
  CHECK(ToJson(back.value()) == ToJson(with));  // The same bytes written again.
  REQUIRE(back.value().conformity.has_value());
  CHECK(back.value().conformity->rule == DecisionRule::kGuarded);
  REQUIRE(back.value().conformity->entries.size() == 3);
  CHECK(back.value().conformity->entries[0].p_conformance == b.p_conformance);
  CHECK(back.value().conformity->entries[2].upper == 0.0618);
  CHECK_FALSE(back.value().conformity->entries[2].lower.has_value());
  // A wrong type in an entry is refused at its position. Keys are sorted, so the text opens
  // `{`, `  "conformity": [`, `    {`, then the entry's keys acceptance_lower,
  // acceptance_upper and, on line 6, `      "constant": ...`: the value at column 19.
  std::string text = ToJson(with);
  const size_t at = text.find("\"constant\": \"");
  REQUIRE(at != std::string::npos);
  text.replace(at, text.find(',', at) - at, "\"constant\": 7");
  Result<Calibration> bad = CalibrationFromJson(text, "x.json");
  REQUIRE_FALSE(bad.ok());
  CHECK(bad.error().ToString() ==
        "x.json:6:19: conformity[0].constant: expected a string, found the number 7");
}

TEST_CASE("Conformity: bad specs are refused at file:line:column", "[calibration][conformity]") {
  Result<Calibration> cal = LoadCalibration(kGolden);
  REQUIRE(cal.ok());
  auto evaluate = [&](const std::string& text) -> std::string {
    testing::TempFile f(text, ".json");
    Result<ConformitySpec> s = LoadConformitySpec(f.path());
    if (!s.ok()) return s.error().ToString();
    Result<ConformityStatement> st = EvaluateConformity(cal.value(), s.value());
    return st.ok() ? std::string() : st.error().ToString();
  };
  // lower > upper, on line 3 column 5.
  std::string e = evaluate(
      "{\"decision_rule\": \"simple\",\n \"tolerances\": [\n    {\"constant\": \"accel.b_x\", "
      "\"lower\": 5, \"upper\": 1, \"unit\": \"LSB\"}]}");
  CHECK(e.find(":3:5: tolerances[0]: 'accel.b_x': lower 5 > upper 1") != std::string::npos);
  // Unknown constant: the names it has.
  e = evaluate(
      "{\"decision_rule\": \"simple\", \"tolerances\": [{\"constant\": \"accel.b_w\", \"upper\": "
      "1, \"unit\": \"LSB\"}]}");
  CHECK(e.find(":1:44: sensor 2 has no constant 'accel.b_w' (did you mean 'accel.b_x'?); it "
               "has: accel.b_x") != std::string::npos);
  // Unit of another dimension, and a dimensionless unit that is not a count.
  e = evaluate(
      "{\"decision_rule\": \"simple\", \"tolerances\": [{\"constant\": \"accel.b_x\", \"upper\": "
      "1, \"unit\": \"m/s^2\"}]}");
  CHECK(e.find("'accel.b_x': unit 'm/s^2' does not match the constant's unit 'LSB'") !=
        std::string::npos);
  e = evaluate(
      "{\"decision_rule\": \"simple\", \"tolerances\": [{\"constant\": \"accel.b_x\", \"upper\": "
      "1, \"unit\": \"rad\"}]}");
  CHECK(e.find("unit 'rad' does not match the constant's unit 'LSB'") != std::string::npos);
  // Rule errors.
  e = evaluate(
      "{\"decision_rule\": \"strict\", \"tolerances\": [{\"constant\": \"accel.b_x\", \"upper\": "
      "1, \"unit\": \"LSB\"}]}");
  CHECK(e.find("decision_rule 'strict' is not simple, guarded or risk") != std::string::npos);
  e = evaluate(
      "{\"decision_rule\": \"risk\", \"tolerances\": [{\"constant\": \"accel.b_x\", \"upper\": "
      "1, \"unit\": \"LSB\"}]}");
  CHECK(e.find("the risk rule needs max_consumer_risk in (0, 0.5)") != std::string::npos);
  e = evaluate(
      "{\"decision_rule\": \"simple\", \"tolerances\": [{\"constant\": \"accel.b_x\", "
      "\"unit\": \"LSB\"}]}");
  CHECK(e.find("'accel.b_x' has neither 'lower' nor 'upper'") != std::string::npos);
  e = evaluate("{\"decision_rule\": \"simple\", \"tolerance\": []}");
  CHECK(e.find("unknown key 'tolerance'") != std::string::npos);
  e = evaluate("{\"decision_rule\": \"simple\", \"tolerances\": [}");
  CHECK(e.find("invalid JSON") != std::string::npos);
}

TEST_CASE("Conformity: every class of bad spec at file:line:column with the expected shape",
          "[calibration][conformity][issue37]") {
  // issue #37: the rule, coverage factor, risk and tolerances errors had no line and column.
  // `at` is the text the error points at (its first occurrence in the spec), located here
  // independently of the reader; `message` follows "path:line:column: ".
  Result<Calibration> cal = LoadCalibration(kGolden);
  REQUIRE(cal.ok());
  const std::string shape =
      R"(expected {"tolerances": [{"constant": "accel.b_x", "lower": -300, "upper": 300, )"
      R"("unit": "LSB"}], "decision_rule": "simple"|"guarded"|"risk"[, "coverage_factor": 2][, )"
      R"("max_consumer_risk": 0.023]})";
  const std::string entry =
      R"(expected {"constant": "accel.b_x", "lower": -300, "upper": 300, "unit": "LSB"} (one )"
      R"(limit may be absent))";
  const std::string ok = R"({"constant": "accel.b_x", "upper": 1, "unit": "LSB"})";
  struct Case {
    std::string spec;
    std::string at;
    std::string message;
  };
  const std::vector<Case> cases = {
      {"[1]", "[1]", "a spec is a JSON object; " + shape},
      {R"({"decision_rule": "simple", "tolerance": []})", "[]",
       "unknown key 'tolerance'; expected tolerances, decision_rule, coverage_factor, "
       "max_consumer_risk or description (did you mean 'tolerances'?)"},
      {R"({"tolerances": [)" + ok + "]}", "{", "missing 'decision_rule'; " + shape},
      {R"({"decision_rule": "strict", "tolerances": [)" + ok + "]}", R"("strict")",
       R"(decision_rule 'strict' is not simple, guarded or risk; expected "decision_rule": )"
       R"("simple" (or "guarded" with "coverage_factor": 2, or "risk" with )"
       R"("max_consumer_risk": 0.023))"},
      {R"({"decision_rule": 1, "tolerances": [)" + ok + "]}", "1,",
       R"(decision_rule 1 is not simple, guarded or risk; expected "decision_rule": )"
       R"("simple" (or "guarded" with "coverage_factor": 2, or "risk" with )"
       R"("max_consumer_risk": 0.023))"},
      {R"({"decision_rule": "guarded", "coverage_factor": -1, "tolerances": [)" + ok + "]}", "-1",
       R"(coverage_factor -1: expected a number > 0, e.g. "coverage_factor": 2 (w = k u, JCGM )"
       R"(106 8.3.2))"},
      {R"({"decision_rule": "risk", "max_consumer_risk": "low", "tolerances": [)" + ok + "]}",
       R"("low")",
       R"(max_consumer_risk 'low': expected a number in (0, 0.5), e.g. "max_consumer_risk": )"
       R"(0.023)"},
      {R"({"decision_rule": "risk", "tolerances": [)" + ok + "]}", R"("risk")",
       R"(the risk rule needs max_consumer_risk in (0, 0.5); expected "decision_rule": "risk", )"
       R"("max_consumer_risk": 0.023)"},
      {R"({"decision_rule": "risk", "max_consumer_risk": 0.7, "tolerances": [)" + ok + "]}", "0.7",
       R"(the risk rule needs max_consumer_risk in (0, 0.5); expected "decision_rule": "risk", )"
       R"("max_consumer_risk": 0.023)"},
      {R"({"decision_rule": "simple"})", "{", "missing 'tolerances'; " + shape},
      {R"({"decision_rule": "simple", "tolerances": {}})", "{}",
       "'tolerances' is {}: expected a non-empty array of entries; " + shape},
      {R"({"decision_rule": "simple", "tolerances": [3]})", "3]", "tolerances[0] is 3: " + entry},
      {R"({"decision_rule": "simple", "tolerances": [{"constant": "accel.b_x", "uper": 1}]})", "1}",
       "tolerances[0]: unknown key 'uper'; an entry has constant, lower, upper, unit (did "
       "you mean 'upper'?): " +
           entry},
      {R"({"decision_rule": "simple", "tolerances": [{"upper": 1, "unit": "LSB"}]})", R"({"upper")",
       R"(tolerances[0]: missing 'constant' (a name such as "accel.b_x"): )" + entry},
      {R"({"decision_rule": "simple", "tolerances": [{"constant": 7, "upper": 1}]})", "7,",
       R"(tolerances[0]: 'constant' is 7: expected a name such as "accel.b_x" )"
       R"((docs/conformity.md))"},
      {R"({"decision_rule": "simple", "tolerances": [)" + ok +
           R"(, {"unit": "LSB", "constant": "accel.b_x", "upper": 2}]})",
       R"("accel.b_x", "upper": 2)",
       "tolerances[1]: 'accel.b_x' is given twice; expected one entry per constant, with both "
       "limits"},
      {R"({"decision_rule": "simple", "tolerances": [{"constant": "accel.b_x", "upper": 1}]})",
       R"({"constant")",
       R"(tolerances[0]: 'accel.b_x': missing 'unit' (e.g. "LSB", "g_n/LSB", "rad"): )" + entry},
      {R"({"decision_rule": "simple", "tolerances": [{"constant": "accel.b_x", "unit": 1}]})", "1}",
       R"(tolerances[0]: 'accel.b_x': 'unit' is 1: expected a unit such as "LSB", "g_n/LSB" )"
       R"(or "rad")"},
      {R"({"decision_rule": "simple", "tolerances": [{"constant": "accel.b_x", "upper": "x", )"
       R"("unit": "LSB"}]})",
       R"("x")",
       R"(tolerances[0]: 'accel.b_x': 'upper' is 'x': expected a finite number (or null for no )"
       R"(limit), e.g. "upper": 300)"},
      {R"({"decision_rule": "simple", "tolerances": [{"constant": "accel.b_x", "unit": "LSB"}]})",
       R"({"constant")", "tolerances[0]: 'accel.b_x' has neither 'lower' nor 'upper': " + entry},
      {R"({"decision_rule": "simple", "tolerances": [{"constant": "accel.b_x", "lower": 5, )"
       R"("upper": 1, "unit": "LSB"}]})",
       R"({"constant")", "tolerances[0]: 'accel.b_x': lower 5 > upper 1; expected lower <= upper"},
      // Checked against the calibration (EvaluateConformity), at the entry.
      {R"({"decision_rule": "simple", "tolerances": [{"constant": "accel.b_x", "upper": 1, )"
       R"("unit": "m/s^2"}]})",
       R"({"constant")",
       R"('accel.b_x': unit 'm/s^2' does not match the constant's unit 'LSB'; expected "unit": )"
       R"("LSB" or a unit convertible to it)"},
  };
  for (const Case& c : cases) {
    testing::TempFile f(c.spec, ".json");
    std::string error;
    Result<ConformitySpec> spec = LoadConformitySpec(f.path());
    if (!spec.ok()) {
      error = spec.error().ToString();
    } else {
      Result<ConformityStatement> st = EvaluateConformity(cal.value(), spec.value());
      if (!st.ok()) error = st.error().ToString();
    }
    INFO(c.spec);
    const size_t at = c.spec.find(c.at);
    REQUIRE(at != std::string::npos);
    CHECK(error == f.path() + ":" + testing::LineColumn(c.spec, at) + ": " + c.message);
  }
}

TEST_CASE("Conformity: named constants carry the units of calibration.json",
          "[calibration][conformity]") {
  Result<Calibration> cal = LoadCalibration(kGolden);
  REQUIRE(cal.ok());
  const std::vector<NamedConstant> c = NamedConstants(cal.value().tags[0]);
  auto find = [&](const std::string& name) -> const NamedConstant& {
    for (const NamedConstant& n : c) {
      if (n.name == name) return n;
    }
    FAIL("no " << name);
    return c[0];
  };
  CHECK(find("accel.b_x").unit == "LSB");
  CHECK(find("accel.k_y").unit == "g_n/LSB");
  CHECK(find("accel.a_zx").unit == "rad");
  CHECK(find("accel.b1_z").unit == "LSB/K");
  CHECK(find("accel.b1_z").covariance_index == 11);
  CHECK(find("gyro.g_yx").covariance_index == 11);
  CHECK(find("accel.b_y").u == cal.value().tags[0].accel->bias_u[1]);
}

}  // namespace
}  // namespace metro
