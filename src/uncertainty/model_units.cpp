#include "uncertainty/model_units.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <utility>

#include "metro/core/terminal_text.hpp"
#include "uncertainty/model_grammar.hpp"

namespace metro {
namespace internal {
namespace {

enum class Kind {
  kConstant,   // A bare number (or an expression of numbers only): takes the unit required.
  kExact,      // Unit known, scale included.
  kScaleFree,  // Dimension known; a constant factor may have converted the scale.
};

struct Term {
  Kind kind = Kind::kConstant;
  PhysicalUnit unit = PhysicalUnit::One();
  double value = 0.0;  // At the input estimates.
  size_t begin = 0;    // The term's text in the expression: [begin, end).
  size_t end = 0;
};

std::string Significant(double x) { return fmt::format("{:.6g}", x); }

// Gives each node of the model's syntax tree (model_grammar.hpp) a unit and its value at the
// estimates, children first, left to right.
class Checker {
 public:
  Checker(const std::string& expression, const ModelSyntax& syntax,
          const std::vector<std::string>& names,
          const std::vector<std::optional<PhysicalUnit>>& units, const std::vector<double>& values)
      : text_(expression), syntax_(syntax), names_(names), units_(units), values_(values) {}

  Result<Term> Run() { return Walk(syntax_.root()); }

 private:
  Error Fail(size_t at, const std::string& what) const {
    // The model is quoted by the caller (once, cut around the column): model.hpp, "Errors".
    Error e = MakeError(fmt::format("column {}: {}", at + 1, what));
    e.column = static_cast<int64_t>(at) + 1;
    return e;
  }

  std::string Quote(const Term& t) const {
    std::string s = text_.substr(t.begin, t.end - t.begin);
    const auto first = s.find_first_not_of(' ');
    const auto last = s.find_last_not_of(' ');
    // A long term is cut (the message stays one short line).
    return "'" +
           Excerpt(first == std::string::npos ? s : s.substr(first, last - first + 1), 0, 60) + "'";
  }

  std::string Describe(const Term& t) const {
    return Quote(t) + " (" + t.unit.ToString() +
           (t.kind == Kind::kScaleFree ? " up to a factor" : "") + ")";
  }

  // Terms that must share one unit: a sum, a comparison, min/max/sum/avg/atan2, ?: branches.
  Result<Term> Same(const Term& a, const Term& b, size_t at, const std::string& what) const {
    Term r;
    r.begin = std::min(a.begin, b.begin);
    r.end = std::max(a.end, b.end);
    if (a.kind == Kind::kConstant && b.kind == Kind::kConstant) return r;
    if (a.kind == Kind::kConstant || b.kind == Kind::kConstant) {
      const Term& x = a.kind == Kind::kConstant ? b : a;
      r.kind = x.kind;
      r.unit = x.unit;
      return r;
    }
    const std::optional<UnitConversion> c = a.unit.ConversionTo(b.unit);
    if (!c) {
      return Fail(at, fmt::format("{}: incompatible dimensions, {} and {}", what, Describe(a),
                                  Describe(b)));
    }
    if (a.kind == Kind::kExact && b.kind == Kind::kExact && !c->IsIdentity()) {
      return Fail(at, fmt::format("{}: {} and {} are in different units (1 {} = {} {}{}); "
                                  "declare the inputs in one unit or convert with a factor",
                                  what, Describe(a), Describe(b), a.unit.ToString(),
                                  Significant(c->factor), b.unit.ToString(),
                                  c->offset != 0.0 ? " + " + Significant(c->offset) : ""));
    }
    const Term& exact = a.kind == Kind::kExact ? a : b;
    r.kind = exact.kind;
    r.unit = exact.unit;
    return r;
  }

  // A function argument that must be a number (1) or, for sin/cos/tan, an angle in rad
  // (the same unit as 1).
  Status NeedNumber(const Term& arg, size_t at, const std::string& function) const {
    if (arg.kind == Kind::kConstant) return Status();
    if (!arg.unit.IsDimensionless()) {
      return Fail(
          at, fmt::format("{}() needs a dimensionless argument, got {}", function, Describe(arg)));
    }
    if (arg.kind == Kind::kExact && !arg.unit.SameAs(PhysicalUnit::One())) {
      const bool trig = function == "sin" || function == "cos" || function == "tan";
      const double factor = arg.unit.ConversionTo(PhysicalUnit::One())->factor;
      return Fail(at, fmt::format("{}() takes {}, got {} (1 {} = {} {}){}", function,
                                  trig ? "radians" : "a number (unit 1)", Describe(arg),
                                  arg.unit.ToString(), Significant(factor), trig ? "rad" : "(1)",
                                  trig ? "; multiply by pi/180 or declare the input in rad" : ""));
    }
    return Status();
  }

  // Nesting (parentheses, arguments, signs, exponents) is bounded so that a hostile model

  Result<Term> Product(const Term& a, const Term& b, bool divide, size_t at) const {
    Term r;
    r.begin = a.begin;
    r.end = b.end;
    r.value = divide ? a.value / b.value : a.value * b.value;
    if (a.kind == Kind::kConstant && b.kind == Kind::kConstant) return r;
    const PhysicalUnit one = PhysicalUnit::One();
    if (b.unit.SameAs(one)) {
      r.unit = a.unit;  // Keeps the unit's own name (cm, not 0.01 m).
    } else if (!divide && a.unit.SameAs(one)) {
      r.unit = b.unit;
    } else {
      auto unit = divide ? a.unit.Divide(b.unit) : a.unit.Multiply(b.unit);
      if (!unit.ok()) return Fail(at, unit.error().message);
      r.unit = unit.value();
    }
    // A constant 1 (1/x, 1*x) converts nothing; any other constant factor may.
    const auto exact = [](const Term& t) {
      return t.kind == Kind::kExact || (t.kind == Kind::kConstant && std::fabs(t.value) == 1.0);
    };
    r.kind = exact(a) && exact(b) ? Kind::kExact : Kind::kScaleFree;
    return r;
  }

  // A term's text is its node's, parentheses included.
  Result<Term> Walk(size_t n) {
    const ModelNode& node = syntax_.nodes[n];
    Result<Term> t = Unit(node);
    if (!t.ok()) return t;
    Term r = t.value();
    r.begin = node.begin;
    r.end = node.end;
    return r;
  }

  Result<Term> Unit(const ModelNode& node) {
    Term t;
    switch (node.kind) {
      case ModelNode::Kind::kNumber:
        t.value = node.number;
        return t;
      case ModelNode::Kind::kInput:
        if (!units_[node.input]) {
          return MakeError("input '" + names_[node.input] +
                           "' states no unit, while other quantities of the budget do; every "
                           "input of the model needs one (\"1\" for a pure number)");
        }
        t.kind = Kind::kExact;
        t.unit = *units_[node.input];
        t.value = values_[node.input];
        return t;
      case ModelNode::Kind::kPi:
        t.value = kModelPi;
        return t;
      case ModelNode::Kind::kE:
        t.value = kModelE;
        return t;
      case ModelNode::Kind::kSign: {
        auto operand = Walk(node.children[0]);
        if (!operand.ok()) return operand;
        t = operand.value();
        if (node.negative) t.value = -t.value;
        return t;
      }
      case ModelNode::Kind::kPower:
        return Power(node);
      case ModelNode::Kind::kChain:
        return Chain(node);
      case ModelNode::Kind::kIf: {
        auto c = Walk(node.children[0]);
        if (!c.ok()) return c;
        auto a = Walk(node.children[1]);
        if (!a.ok()) return a;
        auto b = Walk(node.children[2]);
        if (!b.ok()) return b;
        auto r = Same(a.value(), b.value(), node.at, "the branches of ?:");
        if (!r.ok()) return r;
        t = r.value();
        t.value = c.value().value != 0.0 ? a.value().value : b.value().value;
        return t;
      }
      case ModelNode::Kind::kCall:
        return Call(node);
    }
    return t;
  }

  // + - need one unit, * / multiply units, comparisons need one unit and give a 0/1 number,
  // as do && and ||.
  Result<Term> Chain(const ModelNode& node) {
    auto left = Walk(node.children[0]);
    if (!left.ok()) return left;
    Term a = left.value();
    for (size_t k = 0; k < node.ops.size(); ++k) {
      const ModelOperator op = node.ops[k];
      const size_t at = node.op_at[k];
      auto right = Walk(node.children[k + 1]);
      if (!right.ok()) return right;
      const Term& b = right.value();
      const double v = ApplyOperator(op, a.value, b.value);
      if (op == ModelOperator::kAdd || op == ModelOperator::kSubtract) {
        auto r = Same(a, b, at, op == ModelOperator::kAdd ? "a sum" : "a difference");
        if (!r.ok()) return r;
        a = r.value();
        a.value = v;
        continue;
      }
      if (op == ModelOperator::kMultiply || op == ModelOperator::kDivide) {
        auto r = Product(a, b, op == ModelOperator::kDivide, at);
        if (!r.ok()) return r;
        a = r.value();
        continue;
      }
      if (op != ModelOperator::kOr && op != ModelOperator::kAnd) {
        auto same = Same(a, b, at, "a comparison");
        if (!same.ok()) return same;
      }
      Term r;
      r.kind =
          a.kind == Kind::kConstant && b.kind == Kind::kConstant ? Kind::kConstant : Kind::kExact;
      r.begin = a.begin;
      r.end = b.end;
      r.value = v;
      a = r;
    }
    return a;
  }

  Result<Term> Power(const ModelNode& node) {
    auto base = Walk(node.children[0]);
    if (!base.ok()) return base;
    auto exponent = Walk(node.children[1]);
    if (!exponent.ok()) return exponent;
    const size_t at = node.at;
    const Term& a = base.value();
    const Term& p = exponent.value();
    Term r;
    r.begin = a.begin;
    r.end = p.end;
    r.value = std::pow(a.value, p.value);
    if (a.kind == Kind::kConstant && p.kind == Kind::kConstant) return r;
    if (p.kind != Kind::kConstant) {
      if (Status s = NeedNumber(p, at, "the exponent of ^"); !s.ok()) return s.error();
      if (a.kind != Kind::kConstant && !a.unit.IsDimensionless()) {
        return Fail(at, fmt::format("{} is raised to the power {}, which is not a constant: the "
                                    "unit of the result would vary",
                                    Describe(a), Quote(p)));
      }
      // A number to a number's power is a number; a scaled one (%, deg) loses its scale.
      r.kind = a.kind == Kind::kConstant ||
                       (a.kind == Kind::kExact && a.unit.SameAs(PhysicalUnit::One()))
                   ? Kind::kExact
                   : Kind::kScaleFree;
      return r;
    }
    // A constant exponent m/k with a small k: unit^m, then the k'th root.
    r.kind = a.kind;
    for (int k = 1; k <= 8; ++k) {
      const double m = p.value * k;
      if (std::fabs(m - std::round(m)) > 1e-9 || std::fabs(m) > 255.0) continue;
      auto raised = a.unit.Raise(static_cast<int>(std::lround(m)));
      if (!raised.ok()) break;
      auto rooted = raised.value().Root(k);
      if (!rooted.ok()) {
        return Fail(at, fmt::format("{} cannot be raised to the power {}: {}", Describe(a),
                                    Significant(p.value), rooted.error().message));
      }
      r.unit = rooted.value();
      return r;
    }
    if (a.unit.SameAs(PhysicalUnit::One())) return r;
    return Fail(at, fmt::format("{} is raised to the power {}: a unit takes integer or 1/k "
                                "powers only",
                                Describe(a), Significant(p.value)));
  }

  Result<Term> Call(const ModelNode& node) {
    std::vector<Term> args;
    std::vector<double> values;
    bool constant_args = true;
    for (size_t k : node.children) {
      auto a = Walk(k);
      if (!a.ok()) return a;
      args.push_back(a.value());
      values.push_back(a.value().value);
      constant_args = constant_args && a.value().kind == Kind::kConstant;
    }
    const std::string& name = node.text;
    const size_t at = node.at;
    Term r;
    r.value = ApplyFunction(node.function, values);
    const Term& a = args[0];
    switch (node.function) {
      case ModelFunction::kSqrt:
        r.kind = a.kind;
        r.unit = a.unit;
        if (a.kind != Kind::kConstant) {
          auto root = a.unit.Root(2);
          if (!root.ok()) {
            return Fail(at, fmt::format("sqrt() of {}: {}", Describe(a), root.error().message));
          }
          r.unit = root.value();
        }
        return r;
      case ModelFunction::kAbs:
      case ModelFunction::kRint:
        r.kind = a.kind;
        r.unit = a.unit;
        return r;
      case ModelFunction::kSign:
        r.kind = a.kind == Kind::kConstant ? Kind::kConstant : Kind::kExact;
        return r;
      case ModelFunction::kMin:
      case ModelFunction::kMax:
      case ModelFunction::kSum:
      case ModelFunction::kAvg:
      case ModelFunction::kAtan2: {
        Term acc = a;
        for (size_t i = 1; i < args.size(); ++i) {
          auto same = Same(acc, args[i], at, "the arguments of " + name + "()");
          if (!same.ok()) return same;
          acc.kind = same.value().kind;
          acc.unit = same.value().unit;
        }
        r.kind = acc.kind;
        r.unit = acc.unit;
        if (node.function == ModelFunction::kAtan2) {
          r.unit = PhysicalUnit::One();
          if (r.kind != Kind::kConstant) r.kind = Kind::kExact;
        }
        return r;
      }
      default:  // sin ... log2 take a number and give 1 (asin/acos/atan: rad, the same unit).
        if (Status s = NeedNumber(a, at, name); !s.ok()) return s.error();
        r.kind = constant_args ? Kind::kConstant : Kind::kExact;
        return r;
    }
  }

  const std::string& text_;
  const ModelSyntax& syntax_;
  const std::vector<std::string>& names_;
  const std::vector<std::optional<PhysicalUnit>>& units_;
  const std::vector<double>& values_;
};

}  // namespace

Result<ModelUnit> CheckModelUnits(const std::string& expression,
                                  const std::vector<std::string>& names,
                                  const std::vector<std::optional<PhysicalUnit>>& units,
                                  const std::vector<double>& values, double muparser_value) {
  Result<ModelSyntax> syntax = ParseModel(expression, names);
  if (!syntax.ok()) return syntax.error();
  Checker checker(expression, syntax.value(), names, units, values);
  auto term = checker.Run();
  if (!term.ok()) return term.error();
  const Term& t = term.value();
  // The same tree as muparser's, or the check proves nothing.
  const double mine = t.value;
  if (std::isfinite(mine) && std::isfinite(muparser_value) &&
      std::fabs(mine - muparser_value) >
          1e-9 * std::fmax(1.0, std::fmax(std::fabs(mine), std::fabs(muparser_value)))) {
    return MakeError(
        fmt::format("the unit check reads it as {} at the estimates but muparser as {}; "
                    "parenthesise the model so that both read it alike",
                    Significant(mine), Significant(muparser_value)));
  }
  ModelUnit result;
  result.constant = t.kind == Kind::kConstant;
  result.scale_known = t.kind == Kind::kExact;
  result.unit = t.unit;
  return result;
}

}  // namespace internal
}  // namespace metro
