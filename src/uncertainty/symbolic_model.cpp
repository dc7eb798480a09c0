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
#include <tuple>

namespace metro {
namespace internal {
namespace {

// GiNaC shares reference-counted expression nodes between copies without atomics, and Digits
// is a global: one lock for every use in the process.
std::mutex& GinacMutex() {
  static std::mutex mutex;
  return mutex;
}

// Longer or deeper expressions are left to central differences rather than risk GiNaC's
// recursion on adversarial input (the budget fuzzer's nesting).
// A measurement model is a line (GUM H.1's is 60 characters); towers of powers are what
// makes repeated differentiation slow, so they are bounded too.
constexpr size_t kMaxExpressionLength = 1000;
constexpr int kMaxNesting = 32;
constexpr int kMaxPowers = 32;
constexpr size_t kMaxNodes = 200000;

// The functions a model may use; GiNaC's default reader knows many more (zeta, tgamma, ...)
// that muparser does not, and muparser never reaches here with them anyway.
bool KnownFunction(const std::string& name) {
  static const char* const kNames[] = {"sin",  "cos",  "tan",   "asin",  "acos",  "atan", "sinh",
                                       "cosh", "tanh", "asinh", "acosh", "atanh", "exp",  "sqrt",
                                       "abs",  "log",  "ln",    "log10", "log2",  "pow"};
  for (const char* n : kNames) {
    if (name == n) return true;
  }
  return false;
}

// Rewritten for GiNaC's lexer, identifier by identifier: an input becomes x<index>_ (GiNaC
// takes no leading '_' and reserves I, Pi, Euler, Catalan), _pi and _e become Pi and
// exp(1), a function stays if it is differentiable everywhere it is defined; muparser's ln,
// log10 and log2 become GiNaC's log (GiNaC's parser takes no reader functions of ours: its
// prototype table holds function serial numbers, not pointers). Recursion is bounded by the
// nesting limit checked before.
Result<std::string> RewriteForGinac(const std::string& expression,
                                    const std::map<std::string, size_t>& index) {
  std::string rewritten;
  for (size_t k = 0; k < expression.size();) {
    const unsigned char ch = static_cast<unsigned char>(expression[k]);
    if (std::isdigit(ch) || ch == '.') {
      // A number, its exponent (1e-3) included, is copied as it is.
      size_t end = k;
      while (end < expression.size() &&
             (std::isalnum(static_cast<unsigned char>(expression[end])) || expression[end] == '.' ||
              ((expression[end] == '+' || expression[end] == '-') &&
               (expression[end - 1] == 'e' || expression[end - 1] == 'E')))) {
        ++end;
      }
      rewritten += expression.substr(k, end - k);
      k = end;
      continue;
    }
    if (!(std::isalpha(ch) || ch == '_')) {
      rewritten += expression[k++];
      continue;
    }
    size_t end = k;
    while (end < expression.size() &&
           (std::isalnum(static_cast<unsigned char>(expression[end])) || expression[end] == '_')) {
      ++end;
    }
    const std::string word = expression.substr(k, end - k);
    size_t next = end;
    while (next < expression.size() && std::isspace(static_cast<unsigned char>(expression[next]))) {
      ++next;
    }
    if (next < expression.size() && expression[next] == '(') {
      if (!KnownFunction(word)) {
        return MakeError(fmt::format(
            "the model uses {}(), which has no derivative everywhere or is not known to GiNaC",
            word));
      }
      if (word == "log10" || word == "log2") {
        // log10(u) = log(u) / log(10): the argument (rewritten on its own) in parentheses, so
        // that a^log10(u) and x / log10(u) keep muparser's precedence.
        int depth = 0;
        size_t close = next;
        for (; close < expression.size(); ++close) {
          if (expression[close] == '(') ++depth;
          if (expression[close] == ')' && --depth == 0) break;
        }
        if (close >= expression.size()) return MakeError("the model has an unclosed '('");
        Result<std::string> inner =
            RewriteForGinac(expression.substr(next + 1, close - next - 1), index);
        if (!inner.ok()) return inner.error();
        rewritten += fmt::format("(log({})/log({}))", inner.value(), word == "log10" ? 10 : 2);
        k = close + 1;
        continue;
      }
      rewritten += word == "ln" ? "log" : word;
    } else if (auto it = index.find(word); it != index.end()) {
      rewritten += fmt::format("x{}_", it->second);
    } else if (word == "_pi") {
      rewritten += "Pi";
    } else if (word == "_e") {
      rewritten += "exp(1)";
    } else {
      return MakeError(fmt::format("the model uses '{}', which is not an input", word));
    }
    k = end;
  }
  return rewritten;
}

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
    // terms by the third derivative): beyond kMaxNodes the caller takes differences instead.
    size_t nodes = 0;
    for (auto it = d.preorder_begin(); it != d.preorder_end(); ++it) {
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
      struct Precision {  // 30 digits for this evaluation, GiNaC's default again after it
        long saved = GiNaC::Digits;
        Precision() { GiNaC::Digits = 30; }
        ~Precision() { GiNaC::Digits = saved; }
      } precision;
      return At(e, x);
    } catch (const std::exception& error) {
      return MakeError(std::string("the model cannot be evaluated symbolically: ") + error.what());
    }
  }
};

Result<SymbolicModel> SymbolicModel::Parse(const std::string& expression,
                                           const std::vector<std::string>& names) {
  if (expression.size() > kMaxExpressionLength) {
    return MakeError(fmt::format("the model is longer than {} characters", kMaxExpressionLength));
  }
  int depth = 0, deepest = 0;
  for (char ch : expression) {
    if (ch == '(') deepest = std::max(deepest, ++depth);
    if (ch == ')') --depth;
    if (ch == '?' || ch == '<' || ch == '>' || ch == '=' || ch == '!' || ch == '&' || ch == '|' ||
        ch == ',') {
      if (ch == ',') continue;  // pow(a, b): checked by the function table below
      return MakeError(fmt::format("the model uses '{}' (a comparison or the ternary operator)",
                                   std::string(1, ch)));
    }
  }
  if (std::count(expression.begin(), expression.end(), '^') > kMaxPowers) {
    return MakeError(fmt::format("the model has more than {} powers", kMaxPowers));
  }
  if (deepest > kMaxNesting) {
    return MakeError(fmt::format("the model nests parentheses deeper than {}", kMaxNesting));
  }
  // Rewritten for GiNaC's lexer, identifier by identifier: an input becomes x<index>_ (GiNaC
  // takes no leading '_' and reserves I, Pi, Euler, Catalan), _pi and _e become Pi and
  // exp(1), a function stays if it is differentiable everywhere it is defined.
  std::map<std::string, size_t> index;
  for (size_t i = 0; i < names.size(); ++i) index[names[i]] = i;
  Result<std::string> written = RewriteForGinac(expression, index);
  if (!written.ok()) return written.error();
  const std::string rewritten = std::move(written).value();
  std::lock_guard<std::mutex> lock(GinacMutex());
  try {
    auto impl = std::make_shared<Impl>();
    GiNaC::symtab table;
    for (size_t i = 0; i < names.size(); ++i) {
      impl->symbols.emplace_back(names[i]);
      table[fmt::format("x{}_", i)] = impl->symbols.back();
    }
    GiNaC::parser reader(table, true);
    impl->f = reader(rewritten);
    return SymbolicModel(std::move(impl));
  } catch (const std::exception& error) {
    return MakeError(std::string("GiNaC cannot parse the model: ") + error.what());
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
