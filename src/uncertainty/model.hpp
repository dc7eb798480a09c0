// MeasurementModel: the function y = f(x_1, ..., x_N) of a budget, evaluated one point at a
// time (GUM framework) or over blocks of Monte Carlo trials (JCGM 101).
//
// Two kinds:
//   - an expression parsed by muparser, the variables being the budget's input names;
//   - the classic budget table without a model: y = sum_i c_i x_i with explicit c_i.
// Block evaluation of an expression runs muparser's own optimised bytecode (reverse Polish
// notation) one operation at a time over a whole block of trials, so the interpretation
// cost is paid once per block instead of once per trial. The translation is checked
// against muparser's scalar Eval() at construction; any bytecode it does not handle (the
// ternary operator, string functions) makes it fall back to one muparser Eval() per trial.
// Private to the uncertainty module: muparser never appears in a public header.
#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "metro/core/status.hpp"

namespace metro {
namespace internal {

class BlockProgram;

class MeasurementModel {
 public:
  // Parses `expression` over the variables `names` (in input order). Errors name the
  // undefined identifiers or quote muparser's syntax message, but never the expression
  // itself: an error about its text has `column` = the 1-based byte of the expression it is
  // about (0: the whole expression), and the caller quotes the expression once, cut around
  // that byte (ModelError in budget.cpp: file:line:column of that byte in the budget).
  // An expression longer than muparser's limit (19999 bytes) is refused before parsing.
  static Result<MeasurementModel> FromExpression(const std::string& expression,
                                                 const std::vector<std::string>& names);
  // y = sum_i coefficients[i] * x_i.
  static MeasurementModel Linear(std::vector<double> coefficients);

  MeasurementModel(MeasurementModel&&) noexcept;
  MeasurementModel& operator=(MeasurementModel&&) noexcept;
  ~MeasurementModel();

  size_t input_count() const { return input_count_; }
  bool is_linear() const { return expression_.empty(); }
  // True when block evaluation runs the translated bytecode (false: per-trial fallback).
  bool vectorized() const;
  // Names of the variables the expression uses (all inputs for a linear model).
  const std::vector<std::string>& used_names() const { return used_names_; }

  // f(x) at one point, x[input_count()]. Not thread-safe (a muparser object is stateful);
  // the Monte Carlo uses Evaluator objects, one per thread.
  double Evaluate(const double* x) const;

  // A thread-confined evaluator for blocks of trials. inputs[i] points at n values of x_i;
  // out receives n values of y.
  class Evaluator {
   public:
    virtual ~Evaluator() = default;
    virtual void EvaluateBlock(const double* const* inputs, size_t n, double* out) = 0;
  };
  std::unique_ptr<Evaluator> MakeEvaluator() const;

  struct ScalarParser;  // A muparser object with its own variable storage (model.cpp).

 private:
  MeasurementModel() = default;

  std::string expression_;
  std::vector<std::string> names_;
  std::vector<std::string> used_names_;
  std::vector<double> coefficients_;
  size_t input_count_ = 0;
  std::unique_ptr<ScalarParser> scalar_;
  std::shared_ptr<const BlockProgram> program_;
};

}  // namespace internal
}  // namespace metro
