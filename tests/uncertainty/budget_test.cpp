// Budget parsing: Type A / Type B standard uncertainties and every class of bad input.
#include "metro/uncertainty/budget.hpp"

#include <fmt/format.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <string>

#include "metro/uncertainty/gum.hpp"

namespace metro {
namespace {

Result<Budget> P(const std::string& inputs, const std::string& extra = "",
                 const std::string& model = "x") {
  return ParseBudget(R"({"measurand": {"name": "y", "model": ")" + model + R"("}, "inputs": [)" +
                         inputs + "]" + extra + "}",
                     "b.json");
}

const BudgetInput& First(const Result<Budget>& b) {
  if (!b.ok()) FAIL(b.error().ToString());
  return b.value().inputs.front();
}

void ExpectError(const Result<Budget>& b, const std::string& text) {
  REQUIRE_FALSE(b.ok());
  INFO(b.error().ToString());
  CHECK(b.error().ToString().find(text) != std::string::npos);
}

TEST_CASE("Type B standard uncertainties of JCGM 100 4.3 and JCGM 101 6.4",
          "[uncertainty][budget]") {
  CHECK(
      First(P(R"({"name": "x", "value": 1, "distribution": "rectangular", "half_width": 3})")).u ==
      Approx(std::sqrt(3.0)));
  const BudgetInput lu =
      First(P(R"({"name": "x", "distribution": "rectangular", "lower": 9.5, "upper": 13.5})"));
  CHECK(lu.value == Approx(11.5));
  CHECK(lu.u == Approx(2.0 / std::sqrt(3.0)));
  CHECK(First(P(R"({"name": "x", "value": 0, "distribution": "triangular", "half_width": 6})")).u ==
        Approx(6.0 / std::sqrt(6.0)));
  CHECK(First(P(R"({"name": "x", "value": 0, "distribution": "arcsine", "half_width": 0.5})")).u ==
        Approx(0.5 / std::sqrt(2.0)));
  CHECK(
      First(
          P(R"({"name": "x", "value": 0, "distribution": "trapezoidal", "half_width": 2, "beta": 0.5})"))
          .u == Approx(2.0 * std::sqrt(1.25 / 6.0)));
  CHECK(
      First(
          P(R"({"name": "x", "value": 0, "distribution": "ctrap", "half_width": 0.05, "d": 0.025})"))
          .u == Approx(std::sqrt(0.0025 / 3 + 0.000625 / 9)));
  // Normal from U and k (H.1: 75 nm at k = 3 -> 25 nm); from U at 95 % (z = 1.959964) and
  // with dof 5 (t_0.975(5) = 2.570582).
  CHECK(First(P(R"({"name": "x", "value": 0, "expanded": 0.075, "k": 3})")).u == Approx(0.025));
  CHECK(First(P(R"({"name": "x", "value": 0, "expanded": 1.959964, "coverage": 0.95})")).u ==
        Approx(1.0).epsilon(1e-6));
  const BudgetInput y =
      First(P(R"({"name": "x", "value": 0, "expanded": 0.01, "coverage": 0.95, "dof": 5})"));
  CHECK(y.u == Approx(0.01 / 2.570582).epsilon(1e-6));
  CHECK(y.dof == 5.0);
  // Reliability 25 % -> nu = 1/(2 * 0.0625) = 8 (JCGM 100 G.4.2).
  CHECK(First(P(R"({"name": "x", "value": 0, "u": 1, "reliability": 0.25})")).dof == Approx(8.0));
  CHECK(std::isinf(First(P(R"({"name": "x", "value": 0, "u": 1})")).dof));
  const BudgetInput t =
      First(P(R"({"name": "x", "value": 5, "distribution": "t", "scale": 2, "dof": 7})"));
  CHECK(t.u == 2.0);
  CHECK(t.dof == 7.0);
}

TEST_CASE("Type A inputs from observations, summaries and sessions", "[uncertainty][budget]") {
  // 1.2, 1.3, 1.1: mean 1.2, s = 0.1, s/sqrt(3) = 0.057735, dof 2.
  const BudgetInput a = First(P(R"({"name": "x", "type_a": {"values": [1.2, 1.3, 1.1]}})"));
  CHECK(a.value == Approx(1.2));
  CHECK(a.u == Approx(0.1 / std::sqrt(3.0)));
  CHECK(a.dof == 2.0);
  CHECK(a.distribution == Distribution::kTypeA);
  // Thesis Table 8.3 pitch: s 0.03077, n = 4704 -> s(mean) = 0.000449 deg.
  const BudgetInput b =
      First(P(R"({"name": "x", "type_a": {"mean": -0.09228, "std": 0.03077, "n": 4704}})"));
  CHECK(b.u == Approx(0.03077 / std::sqrt(4704.0)));
  CHECK(b.dof == 4703.0);
  // Session quantity through the resolver; the path is relative to the budget file.
  SessionQuantityRef seen;
  const SessionQuantityResolver resolver =
      [&](const SessionQuantityRef& ref) -> Result<TypeASummary> {
    seen = ref;
    return TypeASummary{0.5, 0.01, 19.45, 40, "autocorrelation-aware", ""};
  };
  auto s = ParseBudget(R"({"measurand": {"name": "y", "model": "p"}, "inputs": [
      {"name": "p", "type_a": {"session": "s.csv", "sensor": 2, "quantity": "pitch_deg"}}]})",
                       "/data/budgets/b.json", resolver);
  REQUIRE(s.ok());
  CHECK(seen.session == "/data/budgets/s.csv");
  CHECK(seen.sensor == 2);
  CHECK(seen.quantity == "pitch_deg");
  CHECK(s.value().inputs[0].u == 0.01);
  CHECK(s.value().inputs[0].dof == 19.45);
  CHECK(s.value().inputs[0].note == "autocorrelation-aware");
  // Without a resolver: an error naming the input.
  ExpectError(
      P(R"({"name": "p", "type_a": {"session": "s.csv", "quantity": "pitch_deg"}})", "", "p"),
      "input 'p': refers to session quantity 'pitch_deg' but no session resolver");
  // A resolver failure is passed on with the input's name.
  const SessionQuantityResolver failing = [](const SessionQuantityRef&) -> Result<TypeASummary> {
    return MakeError("s.csv", 0, "no quantity 'pitch_deg' for sensor 2");
  };
  auto f = ParseBudget(R"({"measurand": {"name": "y", "model": "p"}, "inputs": [
      {"name": "p", "type_a": {"session": "s.csv", "sensor": 2, "quantity": "pitch_deg"}}]})",
                       "b.json", failing);
  ExpectError(f, "input 'p': s.csv: no quantity 'pitch_deg' for sensor 2");
}

TEST_CASE("Bad input: unknown distribution", "[uncertainty][budget]") {
  ExpectError(P(R"({"name": "x", "value": 0, "distribution": "lognormal", "u": 1})"),
              "b.json: input 'x': unknown distribution 'lognormal'");
}

TEST_CASE("Bad input: missing parameter", "[uncertainty][budget]") {
  ExpectError(P(R"({"name": "x", "value": 0, "distribution": "rectangular"})"),
              "input 'x': rectangular needs 'half_width' (or 'lower' and 'upper')");
  ExpectError(P(R"({"name": "x", "value": 0})"), "input 'x': missing 'u'");
  ExpectError(P(R"({"name": "x", "value": 0, "distribution": "t", "scale": 1})"),
              "input 'x': missing 'dof'");
  ExpectError(P(R"({"name": "x", "value": 0, "distribution": "trapezoidal", "half_width": 1})"),
              "input 'x': missing 'beta'");
  ExpectError(P(R"({"name": "x", "value": 0, "expanded": 1})"),
              "input 'x': 'expanded' needs 'k' or 'coverage'");
  ExpectError(P(R"({"name": "x", "type_a": {"mean": 1, "std": 0.1}})"),
              "input 'x': missing 'type_a.n'");
  ExpectError(P(R"({"value": 0, "u": 1})"), "inputs[0]: missing 'name'");
  ExpectError(P(R"({"name": "x", "value": 0, "u": 1})", "", ""),
              "input 'x': missing 'sensitivity' (needed when the budget has no model)");
}

TEST_CASE("Bad input: negative u and other out-of-range parameters", "[uncertainty][budget]") {
  ExpectError(P(R"({"name": "x", "value": 0, "u": -1})"), "input 'x': u must be >= 0, got -1");
  ExpectError(P(R"({"name": "x", "value": 0, "distribution": "rectangular", "half_width": -2})"),
              "input 'x': 'half_width' must be >= 0");
  ExpectError(P(R"({"name": "x", "value": 0, "distribution": "ctrap", "half_width": 1, "d": 2})"),
              "input 'x': 'd' must be in [0, half_width]");
  ExpectError(P(R"({"name": "x", "value": 0, "u": 1, "dof": 0})"), "input 'x': 'dof' must be > 0");
  ExpectError(P(R"({"name": "x", "value": 0, "u": 1, "halfwidth": 1})"),
              "input 'x': unknown key 'halfwidth'");
  ExpectError(P(R"({"name": "x", "value": 0, "u": 1})", R"(, "coverage": 1.5)"),
              "'coverage' must be in (0, 1)");
}

TEST_CASE("Bad input: correlation coefficient beyond 1", "[uncertainty][budget]") {
  ExpectError(P(R"({"name": "x", "value": 0, "u": 1}, {"name": "z", "value": 0, "u": 1})",
                R"(, "correlations": [{"a": "x", "b": "z", "r": 1.2}])", "x + z"),
              "correlation x/z: |r| must be <= 1, got 1.2");
  ExpectError(P(R"({"name": "x", "value": 0, "u": 1})",
                R"(, "correlations": [{"a": "x", "b": "w", "r": 0.2}])"),
              "correlation x/w: input 'w' is not defined");
}

TEST_CASE("Bad input: correlation matrix not positive definite", "[uncertainty][budget]") {
  // r_ab = r_bc = 0.9 forces r_ac >= 0.62; r_ac = -0.9 is impossible.
  ExpectError(
      P(R"({"name": "a", "value": 0, "u": 1}, {"name": "b", "value": 0, "u": 1},
                   {"name": "c", "value": 0, "u": 1})",
        R"(, "correlations": [{"a": "a", "b": "b", "r": 0.9}, {"a": "b", "b": "c", "r": 0.9},
                                      {"a": "a", "b": "c", "r": -0.9}])",
        "a + b + c"),
      "the correlation matrix is not positive definite: input 'c'");
}

TEST_CASE("Bad input: undefined name in the model", "[uncertainty][budget]") {
  ExpectError(P(R"({"name": "x", "value": 0, "u": 1})", "", "x + zz*2"),
              "model 'x + zz*2' uses 'zz', which is not an input");
  ExpectError(P(R"({"name": "x", "value": 0, "u": 1})", "", "x + (2"), "model 'x + (2'");
  ExpectError(P(R"({"name": "x", "value": 0, "u": 1, "sensitivity": 2})"),
              "input 'x': 'sensitivity' is only for budgets without a model");
}

TEST_CASE("Bad input: a model that assigns or has several results", "[uncertainty][budget]") {
  // muparser would evaluate `x=5` by overwriting x: y = 5 +- 0 (issue #20).
  ExpectError(P(R"({"name": "x", "value": 2, "u": 1})", "", "x=5"),
              "model 'x=5': '=' at position 2 assigns; a model is one expression");
  ExpectError(P(R"({"name": "x", "value": 2, "u": 1})", "", "3*x = 5"),
              "'=' at position 5 assigns");
  ExpectError(P(R"({"name": "x", "value": 2, "u": 1})", "", "x, 2*x"),
              "model 'x, 2*x': 2 comma-separated expressions; a model is one expression");
  // Comparisons and function arguments stay legal.
  for (const char* model :
       {"x == 2 ? x : 0", "x >= 1 ? x : 0", "x <= 3 ? x : 0", "x != 1 ? x : 0", "max(x, 1)"}) {
    INFO(model);
    auto b = P(R"({"name": "x", "value": 2, "u": 1})", "", model);
    CHECK(b.ok());
  }
}

TEST_CASE("Bad input: an error in a long model quotes it once, cut around its column",
          "[uncertainty][budget][security][issue37]") {
  // issue #37: a 1 MB model was echoed twice in one message (muparser's "Expression too long"
  // with the whole expression as its token), 2 MB on one line and no line or column.
  // The model starts on line 2 at column 12 (after ` "model": "`).
  auto parse = [](const std::string& model, const std::string& inputs) {
    return ParseBudget("{\"measurand\": {\"name\": \"y\",\n \"model\": \"" + model +
                           "\"}, \"inputs\": [" + inputs + "]}",
                       "b.json");
  };
  const std::string x = R"({"name": "x", "value": 1, "u": 0.1})";
  std::string model = "x";
  while (model.size() < 1000000) model += " + x";
  Result<Budget> b = parse(model, x);
  REQUIRE_FALSE(b.ok());
  std::string text = b.error().ToString();
  INFO(text.substr(0, 400));
  // At byte 19999 of the model (past muparser's limit), column 12 + 19999.
  CHECK(text.rfind("b.json:2:20011: model '...", 0) == 0);
  CHECK(text.find(fmt::format("': {} bytes; muparser reads a model of at most 19999 bytes",
                              model.size())) != std::string::npos);
  CHECK(text.size() < 400);
  CHECK(text.find("model '") == text.rfind("model '"));  // Quoted once.

  // An undefined name at the end of a 15000-byte model: its column, the quote around it.
  model = "x";
  while (model.size() < 15000) model += " + x";
  model += " + zz";
  b = parse(model, x);
  REQUIRE_FALSE(b.ok());
  text = b.error().ToString();
  INFO(text);
  const size_t zz = model.size() - 2;  // byte of 'zz'
  CHECK(text.rfind(fmt::format("b.json:2:{}: model '...", 12 + zz), 0) == 0);
  CHECK(text.find(" + x + zz' uses 'zz', which is not an input") != std::string::npos);
  CHECK(text.size() < 250);

  // A syntax error: muparser's position, its message once (no "near" repeating the token).
  b = parse(model.substr(0, 15000) + " + (2", x);
  REQUIRE_FALSE(b.ok());
  text = b.error().ToString();
  INFO(text);
  CHECK(text.rfind("b.json:2:", 0) == 0);
  CHECK(text.size() < 300);

  // An escape before the error counts as the byte it stands for: "\u0020" is 1 byte of the
  // model (a space) but 6 of the file.
  b = ParseBudget(
      "{\"measurand\": {\"name\": \"y\", \"model\": \"x +\\u0020zz\"}, \"inputs\": [" + x + "]}",
      "b.json");
  REQUIRE_FALSE(b.ok());
  // The opening quote is column 38; 'zz' is byte 4 of the model, 10 of the literal.
  CHECK(b.error().ToString() == "b.json:1:48: model 'x + zz' uses 'zz', which is not an input");
}

TEST_CASE("Bad input: max_trials beyond the memory cap", "[uncertainty][budget]") {
  ExpectError(P(R"({"name": "x", "value": 0, "u": 1})",
                R"(, "monte_carlo": {"adaptive": true, "max_trials": 1000000000000000})"),
              "monte_carlo: max_trials must be at most 5e8 (memory: 8 bytes per trial), got "
              "1000000000000000");
  auto b = P(R"({"name": "x", "value": 0, "u": 1})",
             R"(, "monte_carlo": {"adaptive": true, "max_trials": 500000000})");
  CHECK(b.ok());
}

TEST_CASE("Bad input: model evaluating to NaN", "[uncertainty][budget]") {
  ExpectError(P(R"({"name": "x", "value": -1, "u": 0.1})", "", "sqrt(x)"),
              "model 'sqrt(x)' evaluates to");
  ExpectError(P(R"({"name": "x", "value": -1, "u": 0.1})", "", "sqrt(x)"),
              "at the input estimates");
}

TEST_CASE("Bad input: invalid JSON reports line and column", "[uncertainty][budget]") {
  auto b = ParseBudget("{\n  \"measurand\": {\"name\": \"y\"},\n  \"inputs\": [,]\n}", "b.json");
  REQUIRE_FALSE(b.ok());
  CHECK(b.error().line == 3);
  CHECK(b.error().ToString().find("b.json:3:") == 0);
}

TEST_CASE("Budget options from the file", "[uncertainty][budget]") {
  auto b = P(R"({"name": "x", "value": 0, "u": 1})",
             R"(, "coverage": 0.99, "gum": {"second_order": true, "dof_policy": "ignore"},
                "monte_carlo": {"trials": 20000, "seed": 9, "threads": 1})");
  REQUIRE(b.ok());
  CHECK(b.value().gum.coverage == 0.99);
  CHECK(b.value().gum.second_order);
  CHECK(b.value().gum.correlated_dof == CorrelatedDofPolicy::kIgnore);
  CHECK(b.value().monte_carlo.coverage == 0.99);
  CHECK_FALSE(b.value().monte_carlo.adaptive);
  CHECK(b.value().monte_carlo.trials == 20000);
  CHECK(b.value().monte_carlo.seed == 9);
  ExpectError(P(R"({"name": "x", "value": 0, "u": 1})", R"(, "gum": {"dof_policy": "magic"})"),
              "gum: unknown dof_policy 'magic'");
  ExpectError(P(R"({"name": "x", "value": 0, "u": 1})", R"(, "monte_carlo": {"trials": 1})"),
              "monte_carlo: trials must be at least 2");
}

TEST_CASE("Example budgets in datasets parse", "[uncertainty][budget]") {
  for (const char* name :
       {"gum_h1_end_gauge.json", "jcgm101_9_5_gauge_block.json", "jcgm101_9_3_mass.json",
        "tag_static_angle.json", "fingertip_chord.json", "fingertip_sagitta.json"}) {
    INFO(name);
    auto b = LoadBudget(std::string(METRO_SOURCE_DIR) + "/datasets/budgets/" + name);
    if (!b.ok()) FAIL(b.error().ToString());
  }
}

TEST_CASE("Bundled budgets pass the unit check and keep their published values",
          "[uncertainty][budget][units]") {
  struct Case {
    const char* file;
    const char* model_unit;  // The measurand's unit, as the check must derive it.
    double value;            // Published (JCGM 100 H.1, JCGM 101 9.3/9.5) or closed form.
    double value_tolerance;
    double u;
    double u_tolerance;
  };
  const double kPi = 3.14159265358979323846;
  for (const Case& c : {
           // H.1: l = 50 000 838 nm, u_c = 32 nm (first order, the file's model).
           Case{"gum_h1_end_gauge.json", "nm", 50000838.0, 0.5, 32.0, 0.5},
           // 9.3: GUF dm = 1.2340 mg, u = 0.0539 mg; 9.5: 838 nm, u = 32 nm.
           Case{"jcgm101_9_3_mass.json", "mg", 1.2340, 5e-5, 0.0539, 5e-5},
           Case{"jcgm101_9_5_gauge_block.json", "nm", 838.0, 0.5, 32.0, 0.5},
           // 2 R sin(theta/2) at R = 32 cm, theta = 30 deg; R (1 - cos(theta/2)) at 2 deg.
           Case{"fingertip_chord.json", "cm", 64.0 * std::sin(15.0 * kPi / 180.0), 1e-9, -1, 0},
           Case{"fingertip_sagitta.json", "cm", 32.0 * (1.0 - std::cos(kPi / 180.0)), 1e-12, -1, 0},
           // obs + res + mount + xaxis*yaw at the estimates: -0.09228 deg.
           Case{"tag_static_angle.json", "deg", -0.09228, 1e-12, -1, 0},
       }) {
    INFO(c.file);
    auto b = LoadBudget(std::string(METRO_SOURCE_DIR) + "/datasets/budgets/" + c.file);
    if (!b.ok()) FAIL(b.error().ToString());
    auto units = CheckBudgetUnits(b.value());
    REQUIRE(units.ok());
    CHECK(units.value().checked);
    CHECK(PhysicalUnit::Parse(units.value().model_unit)
              .value()
              .ConvertibleTo(PhysicalUnit::Parse(c.model_unit).value()));
    auto gum = EvaluateGum(b.value());
    REQUIRE(gum.ok());
    CHECK(gum.value().value == Approx(c.value).margin(c.value_tolerance));
    if (c.u > 0) CHECK(gum.value().u == Approx(c.u).margin(c.u_tolerance));
  }
  // No unit on any input (JCGM 101 9.2.2): nothing to compare, and said so.
  auto additive =
      LoadBudget(std::string(METRO_SOURCE_DIR) + "/datasets/budgets/jcgm101_9_2_2_additive.json");
  REQUIRE(additive.ok());
  CHECK_FALSE(CheckBudgetUnits(additive.value()).value().checked);
}

Result<Budget> WithUnits(const std::string& model, const std::string& measurand_unit,
                         const std::string& inputs) {
  return ParseBudget(R"({"measurand": {"name": "y", "unit": ")" + measurand_unit +
                         R"(", "model": ")" + model + R"("}, "inputs": [)" + inputs +
                         R"(], "monte_carlo": false})",
                     "b.json");
}

TEST_CASE("A model adding rad to deg is refused, naming both inputs",
          "[uncertainty][budget][units]") {
  ExpectError(WithUnits("a + b", "rad",
                        R"({"name": "a", "value": 0.5, "u": 0.01, "unit": "rad"},
                           {"name": "b", "value": 30, "u": 0.1, "unit": "deg"})"),
              // The '+' at column 3 of the model, whose first byte is column 54 of the file.
              "b.json:1:56: model 'a + b', column 3: a sum: 'a' (rad) and 'b' (deg) are in "
              "different units (1 rad = 57.2958 deg)");
  ExpectError(WithUnits("a + b", "m",
                        R"({"name": "a", "value": 1, "u": 0.01, "unit": "m"},
                           {"name": "b", "value": 2, "u": 0.1, "unit": "s"})"),
              "incompatible dimensions, 'a' (m) and 'b' (s)");
}

TEST_CASE("The measurand's unit must be the model's", "[uncertainty][budget][units]") {
  const std::string kg = R"({"name": "m", "value": 0.1, "u": 1e-6, "unit": "kg"})";
  // A kg model declared in mg: refused with the factor (1 kg = 1e6 mg), not relabelled.
  ExpectError(WithUnits("m", "mg", kg),
              "measurand 'y' is declared in 'mg' but the model 'm' gives kg (1 kg = 1e+06 mg)");
  // At the model's opening quote, column 52 (issue #37).
  CHECK(WithUnits("m", "mg", kg).error().ToString().rfind("b.json:1:52: measurand 'y'", 0) == 0);
  ExpectError(WithUnits("m", "m/s^2", kg), "incompatible dimensions");
  REQUIRE(WithUnits("m", "kg", kg).ok());
  // A constant factor converts: 1e6*m is in mg (checked by dimension).
  auto scaled = WithUnits("1e6*m", "mg", kg);
  REQUIRE(scaled.ok());
  CHECK_FALSE(CheckBudgetUnits(scaled.value()).value().scale_known);
  // Without a measurand unit the model's is reported.
  auto bare = WithUnits("m*m", "", kg);
  REQUIRE(bare.ok());
  CHECK(PhysicalUnit::Parse(CheckBudgetUnits(bare.value()).value().model_unit)
            .value()
            .SameAs(PhysicalUnit::Parse("kg^2").value()));
}

TEST_CASE("Unknown units and inputs without one are refused by name",
          "[uncertainty][budget][units]") {
  ExpectError(WithUnits("a", "m", R"({"name": "a", "value": 1, "u": 0.1, "unit": "meterz"})"),
              "b.json: input 'a': unknown unit 'meterz'");
  ExpectError(WithUnits("a", "parsecz", R"({"name": "a", "value": 1, "u": 0.1, "unit": "m"})"),
              "measurand 'y': unknown unit 'parsecz'");
  ExpectError(WithUnits("a*b", "m",
                        R"({"name": "a", "value": 1, "u": 0.1, "unit": "m"},
                           {"name": "b", "value": 1, "u": 0.1})"),
              "input 'b' states no unit");
}

// A resolver that answers every quantity with a fixed summary in `unit`.
SessionQuantityResolver FixedResolver(double mean, double u, const std::string& unit) {
  return [=](const SessionQuantityRef&) -> Result<TypeASummary> {
    return TypeASummary{mean, u, 99.0, 100, "test session", unit};
  };
}

Result<Budget> SessionBudget(const std::string& quantity, const std::string& input_unit,
                             const std::string& measurand_unit,
                             const SessionQuantityResolver& resolver) {
  const std::string unit = input_unit.empty() ? "" : R"(, "unit": ")" + input_unit + R"(")";
  return ParseBudget(R"({"measurand": {"name": "y", "unit": ")" + measurand_unit +
                         R"(", "model": "p"}, "inputs": [
      {"name": "p", "type_a": {"sensor": 2, "quantity": ")" +
                         quantity + R"("})" + unit + R"(}], "monte_carlo": false})",
                     "b.json", resolver);
}

TEST_CASE("Session inputs carry their unit and are converted to the declared one",
          "[uncertainty][budget][units]") {
  // pitch_deg = 30 deg, u 0.5 deg, used as an input in rad: 30 deg = pi/6 rad.
  auto rad = SessionBudget("pitch_deg", "rad", "rad", FixedResolver(30.0, 0.5, "deg"));
  if (!rad.ok()) FAIL(rad.error().ToString());
  const BudgetInput& p = rad.value().inputs[0];
  CHECK(p.value == Approx(0.5235987755982988).epsilon(1e-15));
  CHECK(p.u == Approx(0.5 * 0.017453292519943295).epsilon(1e-15));
  REQUIRE(p.unit_conversion.has_value());
  CHECK(p.unit_conversion->from == "deg");
  CHECK(p.unit_conversion->to == "rad");
  CHECK(p.value_before_conversion == 30.0);
  CHECK(p.u_before_conversion == 0.5);
  CHECK(p.dof == 99.0);
  // ax_g = 1 g (standard gravity, io's vocabulary) as m/s^2: 9.80665 exactly.
  auto accel = SessionBudget("ax_g", "m/s^2", "m/s^2", FixedResolver(1.0, 0.002, "g_n"));
  if (!accel.ok()) FAIL(accel.error().ToString());
  CHECK(accel.value().inputs[0].value == Approx(9.80665).epsilon(1e-15));
  CHECK(accel.value().inputs[0].u == Approx(0.0196133).epsilon(1e-14));
  // gz_dps = -90 deg/s as rad/s; a negative factor would still give u >= 0.
  auto rate = SessionBudget("gz_dps", "rad/s", "rad/s", FixedResolver(-90.0, 1.0, "deg/s"));
  REQUIRE(rate.ok());
  CHECK(rate.value().inputs[0].value == Approx(-1.5707963267948966).epsilon(1e-15));
  // temp_c = 25 degC as K: the offset applies to the value, not to u.
  auto temp = SessionBudget("temp_c", "K", "K", FixedResolver(25.0, 0.1, "degC"));
  REQUIRE(temp.ok());
  CHECK(temp.value().inputs[0].value == Approx(298.15).epsilon(1e-14));
  CHECK(temp.value().inputs[0].u == Approx(0.1).epsilon(1e-12));
  // The same unit: no conversion; no declared unit: the session's is taken.
  auto same = SessionBudget("pitch_deg", "deg", "deg", FixedResolver(30.0, 0.5, "deg"));
  REQUIRE(same.ok());
  CHECK_FALSE(same.value().inputs[0].unit_conversion.has_value());
  CHECK(same.value().inputs[0].value == 30.0);
  auto adopted = SessionBudget("pitch_deg", "", "deg", FixedResolver(30.0, 0.5, "deg"));
  REQUIRE(adopted.ok());
  CHECK(adopted.value().inputs[0].unit == "deg");
}

TEST_CASE("A session quantity in an incompatible unit is refused, naming the input",
          "[uncertainty][budget][units]") {
  ExpectError(SessionBudget("pitch_deg", "s", "s", FixedResolver(30.0, 0.5, "deg")),
              "b.json: input 'p': session quantity 'pitch_deg' is in deg, which cannot be "
              "converted to the input's unit 's'");
  // g is the gram: an accelerometer quantity declared in g is refused with the hint.
  ExpectError(SessionBudget("ax_g", "g", "g", FixedResolver(1.0, 0.01, "g_n")),
              "cannot be converted to the input's unit 'g' (g is the gram; standard gravity is "
              "g_n or g0)");
  // Converted to rad, the session's pitch cannot be used as deg: the model refuses rad + deg.
  auto mixed = ParseBudget(R"({"measurand": {"name": "y", "unit": "rad", "model": "p + q"},
      "inputs": [{"name": "p", "type_a": {"quantity": "pitch_deg"}, "unit": "rad"},
                 {"name": "q", "type_a": {"quantity": "yaw_deg"}}], "monte_carlo": false})",
                           "b.json", FixedResolver(30.0, 0.5, "deg"));
  ExpectError(mixed, "'p' (rad) and 'q' (deg) are in different units");
}

}  // namespace
}  // namespace metro
