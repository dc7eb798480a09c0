#include "uncertainty/model_units.hpp"

#include <fmt/format.h>

#include <cmath>
#include <cstdlib>
#include <functional>
#include <utility>

#include "metro/core/terminal_text.hpp"

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

class Checker {
 public:
  Checker(const std::string& expression, const std::vector<std::string>& names,
          const std::vector<std::optional<PhysicalUnit>>& units, const std::vector<double>& values)
      : text_(expression), names_(names), units_(units), values_(values) {}

  Result<Term> Run() {
    auto t = Ternary();
    if (!t.ok()) return t;
    SkipSpace();
    if (pos_ != text_.size()) return Fail(pos_, "unexpected '" + text_.substr(pos_, 1) + "'");
    return t;
  }

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

  void SkipSpace() {
    while (pos_ < text_.size() && (text_[pos_] == ' ' || text_[pos_] == '\t')) ++pos_;
  }

  bool Accept(const char* op) {
    SkipSpace();
    const size_t n = std::char_traits<char>::length(op);
    if (text_.compare(pos_, n, op) != 0) return false;
    pos_ += n;
    return true;
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
  // cannot exhaust the stack.
  class Depth {
   public:
    explicit Depth(int* depth) : depth_(depth) { ++*depth_; }
    ~Depth() { --*depth_; }
    Depth(const Depth&) = delete;
    Depth& operator=(const Depth&) = delete;

   private:
    int* depth_;
  };
  static constexpr int kMaxDepth = 256;

  Result<Term> Ternary() {
    const Depth guard(&depth_);
    if (depth_ > kMaxDepth)
      return Fail(pos_, "nested too deeply (parentheses, arguments and signs beyond 256 levels)");
    auto c = LogicOr();
    if (!c.ok()) return c;
    SkipSpace();
    const size_t at = pos_;
    if (!Accept("?")) return c;
    auto a = Ternary();
    if (!a.ok()) return a;
    if (!Accept(":")) return Fail(pos_, "expected ':' of '?'");
    auto b = Ternary();
    if (!b.ok()) return b;
    auto r = Same(a.value(), b.value(), at, "the branches of ?:");
    if (!r.ok()) return r;
    Term t = r.value();
    t.value = c.value().value != 0.0 ? a.value().value : b.value().value;
    t.begin = c.value().begin;
    return t;
  }

  // a op b with a dimensionless 0/1 result; ops that compare need one unit.
  Result<Term> Binary(std::function<Result<Term>()> next,
                      const std::vector<std::pair<const char*, int>>& ops, bool compare) {
    auto left = next();
    if (!left.ok()) return left;
    Term a = left.value();
    for (;;) {
      SkipSpace();
      const size_t at = pos_;
      int op = -1;
      for (const auto& [text, code] : ops) {
        // '<' must not take the '<' of '<='; '&' / '|' never appear alone.
        if (text_.compare(pos_, std::char_traits<char>::length(text), text) == 0) {
          op = code;
          pos_ += std::char_traits<char>::length(text);
          break;
        }
      }
      if (op < 0) return a;
      auto right = next();
      if (!right.ok()) return right;
      const Term& b = right.value();
      Term r;
      if (compare) {
        auto same = Same(a, b, at, "a comparison");
        if (!same.ok()) return same;
      }
      r.kind =
          a.kind == Kind::kConstant && b.kind == Kind::kConstant ? Kind::kConstant : Kind::kExact;
      r.begin = a.begin;
      r.end = b.end;
      switch (op) {
        case 0:
          r.value = (a.value != 0.0) || (b.value != 0.0);
          break;
        case 1:
          r.value = (a.value != 0.0) && (b.value != 0.0);
          break;
        case 2:
          r.value = a.value == b.value;
          break;
        case 3:
          r.value = a.value != b.value;
          break;
        case 4:
          r.value = a.value <= b.value;
          break;
        case 5:
          r.value = a.value >= b.value;
          break;
        case 6:
          r.value = a.value < b.value;
          break;
        default:
          r.value = a.value > b.value;
          break;
      }
      a = r;
    }
  }

  Result<Term> LogicOr() {
    return Binary([this] { return LogicAnd(); }, {{"||", 0}}, false);
  }
  Result<Term> LogicAnd() {
    return Binary([this] { return Compare(); }, {{"&&", 1}}, false);
  }
  Result<Term> Compare() {
    return Binary([this] { return Additive(); },
                  {{"==", 2}, {"!=", 3}, {"<=", 4}, {">=", 5}, {"<", 6}, {">", 7}}, true);
  }

  Result<Term> Additive() {
    auto left = Multiplicative();
    if (!left.ok()) return left;
    Term a = left.value();
    for (;;) {
      SkipSpace();
      const size_t at = pos_;
      if (pos_ >= text_.size() || (text_[pos_] != '+' && text_[pos_] != '-')) return a;
      const bool plus = text_[pos_++] == '+';
      auto right = Multiplicative();
      if (!right.ok()) return right;
      auto r = Same(a, right.value(), at, plus ? "a sum" : "a difference");
      if (!r.ok()) return r;
      const double v = plus ? a.value + right.value().value : a.value - right.value().value;
      a = r.value();
      a.value = v;
    }
  }

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

  Result<Term> Multiplicative() {
    auto left = Unary();
    if (!left.ok()) return left;
    Term a = left.value();
    for (;;) {
      SkipSpace();
      const size_t at = pos_;
      if (pos_ >= text_.size() || (text_[pos_] != '*' && text_[pos_] != '/')) return a;
      const bool divide = text_[pos_++] == '/';
      auto right = Unary();
      if (!right.ok()) return right;
      auto product = Product(a, right.value(), divide, at);
      if (!product.ok()) return product;
      a = product.value();
    }
  }

  // Signs bind less tightly than ^ (muparser: -2^2 = -4).
  Result<Term> Unary() {
    const Depth guard(&depth_);
    if (depth_ > kMaxDepth)
      return Fail(pos_, "nested too deeply (parentheses, arguments and signs beyond 256 levels)");
    SkipSpace();
    const size_t at = pos_;
    if (pos_ < text_.size() && (text_[pos_] == '-' || text_[pos_] == '+')) {
      const bool minus = text_[pos_++] == '-';
      auto t = Unary();
      if (!t.ok()) return t;
      Term r = t.value();
      r.begin = at;
      if (minus) r.value = -r.value;
      return r;
    }
    return Power();
  }

  Result<Term> Power() {
    auto base = Primary();
    if (!base.ok()) return base;
    SkipSpace();
    const size_t at = pos_;
    if (!Accept("^")) return base;
    auto exponent = Unary();  // Right-associative: 2^3^2 = 2^9; 2^-1 is allowed.
    if (!exponent.ok()) return exponent;
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

  Result<Term> Number() {
    const size_t at = pos_;
    const char* start = text_.c_str() + pos_;
    char* stop = nullptr;
    const double v = std::strtod(start, &stop);
    if (stop == start) return Fail(at, "expected a number");
    pos_ += static_cast<size_t>(stop - start);
    Term t;
    t.value = v;
    t.begin = at;
    t.end = pos_;
    return t;
  }

  Result<Term> Call(const std::string& name, size_t at) {
    std::vector<Term> args;
    SkipSpace();
    if (!Accept(")")) {
      for (;;) {
        auto a = Ternary();
        if (!a.ok()) return a;
        args.push_back(a.value());
        if (Accept(",")) continue;
        if (Accept(")")) break;
        return Fail(pos_, "expected ',' or ')' in the arguments of " + name + "()");
      }
    }
    Term r;
    r.begin = at;
    r.end = pos_;
    const auto arity = [&](size_t n) -> Status {
      if (args.size() == n) return Status();
      return Fail(at, fmt::format("{}() takes {} argument{}", name, n, n == 1 ? "" : "s"));
    };
    const auto constant_args = [&] {
      for (const Term& a : args) {
        if (a.kind != Kind::kConstant) return false;
      }
      return true;
    };
    using F = double (*)(double);
    static const std::vector<std::pair<std::string, F>> kNumberFunctions = {
        {"sin", [](double x) { return std::sin(x); }},
        {"cos", [](double x) { return std::cos(x); }},
        {"tan", [](double x) { return std::tan(x); }},
        {"asin", [](double x) { return std::asin(x); }},
        {"acos", [](double x) { return std::acos(x); }},
        {"atan", [](double x) { return std::atan(x); }},
        {"sinh", [](double x) { return std::sinh(x); }},
        {"cosh", [](double x) { return std::cosh(x); }},
        {"tanh", [](double x) { return std::tanh(x); }},
        {"asinh", [](double x) { return std::asinh(x); }},
        {"acosh", [](double x) { return std::acosh(x); }},
        {"atanh", [](double x) { return std::atanh(x); }},
        {"exp", [](double x) { return std::exp(x); }},
        {"ln", [](double x) { return std::log(x); }},
        {"log", [](double x) { return std::log(x); }},  // muparser: log is ln.
        {"log10", [](double x) { return std::log10(x); }},
        {"log2", [](double x) { return std::log2(x); }},
    };
    for (const auto& [fname, f] : kNumberFunctions) {
      if (fname != name) continue;
      if (Status s = arity(1); !s.ok()) return s.error();
      if (Status s = NeedNumber(args[0], at, name); !s.ok()) return s.error();
      r.value = f(args[0].value);
      r.kind = constant_args() ? Kind::kConstant : Kind::kExact;
      return r;  // 1 (asin/acos/atan: rad, the same unit).
    }
    if (name == "sqrt" || name == "abs" || name == "rint" || name == "sign") {
      if (Status s = arity(1); !s.ok()) return s.error();
      const Term& a = args[0];
      r.kind = a.kind;
      r.unit = a.unit;
      if (name == "sqrt") {
        r.value = std::sqrt(a.value);
        if (a.kind != Kind::kConstant) {
          auto root = a.unit.Root(2);
          if (!root.ok()) {
            return Fail(at, fmt::format("sqrt() of {}: {}", Describe(a), root.error().message));
          }
          r.unit = root.value();
        }
      } else if (name == "abs") {
        r.value = std::fabs(a.value);
      } else if (name == "rint") {
        r.value = std::rint(a.value);
      } else {
        r.value = a.value > 0.0 ? 1.0 : a.value < 0.0 ? -1.0 : 0.0;
        r.unit = PhysicalUnit::One();
        if (a.kind != Kind::kConstant) r.kind = Kind::kExact;
      }
      return r;
    }
    if (name == "min" || name == "max" || name == "sum" || name == "avg" || name == "atan2") {
      if (name == "atan2") {
        if (Status s = arity(2); !s.ok()) return s.error();
      } else if (args.empty()) {
        return Fail(at, name + "() needs at least one argument");
      }
      Term acc = args[0];
      for (size_t i = 1; i < args.size(); ++i) {
        auto same = Same(acc, args[i], at, "the arguments of " + name + "()");
        if (!same.ok()) return same;
        acc.kind = same.value().kind;
        acc.unit = same.value().unit;
      }
      r.kind = acc.kind;
      r.unit = acc.unit;
      double v = args[0].value;
      for (size_t i = 1; i < args.size(); ++i) {
        const double x = args[i].value;
        if (name == "min") v = std::fmin(v, x);
        if (name == "max") v = std::fmax(v, x);
        if (name == "sum" || name == "avg") v += x;
      }
      if (name == "avg") v /= static_cast<double>(args.size());
      if (name == "atan2") {
        v = std::atan2(args[0].value, args[1].value);
        r.unit = PhysicalUnit::One();
        if (r.kind != Kind::kConstant) r.kind = Kind::kExact;
      }
      r.value = v;
      return r;
    }
    return Fail(at, "function '" + name + "' has no unit rule");
  }

  Result<Term> Primary() {
    SkipSpace();
    const size_t at = pos_;
    if (pos_ >= text_.size()) return Fail(at, "unexpected end of the model");
    const char c = text_[pos_];
    if (c == '(') {
      ++pos_;
      auto t = Ternary();
      if (!t.ok()) return t;
      if (!Accept(")")) return Fail(pos_, "expected ')'");
      Term r = t.value();
      r.begin = at;
      r.end = pos_;
      return r;
    }
    if ((c >= '0' && c <= '9') || c == '.') return Number();
    const auto name_char = [](char x) {
      return (x >= 'a' && x <= 'z') || (x >= 'A' && x <= 'Z') || (x >= '0' && x <= '9') || x == '_';
    };
    if (!name_char(c)) return Fail(at, "unexpected '" + std::string(1, c) + "'");
    size_t end = pos_;
    while (end < text_.size() && name_char(text_[end])) ++end;
    const std::string name = text_.substr(pos_, end - pos_);
    pos_ = end;
    SkipSpace();
    if (pos_ < text_.size() && text_[pos_] == '(') {
      ++pos_;
      return Call(name, at);
    }
    Term t;
    t.begin = at;
    t.end = end;
    for (size_t i = 0; i < names_.size(); ++i) {
      if (names_[i] != name) continue;
      if (!units_[i]) {
        return MakeError("input '" + name +
                         "' states no unit, while other quantities of the budget do; every input "
                         "of the model needs one (\"1\" for a pure number)");
      }
      t.kind = Kind::kExact;
      t.unit = *units_[i];
      t.value = values_[i];
      return t;
    }
    if (name == "pi" || name == "_pi") {
      t.value = 3.14159265358979323846;
      return t;
    }
    if (name == "_e") {
      t.value = 2.71828182845904523536;
      return t;
    }
    return Fail(at, "'" + name + "' is not an input");
  }

  const std::string& text_;
  const std::vector<std::string>& names_;
  const std::vector<std::optional<PhysicalUnit>>& units_;
  const std::vector<double>& values_;
  size_t pos_ = 0;
  int depth_ = 0;
};

}  // namespace

Result<ModelUnit> CheckModelUnits(const std::string& expression,
                                  const std::vector<std::string>& names,
                                  const std::vector<std::optional<PhysicalUnit>>& units,
                                  const std::vector<double>& values, double muparser_value) {
  Checker checker(expression, names, units, values);
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
