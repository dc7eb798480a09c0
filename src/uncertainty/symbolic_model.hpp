// SymbolicModel: exact derivatives of a budget's model expression, for the GUM framework's
// sensitivity coefficients c_i = df/dx_i (JCGM 100:2008 5.1.3) and the second-order terms
// of the JCGM 100 5.1.2 note (d2f/dx_i dx_j, d3f/dx_i dx_j^2).
//
// The expression's syntax tree (model_grammar.hpp: muparser's grammar, read once for this and
// the unit check) becomes a GiNaC expression (Debian libginac-dev) over one symbol per input
// name, differentiated symbolically; each derivative is evaluated
// at the input estimates in GiNaC's arbitrary-precision floating point (30 significant
// digits) and rounded to double once. Central differences, which rounding erases when u_i is
// tiny beside |x_i| (f = fm at 1e7 +- 1e-6 Hz gave u_c 86 % high, issue #22; 2*pi*f at 1e7
// +- 1e-6 Hz 78 % high, issue #36), are never used for a model read here.
//
// Everything the grammar takes is read: numbers exactly (0.1 is 1/10), pi and _pi as GiNaC's
// Pi, _e as exp(1), the smooth functions as GiNaC's, and the piecewise parts (abs, sign, rint,
// min, max, the comparisons, && || and ?:) as below. A piecewise part is
// replaced by the piece that holds at the estimates x0 given to Parse (abs(u) by u or -u,
// min(a, b) by the smaller, a comparison or sign() by its constant value, c ? a : b by the
// branch taken): the derivatives are exact at x0 and near it, where the same pieces hold.
// Where x0 lies on a seam (abs(0), a tie of min or max, a comparison between equal values,
// sign(0), rint at a half-integer), no derivative exists: Parse refuses with the reason.
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
  // The model around x0 (x0[names.size()], the input estimates: it chooses the pieces of
  // piecewise functions). Errors: the grammar's (ParseModel), a seam at x0, or an expression
  // too long or deep (each message says which).
  static Result<SymbolicModel> Parse(const std::string& expression,
                                     const std::vector<std::string>& names, const double* x0);

  // f(x), df/dx_i, d2f/(dx_i dx_j) and d3f/(dx_i dx_j^2) at x (x[names.size()]), with the
  // pieces chosen at x0.
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
