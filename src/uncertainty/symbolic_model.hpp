// SymbolicModel: exact derivatives of a budget's model expression, for the GUM framework's
// sensitivity coefficients c_i = df/dx_i (JCGM 100:2008 5.1.3) and the second-order terms
// of the JCGM 100 5.1.2 note (d2f/dx_i dx_j, d3f/dx_i dx_j^2).
//
// The expression is parsed by GiNaC (Debian libginac-dev) over one symbol per input name and
// differentiated symbolically; each derivative is evaluated at the input estimates in
// GiNaC's arbitrary-precision floating point (30 significant digits) and rounded to double
// once. Central differences, which rounding erases when u_i is tiny beside |x_i| (f = fm at
// 1e7 +- 1e-6 Hz gave u_c 86 % high, issue #22), are never used for an expression GiNaC
// accepts.
//
// Accepted: + - * / ^, parentheses, numbers, the input names, _pi and _e (muparser's
// constants), and sin cos tan asin acos atan sinh cosh tanh asinh acosh atanh exp sqrt abs,
// log and ln (natural), log10, log2, pow. Anything else muparser evaluates (min, max, sign,
// rint, sum, avg, comparisons, the ternary operator) is refused with the reason: such a
// model is not differentiable everywhere, and the caller says that it falls back to central
// differences. Input names are renamed for GiNaC, so any name muparser takes works.
//
// GiNaC is not thread-safe (its expressions share reference-counted nodes): every call
// takes one process-wide lock. Budgets are small; the Monte Carlo never calls this.
// Private to the uncertainty module: GiNaC never appears in a public header.
#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "metro/core/status.hpp"

namespace metro {
namespace internal {

class SymbolicModel {
 public:
  // Errors: a function, operator or name GiNaC cannot take (the message names it).
  static Result<SymbolicModel> Parse(const std::string& expression,
                                     const std::vector<std::string>& names);

  // f(x), df/dx_i, d2f/(dx_i dx_j) and d3f/(dx_i dx_j^2) at x (x[names.size()]).
  // Errors: the value is not a finite real number there (a pole, log of a negative).
  Result<double> Value(const double* x) const;
  Result<double> First(size_t i, const double* x) const;
  Result<double> Second(size_t i, size_t j, const double* x) const;
  Result<double> Third(size_t i, size_t j, const double* x) const;

  struct Impl;

 private:
  explicit SymbolicModel(std::shared_ptr<Impl> impl) : impl_(std::move(impl)) {}
  std::shared_ptr<Impl> impl_;
};

}  // namespace internal
}  // namespace metro
