#include "uncertainty/symbolic_model.hpp"

#include <fmt/format.h>
#include <ginac/ginac.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <exception>
#include <map>
#include <mutex>
#include <stdexcept>

#include "uncertainty/model_grammar.hpp"

namespace metro {
namespace internal {
namespace {

// GiNaC shares reference-counted expression nodes between copies without atomics, and Digits
// is a global: one lock for every use in the process.
std::mutex& GinacMutex() {
  static std::mutex mutex;
  return mutex;
}

// Longer or deeper expressions are refused rather than risk GiNaC's recursion on
// adversarial input (the budget fuzzer's nesting).
// A measurement model is a line (GUM H.1's is 60 characters); towers of powers are what
// makes repeated differentiation slow, so they are bounded too.
constexpr size_t kMaxExpressionLength = 1000;
constexpr int kMaxNesting = 32;
constexpr int kMaxPowers = 32;
constexpr size_t kMaxNodes = 200000;

// 30 significant digits while the guard lives, GiNaC's previous precision again after it.
struct Precision {
  long saved = GiNaC::Digits;
  Precision() { GiNaC::Digits = 30; }
  ~Precision() { GiNaC::Digits = saved; }
  Precision(const Precision&) = delete;
  Precision& operator=(const Precision&) = delete;
};

// Why a model has no exact derivative here (caught in Parse and turned into its Error).
struct NotExact : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// The GiNaC expression of a model's syntax tree (model_grammar.hpp), with the pieces of
// piecewise functions chosen at x0. Nodes are read children first, left to right.
class Builder {
 public:
  Builder(const ModelSyntax& syntax, const std::vector<GiNaC::symbol>& symbols, const double* x0)
      : syntax_(syntax), symbols_(symbols) {
    for (size_t i = 0; i < symbols.size(); ++i) at_[symbols[i]] = GiNaC::numeric(x0[i]);
  }

  GiNaC::ex Run() { return Build(syntax_.root()); }

 private:
  [[noreturn]] static void Fail(size_t at, const std::string& what) {
    throw NotExact(fmt::format("column {}: {}", at + 1, what));
  }

  // The value of e at x0 (30 digits); a piece is chosen by it.
  GiNaC::numeric At(const GiNaC::ex& e, size_t at) const {
    const GiNaC::ex v = e.subs(at_).evalf();
    if (!GiNaC::is_a<GiNaC::numeric>(v) || !GiNaC::ex_to<GiNaC::numeric>(v).is_real()) {
      Fail(at, "a part of the model is not a real number at the estimates");
    }
    return GiNaC::ex_to<GiNaC::numeric>(v);
  }

  // True when e depends on an input (a constant part has no seam to sit on).
  bool Varies(const GiNaC::ex& e) const {
    for (const GiNaC::symbol& s : symbols_) {
      if (e.has(s)) return true;
    }
    return false;
  }

  // A truth value for && and ||: constant near x0 unless the operand is 0 there and varies.
  bool Truth(const GiNaC::ex& e, size_t at) const {
    const bool truth = !At(e, at).is_zero();
    if (!truth && Varies(e)) Fail(at, "an operand of && or || is 0 at the estimates (a seam)");
    return truth;
  }

  GiNaC::ex Build(size_t n) {
    const ModelNode& node = syntax_.nodes[n];
    switch (node.kind) {
      case ModelNode::Kind::kNumber:
        return Number(node);
      case ModelNode::Kind::kInput:
        return symbols_[node.input];
      case ModelNode::Kind::kPi:
        return GiNaC::Pi;
      case ModelNode::Kind::kE:
        return GiNaC::exp(GiNaC::ex(1));
      case ModelNode::Kind::kSign: {
        const GiNaC::ex t = Build(node.children[0]);
        return node.negative ? -t : t;
      }
      case ModelNode::Kind::kPower: {
        const GiNaC::ex base = Build(node.children[0]);
        return GiNaC::pow(base, Build(node.children[1]));
      }
      case ModelNode::Kind::kChain:
        return Chain(node);
      case ModelNode::Kind::kIf: {
        const GiNaC::ex c = Build(node.children[0]);
        const GiNaC::ex a = Build(node.children[1]);
        const GiNaC::ex b = Build(node.children[2]);
        const bool taken = !At(c, node.lead).is_zero();
        if (!taken && Varies(c)) {
          Fail(node.lead, "the condition of ?: is 0 at the estimates (a seam)");
        }
        return taken ? a : b;
      }
      case ModelNode::Kind::kCall:
        return Call(node);
    }
    Fail(node.at, "unknown node");
  }

  // A decimal literal read exactly: digits, a fraction and an exponent as a rational.
  GiNaC::ex Number(const ModelNode& node) const {
    const std::string& text = node.text;
    std::string digits;
    long scale = 0;
    size_t k = 0;
    for (; k < text.size() && std::isdigit(static_cast<unsigned char>(text[k])); ++k) {
      digits += text[k];
    }
    if (k < text.size() && text[k] == '.') {
      for (++k; k < text.size() && std::isdigit(static_cast<unsigned char>(text[k])); ++k) {
        digits += text[k];
        --scale;
      }
    }
    if (k < text.size()) {  // The exponent: e or E, a sign, digits (model_grammar.cpp).
      const bool negative = text[++k] == '-';
      if (text[k] == '+' || text[k] == '-') ++k;
      long exponent = 0;
      for (; k < text.size(); ++k) {
        if (exponent > 100000) Fail(node.at, "a number's exponent is out of range");
        exponent = 10 * exponent + (text[k] - '0');
      }
      scale += negative ? -exponent : exponent;
    }
    const size_t nonzero = digits.find_first_not_of('0');
    const GiNaC::numeric mantissa(nonzero == std::string::npos ? "0"
                                                               : digits.substr(nonzero).c_str());
    return mantissa * GiNaC::numeric(10).power(GiNaC::numeric(scale));
  }

  // A comparison, && or || is the constant it has at x0; + - * / stay symbolic.
  GiNaC::ex Chain(const ModelNode& node) {
    GiNaC::ex a = Build(node.children[0]);
    for (size_t k = 0; k < node.ops.size(); ++k) {
      const ModelOperator op = node.ops[k];
      const GiNaC::ex b = Build(node.children[k + 1]);
      switch (op) {
        case ModelOperator::kAdd:
          a = a + b;
          break;
        case ModelOperator::kSubtract:
          a = a - b;
          break;
        case ModelOperator::kMultiply:
          a = a * b;
          break;
        case ModelOperator::kDivide:
          a = a / b;
          break;
        case ModelOperator::kOr:
          a = (Truth(a, node.lead) || Truth(b, node.lead)) ? 1 : 0;
          break;
        case ModelOperator::kAnd:
          a = (Truth(a, node.lead) && Truth(b, node.lead)) ? 1 : 0;
          break;
        default: {  // A comparison.
          const size_t at = node.op_at[k];
          const GiNaC::numeric va = At(a, at), vb = At(b, at);
          if (va == vb && Varies(a - b)) {
            Fail(at, fmt::format("the comparison '{}' is between equal values at the estimates "
                                 "(a seam)",
                                 ModelOperatorText(op)));
          }
          bool r = false;
          if (op == ModelOperator::kEqual) r = va == vb;
          if (op == ModelOperator::kNotEqual) r = va != vb;
          if (op == ModelOperator::kLessEqual) r = va <= vb;
          if (op == ModelOperator::kGreaterEqual) r = va >= vb;
          if (op == ModelOperator::kLess) r = va < vb;
          if (op == ModelOperator::kGreater) r = va > vb;
          a = r ? 1 : 0;
        }
      }
    }
    return a;
  }

  GiNaC::ex Call(const ModelNode& node) {
    std::vector<GiNaC::ex> args;
    for (size_t k : node.children) args.push_back(Build(k));
    const std::string& name = node.text;
    const size_t at = node.at;
    const GiNaC::ex& u = args[0];
    using F = GiNaC::ex (*)(const GiNaC::ex&);
    static const std::map<ModelFunction, F> kSmooth = {
        {ModelFunction::kSin, [](const GiNaC::ex& x) -> GiNaC::ex { return GiNaC::sin(x); }},
        {ModelFunction::kCos, [](const GiNaC::ex& x) -> GiNaC::ex { return GiNaC::cos(x); }},
        {ModelFunction::kTan, [](const GiNaC::ex& x) -> GiNaC::ex { return GiNaC::tan(x); }},
        {ModelFunction::kAsin, [](const GiNaC::ex& x) -> GiNaC::ex { return GiNaC::asin(x); }},
        {ModelFunction::kAcos, [](const GiNaC::ex& x) -> GiNaC::ex { return GiNaC::acos(x); }},
        {ModelFunction::kAtan, [](const GiNaC::ex& x) -> GiNaC::ex { return GiNaC::atan(x); }},
        {ModelFunction::kSinh, [](const GiNaC::ex& x) -> GiNaC::ex { return GiNaC::sinh(x); }},
        {ModelFunction::kCosh, [](const GiNaC::ex& x) -> GiNaC::ex { return GiNaC::cosh(x); }},
        {ModelFunction::kTanh, [](const GiNaC::ex& x) -> GiNaC::ex { return GiNaC::tanh(x); }},
        {ModelFunction::kAsinh, [](const GiNaC::ex& x) -> GiNaC::ex { return GiNaC::asinh(x); }},
        {ModelFunction::kAcosh, [](const GiNaC::ex& x) -> GiNaC::ex { return GiNaC::acosh(x); }},
        {ModelFunction::kAtanh, [](const GiNaC::ex& x) -> GiNaC::ex { return GiNaC::atanh(x); }},
        {ModelFunction::kExp, [](const GiNaC::ex& x) -> GiNaC::ex { return GiNaC::exp(x); }},
        {ModelFunction::kSqrt, [](const GiNaC::ex& x) -> GiNaC::ex { return GiNaC::sqrt(x); }},
        {ModelFunction::kLog, [](const GiNaC::ex& x) -> GiNaC::ex { return GiNaC::log(x); }},
        {ModelFunction::kLn, [](const GiNaC::ex& x) -> GiNaC::ex { return GiNaC::log(x); }},
        {ModelFunction::kLog10,
         [](const GiNaC::ex& x) -> GiNaC::ex { return GiNaC::log(x) / GiNaC::log(GiNaC::ex(10)); }},
        {ModelFunction::kLog2,
         [](const GiNaC::ex& x) -> GiNaC::ex { return GiNaC::log(x) / GiNaC::log(GiNaC::ex(2)); }},
    };
    if (auto it = kSmooth.find(node.function); it != kSmooth.end()) return it->second(u);
    switch (node.function) {
      case ModelFunction::kAtan2:
        return GiNaC::atan2(u, args[1]);
      case ModelFunction::kSum:
      case ModelFunction::kAvg: {
        GiNaC::ex s = 0;
        for (const GiNaC::ex& a : args) s += a;
        return node.function == ModelFunction::kSum ? s : s / static_cast<int>(args.size());
      }
      case ModelFunction::kAbs:
      case ModelFunction::kSign: {
        const GiNaC::numeric v = At(u, at);
        if (v.is_zero() && Varies(u)) {
          Fail(at, name + "() of 0 at the estimates (a seam: no derivative there)");
        }
        const int s = v.is_zero() ? 0 : (v.is_positive() ? 1 : -1);
        return node.function == ModelFunction::kAbs ? s * u : GiNaC::ex(s);
      }
      case ModelFunction::kRint: {
        // muparser's rint is floor(x + 0.5) in double (model_grammar.hpp): a step function.
        const double v = At(u, at).to_double();
        if (Varies(u) && std::fabs(v - std::trunc(v)) == 0.5) {
          Fail(at, "rint() of a half-integer at the estimates (a seam: no derivative there)");
        }
        return GiNaC::numeric(std::floor(v + 0.5));
      }
      case ModelFunction::kMin:
      case ModelFunction::kMax: {
        const bool min = node.function == ModelFunction::kMin;
        size_t best = 0;
        GiNaC::numeric best_value = At(args[0], at);
        bool tie = false;
        for (size_t k = 1; k < args.size(); ++k) {
          const GiNaC::numeric v = At(args[k], at);
          if (v == best_value) {
            tie = tie || Varies(args[k] - args[best]);
          } else if (min ? v < best_value : v > best_value) {
            best = k;
            best_value = v;
            tie = false;
          }
        }
        if (tie) Fail(at, name + "() has a tie at the estimates (a seam: no derivative there)");
        return args[best];
      }
      default:
        break;
    }
    Fail(at, "the function " + name + "() is not known to the exact derivatives");
  }

  const ModelSyntax& syntax_;
  const std::vector<GiNaC::symbol>& symbols_;
  GiNaC::exmap at_;
};

}  // namespace

struct SymbolicModel::Impl {
  GiNaC::ex f;
  std::vector<GiNaC::symbol> symbols;
  // Derivatives by the list of variable indices they are taken over, computed once.
  mutable std::map<std::vector<size_t>, GiNaC::ex> derivatives;

  const GiNaC::ex& Derivative(const std::vector<size_t>& over) const {
    auto it = derivatives.find(over);
    if (it != derivatives.end()) return it->second;
    GiNaC::ex d = f;
    for (size_t i : over) d = d.diff(symbols[i]);
    // Repeated differentiation of a long product or a deep nest swells (n factors give n^3
    // terms by the third derivative): beyond kMaxNodes the caller is told.
    size_t nodes = 0;
    for (auto node = d.preorder_begin(); node != d.preorder_end(); ++node) {
      if (++nodes > kMaxNodes) {
        throw std::length_error(
            fmt::format("its derivative has more than {} terms and operations", kMaxNodes));
      }
    }
    return derivatives.emplace(over, d).first->second;
  }

  Result<double> At(const GiNaC::ex& e, const double* x) const {
    GiNaC::exmap values;
    for (size_t i = 0; i < symbols.size(); ++i) values[symbols[i]] = GiNaC::numeric(x[i]);
    const GiNaC::ex v = e.subs(values).evalf();
    if (!GiNaC::is_a<GiNaC::numeric>(v)) {
      return MakeError("the model's derivative does not evaluate to a number at the estimates");
    }
    const GiNaC::numeric n = GiNaC::ex_to<GiNaC::numeric>(v);
    if (!n.is_real()) {
      return MakeError("the model's derivative is not real at the input estimates");
    }
    const double d = n.to_double();
    if (!std::isfinite(d)) {
      return MakeError("the model's derivative is not finite at the input estimates");
    }
    return d;
  }

  Result<double> Evaluate(const std::vector<size_t>& over, const double* x) const {
    std::lock_guard<std::mutex> lock(GinacMutex());
    try {
      const GiNaC::ex& e = Derivative(over);
      const Precision precision;
      return At(e, x);
    } catch (const std::exception& error) {
      return MakeError(std::string("the model cannot be evaluated symbolically: ") + error.what());
    }
  }
};

Result<SymbolicModel> SymbolicModel::Parse(const std::string& expression,
                                           const std::vector<std::string>& names,
                                           const double* x0) {
  if (expression.size() > kMaxExpressionLength) {
    return MakeError(fmt::format("the model is longer than {} characters", kMaxExpressionLength));
  }
  int depth = 0, deepest = 0;
  for (char ch : expression) {
    if (ch == '(') deepest = std::max(deepest, ++depth);
    if (ch == ')') --depth;
  }
  if (std::count(expression.begin(), expression.end(), '^') > kMaxPowers) {
    return MakeError(fmt::format("the model has more than {} powers", kMaxPowers));
  }
  if (deepest > kMaxNesting) {
    return MakeError(fmt::format("the model nests parentheses deeper than {}", kMaxNesting));
  }
  std::lock_guard<std::mutex> lock(GinacMutex());
  try {
    auto impl = std::make_shared<Impl>();
    for (const std::string& name : names) impl->symbols.emplace_back(name);
    const Precision precision;
    Result<ModelSyntax> syntax = ParseModel(expression, names);
    if (!syntax.ok()) return MakeError(syntax.error().message);
    impl->f = Builder(syntax.value(), impl->symbols, x0).Run();
    return SymbolicModel(std::move(impl));
  } catch (const std::exception& error) {
    return MakeError(error.what());
  }
}

Result<double> SymbolicModel::Value(const double* x) const { return impl_->Evaluate({}, x); }

Result<double> SymbolicModel::First(size_t i, const double* x) const {
  return impl_->Evaluate({i}, x);
}

Result<double> SymbolicModel::Second(size_t i, size_t j, const double* x) const {
  return impl_->Evaluate({i, j}, x);
}

Result<double> SymbolicModel::Third(size_t i, size_t j, const double* x) const {
  return impl_->Evaluate({i, j, j}, x);
}

}  // namespace internal
}  // namespace metro
