// The model grammar's one reader (model_grammar.hpp): the trees it builds for muparser's
// precedence and associativity, its errors at their columns, and, on random expressions of
// the grammar, agreement with muparser's own evaluation of both the tree and the GiNaC
// expression the exact derivatives are taken from.
#include "uncertainty/model_grammar.hpp"

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "uncertainty/model.hpp"
#include "uncertainty/model_units.hpp"
#include "uncertainty/symbolic_model.hpp"

namespace metro {
namespace internal {
namespace {

const std::vector<std::string> kNames = {"a", "b", "c"};

// The tree as an S-expression: (op children...), inputs by name, numbers as written.
std::string Lisp(const ModelSyntax& s, size_t n) {
  const ModelNode& node = s.nodes[n];
  std::string out;
  const auto kids = [&] {
    std::string k;
    for (size_t c : node.children) k += " " + Lisp(s, c);
    return k;
  };
  switch (node.kind) {
    case ModelNode::Kind::kNumber:
      return node.text;
    case ModelNode::Kind::kInput:
      return kNames[node.input];
    case ModelNode::Kind::kPi:
      return "pi";
    case ModelNode::Kind::kE:
      return "e";
    case ModelNode::Kind::kSign:
      return std::string("(") + (node.negative ? "neg" : "pos") + kids() + ")";
    case ModelNode::Kind::kPower:
      return "(^" + kids() + ")";
    case ModelNode::Kind::kIf:
      return "(?" + kids() + ")";
    case ModelNode::Kind::kCall:
      return "(" + node.text + kids() + ")";
    case ModelNode::Kind::kChain:
      out = "(" + Lisp(s, node.children[0]);
      for (size_t k = 0; k < node.ops.size(); ++k) {
        out +=
            std::string(" ") + ModelOperatorText(node.ops[k]) + " " + Lisp(s, node.children[k + 1]);
      }
      return out + ")";
  }
  return "?";
}

std::string Tree(const std::string& model) {
  auto s = ParseModel(model, kNames);
  if (!s.ok()) return "error: " + s.error().message;
  return Lisp(s.value(), s.value().root());
}

TEST_CASE("The model grammar reads muparser's precedence and associativity",
          "[uncertainty][grammar]") {
  CHECK(Tree("a + b*c") == "(a + (b * c))");
  CHECK(Tree("a - b - c") == "(a - b - c)");  // One chain, from the left: (a - b) - c.
  CHECK(Tree("-a^2") == "(neg (^ a 2))");     // Signs below ^.
  CHECK(Tree("a^b^2") == "(^ a (^ b 2))");    // ^ right-associative.
  CHECK(Tree("a^-1^2") == "(^ a (neg (^ 1 2)))");
  CHECK(Tree("2*-a") == "(2 * (neg a))");
  CHECK(Tree("a < b == 1") == "(a < b == 1)");
  CHECK(Tree("a && b || c") == "((a && b) || c)");
  CHECK(Tree("a || b && c") == "(a || (b && c))");
  CHECK(Tree("a + 1 > b ? a : b ? 5 : 6") == "(? ((a + 1) > b) a (? b 5 6))");
  CHECK(Tree("max(a, b*2, sum(c))") == "(max a (b * 2) (sum c))");
  CHECK(Tree("pi*_pi + _e") == "((pi * pi) + e)");
  CHECK(Tree("1e-3*a + .5 + 5. + 2E+2") == "((1e-3 * a) + .5 + 5. + 2E+2)");
  // Space is any byte from 1 to 32, as muparser skips it (a model may span lines).
  CHECK(Tree(" a +\n\tb\r\n* c ") == "(a + (b * c))");
}

TEST_CASE("The model grammar's nodes carry their byte offsets", "[uncertainty][grammar]") {
  //                        0123456789012345678
  auto s = ParseModel("(a + b) * -c^2 ? a : b", kNames);
  REQUIRE(s.ok());
  const ModelNode& root = s.value().nodes[s.value().root()];
  REQUIRE(root.kind == ModelNode::Kind::kIf);
  CHECK(root.at == 15);  // The '?'.
  CHECK(root.begin == 0);
  CHECK(root.end == 22);
  const ModelNode& product = s.value().nodes[root.children[0]];
  REQUIRE(product.kind == ModelNode::Kind::kChain);
  CHECK(product.op_at == std::vector<size_t>{8});
  const ModelNode& sum = s.value().nodes[product.children[0]];
  CHECK(sum.begin == 0);  // Its parentheses belong to it.
  CHECK(sum.end == 7);
  CHECK(sum.op_at == std::vector<size_t>{3});
  const ModelNode& sign = s.value().nodes[product.children[1]];
  CHECK(sign.kind == ModelNode::Kind::kSign);
  CHECK(sign.begin == 10);
  CHECK(sign.end == 14);
  CHECK(s.value().nodes[sign.children[0]].at == 12);  // The '^'.
}

TEST_CASE("The model grammar's errors name the column and what was expected",
          "[uncertainty][grammar]") {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"a +", "column 4: unexpected end of the model"},
      {"(a + b", "column 7: expected ')'"},
      {"sin(a", "column 6: expected ',' or ')' in the arguments of sin()"},
      {"a ? b", "column 6: expected ':' of '?'"},
      {"a $ b", "column 3: unexpected '$'"},
      {"a b", "column 3: unexpected 'b'"},
      {"z + a", "column 1: 'z' is not an input"},
      {"a + fmod(a, b)", "column 5: the function fmod() is not in the model grammar"},
      {"1 + sin(a, b)", "column 5: sin() takes 1 argument"},
      {"atan2(a)", "column 1: atan2() takes 2 arguments"},
      {"a*min()", "column 3: min() needs at least one argument"},
      {"a + .", "column 5: expected a number"},
  };
  for (const auto& [model, message] : cases) {
    INFO(model);
    auto s = ParseModel(model, kNames);
    REQUIRE_FALSE(s.ok());
    CHECK(s.error().message == message);
    CHECK(s.error().column == std::stoll(message.substr(7)));
  }
  // Nesting is bounded (parentheses and signs each count), so a hostile model cannot
  // exhaust the stack: 127 parentheses read, 128 do not.
  CHECK(ParseModel(std::string(127, '(') + "a" + std::string(127, ')'), kNames).ok());
  auto deep = ParseModel(std::string(128, '(') + "a" + std::string(128, ')'), kNames);
  REQUIRE_FALSE(deep.ok());
  CHECK(deep.error().message ==
        "column 129: nested too deeply (parentheses, arguments and signs beyond 256 levels)");
  CHECK_FALSE(ParseModel(std::string(300, '-') + "a", kNames).ok());
}

// Random expressions of the grammar whose value at inputs in [1, 2] keeps its sign by
// construction (positive unless `negative`), so that no sum cancels and double and 30-digit
// evaluations may be compared relatively. Every operator, sign, constant and function of the
// grammar appears; parentheses only where the grammar needs them (precedence is what is
// tested).
class Generator {
 public:
  explicit Generator(uint64_t seed) : rng_(seed) {}

  std::string Positive(int depth) {
    if (depth <= 0) return Leaf();
    const int d = depth - 1;
    switch (Pick(22)) {
      case 0:
        return Positive(d) + " + " + Positive(d) + "*" + Positive(d);
      case 1:
        return Positive(d) + " / " + Paren(d) + " / " + Leaf();  // (x / y) / z.
      case 2:                                                    // x + y - y/2, no cancellation.
        return Positive(d) + " + " + Leaf("a") + " - " + Leaf("a") + "/2";
      case 3:
        return Paren(d) + "^" + Exponent();
      case 4:
        return Leaf() + "^" + Leaf() + "^0.5";  // Right-associative.
      case 5:
        return "-" + Leaf() + "*-" + Paren(d);  // Signs below *: (-x)*(-y).
      case 6:
        return Leaf() + " - -" + Leaf() + "^2";  // x - (-(y^2)).
      case 7:
        return "(" + Leaf() + " < " + Leaf() + " == 1)*" + Leaf() + " + " + Leaf();
      case 8:
        return "(" + Leaf() + " > 1.5 && " + Leaf() + " <= 1.2 || " + Leaf() + " != " + Leaf() +
               ")*2 + (" + Leaf() + " > 1.5 || " + Leaf() + " < 1.7 && " + Leaf() + " >= 1.3) + " +
               Leaf();
      case 9:
        return "(" + Leaf() + " >= " + Leaf() + " ? " + Positive(d) + " : " + Leaf() + " < 1.5 ? " +
               Leaf() + " : " + Positive(d) + ")";
      case 10:
        return Fn({"sqrt", "abs", "atan", "asinh", "cosh"}) + "(" + Positive(d) + ")";
      case 11:
        return Fn({"ln", "log", "log10", "log2"}) + "(1 + " + Positive(d) + ")";
      case 12:  // Arguments in (0, 1): leaves are at most pi.
        return Fn({"exp", "sinh", "tanh", "asin", "acos", "atanh", "sin", "cos", "tan"}) + "(" +
               Leaf() + "/(4 + " + Positive(d) + "))";
      case 13:
        return "atan2(" + Positive(d) + ", " + Positive(d) + ")";
      case 14:
        return Fn({"min", "max", "sum", "avg"}) + "(" + Positive(d) + ", " + Leaf() + ", " +
               Positive(d) + ")";
      case 15:
        return "acosh(1 + " + Positive(d) + ")";
      case 16:
        return "sign(" + Negative(d) + ")*" + Paren(d) + "*-1";
      case 17:
        return "rint(" + Positive(d) + ") + " + Leaf();
      case 18:
        return "abs(" + Negative(d) + ")";
      case 19:
        return "+" + Leaf() + "*" + Positive(d);
      case 20:
        return Negative(d) + "*" + Negative(d);
      default:
        return Paren(d);
    }
  }

  std::string Negative(int depth) {
    switch (Pick(3)) {
      case 0:
        return "-" + Paren(depth - 1);
      case 1:
        return "-" + Leaf() + "^2";  // -(x^2).
      default:
        return "(-" + Leaf() + ")*" + Leaf();
    }
  }

 private:
  int Pick(int n) { return std::uniform_int_distribution<int>(0, n - 1)(rng_); }

  std::string Paren(int depth) { return "(" + Positive(std::max(depth, 0)) + ")"; }

  std::string Fn(const std::vector<const char*>& names) {
    return names[static_cast<size_t>(Pick(static_cast<int>(names.size())))];
  }

  std::string Leaf(const char* input = nullptr) {
    if (input != nullptr) return input;
    static const std::vector<const char*> kLeaves = {"a",       "b",   "c",   "a",    "b",
                                                     "c",       "2",   "0.5", "1.25", "3e0",
                                                     "12.5e-1", ".75", "pi",  "_pi",  "_e"};
    return kLeaves[static_cast<size_t>(Pick(static_cast<int>(kLeaves.size())))];
  }

  std::string Exponent() {
    static const std::vector<const char*> kExponents = {"2",   "3", "0.5", "-1",     "-0.5",
                                                        "1.5", "a", "-b",  "(c - 1)"};
    return kExponents[static_cast<size_t>(Pick(static_cast<int>(kExponents.size())))];
  }

  std::mt19937_64 rng_;
};

TEST_CASE("Random expressions of the grammar: the tree and GiNaC agree with muparser",
          "[uncertainty][grammar]") {
  Generator generator(20261202);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> input(1.0, 2.0);
  const std::vector<std::optional<PhysicalUnit>> units(3, PhysicalUnit::One());
  int compared = 0, symbolic = 0;
  for (int trial = 0; trial < 600; ++trial) {
    const std::string model = generator.Positive(1 + trial % 4);
    INFO(model);
    auto muparser = MeasurementModel::FromExpression(model, kNames);
    REQUIRE(muparser.ok());
    auto syntax = ParseModel(model, kNames);
    REQUIRE(syntax.ok());
    for (int point = 0; point < 2; ++point) {
      const std::vector<double> x = {input(rng), input(rng), input(rng)};
      INFO("a = " << x[0] << ", b = " << x[1] << ", c = " << x[2]);
      const double want = muparser.value().Evaluate(x.data());
      if (!std::isfinite(want) || want == 0.0) continue;
      ++compared;
      CHECK(std::fabs(EvaluateModel(syntax.value(), x.data()) - want) <= 1e-12 * std::fabs(want));
      // The unit check reads the same tree (and refuses a value unlike muparser's).
      CHECK(CheckModelUnits(model, kNames, units, x, want).ok());
      // GiNaC's expression, its pieces chosen at this point; beyond its length or power limits
      // it is not built.
      auto exact = SymbolicModel::Parse(model, kNames, x.data());
      if (!exact.ok()) {
        const std::string& why = exact.error().message;
        CHECK((why.find("longer than") != std::string::npos ||
               why.find("more than 32 powers") != std::string::npos ||
               why.find("deeper than 32") != std::string::npos));
        continue;
      }
      auto value = exact.value().Value(x.data());
      REQUIRE(value.ok());
      ++symbolic;
      CHECK(std::fabs(value.value() - want) <= 1e-12 * std::fabs(want));
    }
  }
  // Nearly every sample is finite and short enough for GiNaC.
  CHECK(compared >= 1100);
  CHECK(symbolic >= 1000);
}

TEST_CASE("A model spanning lines reads alike in muparser, the unit check and GiNaC",
          "[uncertainty][grammar]") {
  // The unit check's own reader stopped at a newline ("unexpected '\n'") that muparser and
  // the exact derivatives skipped; one reader skips what muparser skips.
  const std::string model = "2*a*\n\tb +\r\n c";
  const std::vector<double> x = {1.5, 2.0, 0.25};
  const std::vector<std::optional<PhysicalUnit>> units = {PhysicalUnit::Parse("m").value(),
                                                          PhysicalUnit::Parse("1").value(),
                                                          PhysicalUnit::Parse("m").value()};
  auto muparser = MeasurementModel::FromExpression(model, kNames);
  REQUIRE(muparser.ok());
  CHECK(muparser.value().Evaluate(x.data()) == 6.25);
  auto checked = CheckModelUnits(model, kNames, units, x, 6.25);
  REQUIRE(checked.ok());
  CHECK(checked.value().unit.SameAs(PhysicalUnit::Parse("m").value()));
  auto exact = SymbolicModel::Parse(model, kNames, x.data());
  REQUIRE(exact.ok());
  CHECK(exact.value().First(1, x.data()).value() == 3.0);  // d/db = 2a.
}

TEST_CASE("_pi is pi in muparser too, as the grammar reads it (issue #36)",
          "[uncertainty][grammar]") {
  // muparser 2.3.3 built with GCC defines _pi as 3.141592653589; metro defines it as pi, so
  // 2*_pi*f at f = 1e7 Hz is 2 pi 1e7 rad/s (it was 1.6e-5 rad/s low: 2.5 u for u(f) = 1 uHz).
  const double f = 1e7;
  auto model = MeasurementModel::FromExpression("2*_pi*a", kNames);
  REQUIRE(model.ok());
  const std::vector<double> x = {f, 0.0, 0.0};
  CHECK(model.value().Evaluate(x.data()) == 2.0 * M_PI * f);
  auto same = MeasurementModel::FromExpression("_pi - pi", kNames);
  REQUIRE(same.ok());
  CHECK(same.value().Evaluate(x.data()) == 0.0);
}

TEST_CASE("asinh, acosh and atanh are the C library's in muparser too, as the grammar reads them",
          "[uncertainty][grammar]") {
  // muparser 2.3.3 computes them as logarithms: asinh(1e-10) and atanh(1e-10) were 8.3e-8 high,
  // asinh(-1e8) and acosh(1e155) infinite; the exact derivatives' values are the C library's.
  for (const auto& [model, a] : std::vector<std::pair<std::string, double>>{
           {"asinh(a)", 1e-10}, {"asinh(a)", -1e8}, {"atanh(a)", 1e-10}, {"acosh(a)", 1e155}}) {
    INFO(model << " at a = " << a);
    auto m = MeasurementModel::FromExpression(model, kNames);
    REQUIRE(m.ok());
    const std::vector<double> x = {a, 0.0, 0.0};
    const double want = model[1] == 's'   ? std::asinh(a)
                        : model[1] == 't' ? std::atanh(a)
                                          : std::acosh(a);
    CHECK(m.value().Evaluate(x.data()) == want);
    if (a > 1e100) continue;  // GiNaC's double-float arithmetic overflows there.
    auto exact = SymbolicModel::Parse(model, kNames, x.data());
    REQUIRE(exact.ok());
    auto value = exact.value().Value(x.data());
    REQUIRE(value.ok());
    CHECK(value.value() == Approx(want).epsilon(1e-15));
  }
}

TEST_CASE("rint is muparser's, halves rounded up, in the tree, the unit check and GiNaC",
          "[uncertainty][grammar]") {
  // muparser's rint(x) is floor(x + 0.5): rint(2.5) = 3, rint(-2.5) = -2, rint(0.5) = 1 (the C
  // library's rint gives 2, -2, 0).
  const std::vector<std::pair<std::string, double>> cases = {
      {"a*rint(2.5)", 3.0}, {"a*rint(-2.5)", -2.0}, {"a*rint(0.5)", 1.0}, {"a*rint(1.4)", 1.0}};
  const std::vector<double> x = {1.5, 1.0, 1.0};
  const std::vector<std::optional<PhysicalUnit>> units(3, PhysicalUnit::Parse("m").value());
  for (const auto& [model, factor] : cases) {
    INFO(model);
    auto muparser = MeasurementModel::FromExpression(model, kNames);
    REQUIRE(muparser.ok());
    CHECK(muparser.value().Evaluate(x.data()) == 1.5 * factor);
    auto syntax = ParseModel(model, kNames);
    REQUIRE(syntax.ok());
    CHECK(EvaluateModel(syntax.value(), x.data()) == 1.5 * factor);
    CHECK(CheckModelUnits(model, kNames, units, x, 1.5 * factor).ok());
    auto exact = SymbolicModel::Parse(model, kNames, x.data());
    REQUIRE(exact.ok());
    CHECK(exact.value().Value(x.data()).value() == 1.5 * factor);
    CHECK(exact.value().First(0, x.data()).value() == factor);
  }
}

}  // namespace
}  // namespace internal
}  // namespace metro
