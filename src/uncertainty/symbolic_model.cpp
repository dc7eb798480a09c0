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

// Reads the expression with muparser's grammar (the same as model_units.cpp's unit checker:
// ?: lowest, then ||, &&, comparisons, + -, * /, signs, ^ right-associative with a signed
// exponent) into a GiNaC expression, choosing the pieces of piecewise functions at x0.
class Reader {
 public:
  Reader(const std::string& text, const std::vector<std::string>& names,
         const std::vector<GiNaC::symbol>& symbols, const double* x0)
      : text_(text), names_(names), symbols_(symbols) {
    for (size_t i = 0; i < symbols.size(); ++i) at_[symbols[i]] = GiNaC::numeric(x0[i]);
  }

  GiNaC::ex Run() {
    GiNaC::ex e = Ternary();
    SkipSpace();
    if (pos_ != text_.size()) Fail(pos_, "unexpected '" + text_.substr(pos_, 1) + "'");
    return e;
  }

 private:
  [[noreturn]] void Fail(size_t at, const std::string& what) const {
    throw NotExact(fmt::format("column {}: {}", at + 1, what));
  }

  void SkipSpace() {
    while (pos_ < text_.size() && std::isspace(static_cast<unsigned char>(text_[pos_]))) ++pos_;
  }

  bool Accept(const char* op) {
    SkipSpace();
    const size_t n = std::char_traits<char>::length(op);
    if (text_.compare(pos_, n, op) != 0) return false;
    pos_ += n;
    return true;
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

  GiNaC::ex Ternary() {
    const size_t at = pos_;
    GiNaC::ex c = LogicOr();
    if (!Accept("?")) return c;
    GiNaC::ex a = Ternary();
    if (!Accept(":")) Fail(pos_, "expected ':' of '?'");
    GiNaC::ex b = Ternary();
    const bool taken = !At(c, at).is_zero();
    if (!taken && Varies(c)) Fail(at, "the condition of ?: is 0 at the estimates (a seam)");
    return taken ? a : b;
  }

  // A truth value for && and ||: constant near x0 unless the operand is 0 there and varies.
  bool Truth(const GiNaC::ex& e, size_t at) const {
    const bool truth = !At(e, at).is_zero();
    if (!truth && Varies(e)) Fail(at, "an operand of && or || is 0 at the estimates (a seam)");
    return truth;
  }

  GiNaC::ex LogicOr() {
    const size_t at = pos_;
    GiNaC::ex a = LogicAnd();
    while (Accept("||")) {
      GiNaC::ex b = LogicAnd();
      a = (Truth(a, at) || Truth(b, at)) ? 1 : 0;
    }
    return a;
  }

  GiNaC::ex LogicAnd() {
    const size_t at = pos_;
    GiNaC::ex a = Compare();
    while (Accept("&&")) {
      GiNaC::ex b = Compare();
      a = (Truth(a, at) && Truth(b, at)) ? 1 : 0;
    }
    return a;
  }

  GiNaC::ex Compare() {
    GiNaC::ex a = Additive();
    for (;;) {
      SkipSpace();
      const size_t at = pos_;
      static const char* const kOps[] = {"==", "!=", "<=", ">=", "<", ">"};
      int op = -1;
      for (int k = 0; k < 6; ++k) {
        if (text_.compare(pos_, std::char_traits<char>::length(kOps[k]), kOps[k]) == 0) {
          op = k;
          pos_ += std::char_traits<char>::length(kOps[k]);
          break;
        }
      }
      if (op < 0) return a;
      GiNaC::ex b = Additive();
      const GiNaC::numeric va = At(a, at), vb = At(b, at);
      if (va == vb && Varies(a - b)) {
        Fail(at, fmt::format("the comparison '{}' is between equal values at the estimates (a "
                             "seam)",
                             kOps[op]));
      }
      bool r = false;
      switch (op) {
        case 0:
          r = va == vb;
          break;
        case 1:
          r = va != vb;
          break;
        case 2:
          r = va <= vb;
          break;
        case 3:
          r = va >= vb;
          break;
        case 4:
          r = va < vb;
          break;
        default:
          r = va > vb;
          break;
      }
      a = r ? 1 : 0;
    }
  }

  GiNaC::ex Additive() {
    GiNaC::ex a = Multiplicative();
    for (;;) {
      SkipSpace();
      if (pos_ >= text_.size() || (text_[pos_] != '+' && text_[pos_] != '-')) return a;
      const bool plus = text_[pos_++] == '+';
      GiNaC::ex b = Multiplicative();
      a = plus ? a + b : a - b;
    }
  }

  GiNaC::ex Multiplicative() {
    GiNaC::ex a = Unary();
    for (;;) {
      SkipSpace();
      if (pos_ >= text_.size() || (text_[pos_] != '*' && text_[pos_] != '/')) return a;
      const bool divide = text_[pos_++] == '/';
      GiNaC::ex b = Unary();
      a = divide ? a / b : a * b;
    }
  }

  // Signs bind less tightly than ^ (muparser: -2^2 = -4).
  GiNaC::ex Unary() {
    SkipSpace();
    if (pos_ < text_.size() && (text_[pos_] == '-' || text_[pos_] == '+')) {
      const bool minus = text_[pos_++] == '-';
      GiNaC::ex t = Unary();
      return minus ? -t : t;
    }
    return Power();
  }

  GiNaC::ex Power() {
    GiNaC::ex base = Primary();
    if (!Accept("^")) return base;
    GiNaC::ex exponent = Unary();  // Right-associative: 2^3^2 = 2^9; 2^-1 is allowed.
    return GiNaC::pow(base, exponent);
  }

  // A decimal number read exactly: digits, a fraction and an exponent as a rational.
  GiNaC::ex Number() {
    const size_t at = pos_;
    std::string digits;
    long scale = 0;
    while (pos_ < text_.size() && std::isdigit(static_cast<unsigned char>(text_[pos_]))) {
      digits += text_[pos_++];
    }
    if (pos_ < text_.size() && text_[pos_] == '.') {
      ++pos_;
      while (pos_ < text_.size() && std::isdigit(static_cast<unsigned char>(text_[pos_]))) {
        digits += text_[pos_++];
        --scale;
      }
    }
    if (digits.empty()) Fail(at, "expected a number");
    if (pos_ < text_.size() && (text_[pos_] == 'e' || text_[pos_] == 'E')) {
      size_t k = pos_ + 1;
      bool negative = false;
      if (k < text_.size() && (text_[k] == '+' || text_[k] == '-')) negative = text_[k++] == '-';
      const size_t first = k;
      long exponent = 0;
      while (k < text_.size() && std::isdigit(static_cast<unsigned char>(text_[k]))) {
        if (exponent > 100000) Fail(at, "a number's exponent is out of range");
        exponent = 10 * exponent + (text_[k++] - '0');
      }
      if (k > first) {
        scale += negative ? -exponent : exponent;
        pos_ = k;
      }
    }
    const size_t nonzero = digits.find_first_not_of('0');
    const GiNaC::numeric mantissa(nonzero == std::string::npos ? "0"
                                                               : digits.substr(nonzero).c_str());
    return mantissa * GiNaC::numeric(10).power(GiNaC::numeric(scale));
  }

  std::vector<GiNaC::ex> Arguments(const std::string& name) {
    std::vector<GiNaC::ex> args;
    if (Accept(")")) return args;
    for (;;) {
      args.push_back(Ternary());
      if (Accept(",")) continue;
      if (Accept(")")) return args;
      Fail(pos_, "expected ',' or ')' in the arguments of " + name + "()");
    }
  }

  GiNaC::ex Call(const std::string& name, size_t at) {
    const std::vector<GiNaC::ex> args = Arguments(name);
    const auto need = [&](size_t n) {
      if (args.size() != n) {
        Fail(at, fmt::format("{}() takes {} argument{}", name, n, n == 1 ? "" : "s"));
      }
    };
    using F = GiNaC::ex (*)(const GiNaC::ex&);
    static const std::map<std::string, F> kSmooth = {
        {"sin", [](const GiNaC::ex& u) -> GiNaC::ex { return GiNaC::sin(u); }},
        {"cos", [](const GiNaC::ex& u) -> GiNaC::ex { return GiNaC::cos(u); }},
        {"tan", [](const GiNaC::ex& u) -> GiNaC::ex { return GiNaC::tan(u); }},
        {"asin", [](const GiNaC::ex& u) -> GiNaC::ex { return GiNaC::asin(u); }},
        {"acos", [](const GiNaC::ex& u) -> GiNaC::ex { return GiNaC::acos(u); }},
        {"atan", [](const GiNaC::ex& u) -> GiNaC::ex { return GiNaC::atan(u); }},
        {"sinh", [](const GiNaC::ex& u) -> GiNaC::ex { return GiNaC::sinh(u); }},
        {"cosh", [](const GiNaC::ex& u) -> GiNaC::ex { return GiNaC::cosh(u); }},
        {"tanh", [](const GiNaC::ex& u) -> GiNaC::ex { return GiNaC::tanh(u); }},
        {"asinh", [](const GiNaC::ex& u) -> GiNaC::ex { return GiNaC::asinh(u); }},
        {"acosh", [](const GiNaC::ex& u) -> GiNaC::ex { return GiNaC::acosh(u); }},
        {"atanh", [](const GiNaC::ex& u) -> GiNaC::ex { return GiNaC::atanh(u); }},
        {"exp", [](const GiNaC::ex& u) -> GiNaC::ex { return GiNaC::exp(u); }},
        {"sqrt", [](const GiNaC::ex& u) -> GiNaC::ex { return GiNaC::sqrt(u); }},
        // muparser's log is the natural logarithm, like ln.
        {"log", [](const GiNaC::ex& u) -> GiNaC::ex { return GiNaC::log(u); }},
        {"ln", [](const GiNaC::ex& u) -> GiNaC::ex { return GiNaC::log(u); }},
        {"log10",
         [](const GiNaC::ex& u) -> GiNaC::ex { return GiNaC::log(u) / GiNaC::log(GiNaC::ex(10)); }},
        {"log2",
         [](const GiNaC::ex& u) -> GiNaC::ex { return GiNaC::log(u) / GiNaC::log(GiNaC::ex(2)); }},
    };
    if (auto it = kSmooth.find(name); it != kSmooth.end()) {
      need(1);
      return it->second(args[0]);
    }
    if (name == "atan2") {  // muparser's atan2(y, x).
      need(2);
      return GiNaC::atan2(args[0], args[1]);
    }
    if (name == "sum" || name == "avg") {
      if (args.empty()) Fail(at, name + "() needs at least one argument");
      GiNaC::ex s = 0;
      for (const GiNaC::ex& a : args) s += a;
      return name == "sum" ? s : s / static_cast<int>(args.size());
    }
    if (name == "abs" || name == "sign") {
      need(1);
      const GiNaC::numeric v = At(args[0], at);
      if (v.is_zero() && Varies(args[0])) {
        Fail(at, name + "() of 0 at the estimates (a seam: no derivative there)");
      }
      const int s = v.is_zero() ? 0 : (v.is_positive() ? 1 : -1);
      return name == "abs" ? s * args[0] : GiNaC::ex(s);
    }
    if (name == "rint") {
      need(1);
      // muparser's rint is the C library's (ties to even, in double): a step function.
      const double v = At(args[0], at).to_double();
      if (Varies(args[0]) && std::fabs(v - std::trunc(v)) == 0.5) {
        Fail(at, "rint() of a half-integer at the estimates (a seam: no derivative there)");
      }
      return GiNaC::numeric(std::rint(v));
    }
    if (name == "min" || name == "max") {
      if (args.empty()) Fail(at, name + "() needs at least one argument");
      size_t best = 0;
      GiNaC::numeric best_value = At(args[0], at);
      bool tie = false;
      for (size_t k = 1; k < args.size(); ++k) {
        const GiNaC::numeric v = At(args[k], at);
        if (v == best_value) {
          tie = tie || Varies(args[k] - args[best]);
        } else if (name == "min" ? v < best_value : v > best_value) {
          best = k;
          best_value = v;
          tie = false;
        }
      }
      if (tie) Fail(at, name + "() has a tie at the estimates (a seam: no derivative there)");
      return args[best];
    }
    Fail(at, "the function " + name + "() is not known to the exact derivatives");
  }

  GiNaC::ex Primary() {
    SkipSpace();
    const size_t at = pos_;
    if (pos_ >= text_.size()) Fail(at, "unexpected end of the model");
    const char c = text_[pos_];
    if (c == '(') {
      ++pos_;
      GiNaC::ex e = Ternary();
      if (!Accept(")")) Fail(pos_, "expected ')'");
      return e;
    }
    if (std::isdigit(static_cast<unsigned char>(c)) || c == '.') return Number();
    if (!(std::isalpha(static_cast<unsigned char>(c)) || c == '_')) {
      Fail(at, "unexpected '" + std::string(1, c) + "'");
    }
    size_t end = pos_;
    while (end < text_.size() &&
           (std::isalnum(static_cast<unsigned char>(text_[end])) || text_[end] == '_')) {
      ++end;
    }
    const std::string name = text_.substr(pos_, end - pos_);
    pos_ = end;
    SkipSpace();
    if (pos_ < text_.size() && text_[pos_] == '(') {
      ++pos_;
      return Call(name, at);
    }
    for (size_t i = 0; i < names_.size(); ++i) {
      if (names_[i] == name) return symbols_[i];
    }
    // metro defines pi for muparser (model.cpp) unless an input has that name.
    if (name == "pi" || name == "_pi") return GiNaC::Pi;
    if (name == "_e") return GiNaC::exp(GiNaC::ex(1));
    Fail(at, "'" + name + "' is not an input");
  }

  const std::string& text_;
  const std::vector<std::string>& names_;
  const std::vector<GiNaC::symbol>& symbols_;
  GiNaC::exmap at_;
  size_t pos_ = 0;
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
    impl->f = Reader(expression, names, impl->symbols, x0).Run();
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
