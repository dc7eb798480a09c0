// The unit check of a model: sums need one unit, constants take their place's unit, functions
// take numbers or radians, and the checker reads the expression as muparser does.
#include "uncertainty/model_units.hpp"

#include <catch2/catch.hpp>
#include <string>
#include <utility>
#include <vector>

#include "uncertainty/model.hpp"

namespace metro {
namespace internal {
namespace {

struct Var {
  std::string name;
  std::string unit;  // "" = not stated.
  double value;
};

Result<ModelUnit> Check(const std::string& model, const std::vector<Var>& vars) {
  std::vector<std::string> names;
  std::vector<std::optional<PhysicalUnit>> units;
  std::vector<double> values;
  for (const Var& v : vars) {
    names.push_back(v.name);
    values.push_back(v.value);
    if (v.unit.empty()) {
      units.emplace_back();
    } else {
      auto u = PhysicalUnit::Parse(v.unit);
      REQUIRE(u.ok());
      units.emplace_back(u.value());
    }
  }
  auto parsed = MeasurementModel::FromExpression(model, names);
  REQUIRE(parsed.ok());
  return CheckModelUnits(model, names, units, values, parsed.value().Evaluate(values.data()));
}

PhysicalUnit U(const std::string& text) { return PhysicalUnit::Parse(text).value(); }

void ExpectUnit(const std::string& model, const std::vector<Var>& vars, const std::string& unit,
                bool scale_known = true) {
  INFO(model);
  auto r = Check(model, vars);
  if (!r.ok()) FAIL(r.error().ToString());
  CHECK(r.value().unit.SameAs(U(unit)));
  CHECK(r.value().scale_known == scale_known);
}

void ExpectRefused(const std::string& model, const std::vector<Var>& vars,
                   const std::string& text) {
  INFO(model);
  auto r = Check(model, vars);
  REQUIRE_FALSE(r.ok());
  INFO(r.error().ToString());
  CHECK(r.error().ToString().find(text) != std::string::npos);
}

TEST_CASE("A sum of rad and deg is refused; terms in one unit pass", "[uncertainty][units]") {
  const std::vector<Var> v = {{"a", "rad", 0.5}, {"b", "deg", 30.0}, {"c", "rad", 0.1}};
  ExpectRefused("a + b", v, "column 3: a sum: 'a' (rad) and 'b' (deg) are in different units");
  ExpectRefused("c - b", v, "a difference: 'c' (rad) and 'b' (deg)");
  ExpectUnit("a + c", v, "rad");
  // The constant factor pi/180 is taken as the conversion: checked by dimension.
  ExpectUnit("a + b*pi/180", v, "rad");
}

TEST_CASE("Incompatible dimensions are refused with both terms and units", "[uncertainty][units]") {
  const std::vector<Var> v = {{"R", "cm", 32.0}, {"t", "s", 2.0}, {"k", "1/s", 3.0}};
  ExpectRefused("R + t", v, "a sum: incompatible dimensions, 'R' (cm) and 't' (s)");
  ExpectRefused("2*R - t", v, "incompatible dimensions");
  ExpectRefused("R < t", v, "a comparison");
  ExpectRefused("max(R, t)", v, "the arguments of max()");
  ExpectRefused("t > 1 ? R : t", v, "the branches of ?:");
  ExpectUnit("R*k*t", v, "cm");
  ExpectUnit("R/t + R*k", v, "cm/s");
}

TEST_CASE("Bare constants take the unit of their sum (JCGM 101 9.3 model)",
          "[uncertainty][units]") {
  // (mrc + dmrc)(1 + (rhoa - 1.2)(1/rhow - 1/rhor)) - 100000: 1.2 is kg/m^3, 100000 is mg.
  const std::vector<Var> v = {{"mrc", "mg", 100000.0},
                              {"dmrc", "mg", 1.234},
                              {"rhoa", "kg/m^3", 1.2},
                              {"rhow", "kg/m^3", 8000.0},
                              {"rhor", "kg/m^3", 8000.0}};
  ExpectUnit("(mrc + dmrc)*(1 + (rhoa - 1.2)*(1/rhow - 1/rhor)) - 100000", v, "mg");
  ExpectRefused("mrc + rhoa", v, "incompatible dimensions");
  // A constant alone in a sum never fixes a unit: 1 + 2 stays a number for its partner.
  ExpectUnit("(1 + 2) + mrc", v, "mg");
}

TEST_CASE("Functions take numbers; sin/cos/tan take radians", "[uncertainty][units]") {
  const std::vector<Var> v = {
      {"R", "cm", 32.0}, {"theta", "deg", 30.0}, {"phi", "rad", 0.5}, {"xs", "1", 0.0}};
  ExpectUnit("2*R*sin(theta*(1 + xs)*pi/360)", v, "cm", false);  // fingertip_chord.json
  ExpectUnit("R*sin(phi)", v, "cm");
  ExpectRefused("sin(theta)", v, "sin() takes radians, got 'theta' (deg)");
  ExpectRefused("exp(R)", v, "exp() needs a dimensionless argument, got 'R' (cm)");
  ExpectRefused("log(theta)", v, "log() takes a number");
  ExpectUnit("R*atan2(R, R)", v, "cm");
  ExpectUnit("sqrt(R*R)", v, "cm");
  ExpectRefused("sqrt(R)", v, "sqrt() of 'R' (cm)");
  ExpectUnit("abs(R) + R", v, "cm");
}

TEST_CASE("Powers: constant exponents raise the unit; a varying one needs a number",
          "[uncertainty][units]") {
  const std::vector<Var> v = {{"x", "m", 2.0}, {"n", "1", 2.0}, {"s", "s", 4.0}};
  ExpectUnit("x^2", v, "m^2");
  ExpectUnit("x^3^1", v, "m^3");     // Right-associative: x^(3^1).
  ExpectUnit("(x^2)^0.5", v, "m");   // 1/k powers.
  ExpectUnit("x^-1 * x^2", v, "m");  // A sign in the exponent.
  ExpectUnit("-x^2", v, "m^2");      // -(x^2) in muparser.
  ExpectRefused("x^n", v, "not a constant");
  ExpectUnit("2^n", v, "1");
  ExpectRefused("x^1.5", v, "cannot be raised to the power 1.5");
  ExpectRefused("s^0.5", v, "has no 2nd root");
}

TEST_CASE("A deeply nested model is refused, not a stack overflow", "[uncertainty][units]") {
  const std::vector<Var> v = {{"x", "m", 2.0}};
  const std::string deep = std::string(300, '(') + "x" + std::string(300, ')');
  ExpectRefused(deep, v, "nested too deeply");
  const std::string fine = std::string(100, '(') + "x" + std::string(100, ')');
  ExpectUnit(fine, v, "m");
}

TEST_CASE("An input without a unit is refused when it is used", "[uncertainty][units]") {
  const std::vector<Var> v = {{"a", "m", 1.0}, {"b", "", 2.0}};
  ExpectRefused("a*b", v, "input 'b' states no unit");
  ExpectUnit("a", v, "m");  // b unused.
}

TEST_CASE("The checker reads models as muparser does, or says so", "[uncertainty][units]") {
  // Precedence and associativity that differ between grammars: each value must match
  // muparser's (CheckModelUnits compares them and refuses a disagreement).
  const std::vector<Var> v = {{"x", "1", 2.0}, {"y", "1", 3.0}};
  for (const char* model :
       {"-x^2", "x^y^2", "x^-1^2", "2*-x", "x - y - 1", "x / y / 2", "x < y == 1",
        "x > 1 ? y : 0 ? 5 : 6", "x && 0 || y", "sum(x, y, 1) * avg(x, y)", "min(x, y) + max(x, 1)",
        "1e-3*x + .5 + 5.", "_pi*x + _e", "sign(-x) + rint(2.6)"}) {
    INFO(model);
    auto r = Check(model, v);
    if (!r.ok()) FAIL(r.error().ToString());
  }
  // A disagreeing value is refused (the check must be able to fail).
  std::vector<std::optional<PhysicalUnit>> units = {U("1"), U("1")};
  auto wrong = CheckModelUnits("-x^2", {"x", "y"}, units, {2.0, 3.0}, 4.0);
  REQUIRE_FALSE(wrong.ok());
  CHECK(wrong.error().ToString().find("reads it as -4 at the estimates but muparser as 4") !=
        std::string::npos);
}

}  // namespace
}  // namespace internal
}  // namespace metro
