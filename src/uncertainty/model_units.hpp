// The unit check of a measurement model y = f(x) (docs/budget-format.md, "Units").
//
// The expression's syntax tree (model_grammar.hpp: muparser's grammar, read once for this and
// the exact derivatives) is walked and every subexpression given a unit from its inputs':
//   - sums, differences, comparisons, min/max/sum/avg/atan2 and the branches of ?: need the
//     same unit in every term (rad + deg is refused although both are plane angles);
//   - products and quotients multiply units; x^p needs a constant p (integer or 1/k) unless x
//     is a number; sqrt takes the square root of the unit;
//   - sin/cos/tan take radians; the other functions of muparser (exp, ln, log*, asin, ...)
//     take a number (the unit 1) and give 1 (asin/acos/atan/atan2 give rad).
// Bare numeric constants take the unit their place requires: in a sum (or comparison, min,
// ...) the unit of the other terms, so `m - 100000` with m in mg subtracts 100000 mg. A
// constant factor or divisor is a pure number that may be a conversion factor (theta*pi/180):
// a product with one is known in dimension but not in scale, and is then checked by
// dimension only (`scale_known` false).
// To prove the parse is muparser's, the check also evaluates f at the estimates and must
// agree with muparser's value there.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "metro/core/status.hpp"
#include "metro/core/units.hpp"

namespace metro {
namespace internal {

struct ModelUnit {
  PhysicalUnit unit = PhysicalUnit::One();
  bool scale_known = true;  // False: dimension known, scale not (a constant factor).
  bool constant = false;    // The model uses no input: it takes the measurand's unit.
};

// `units[i]` is the unit of input `names[i]` (nullopt when not stated: an error if the model
// uses it); `values[i]` its estimate; `muparser_value` muparser's f at those estimates.
// Errors name the column (1-based) of the offending operator or function ("column 3: a sum:
// ..."; Error::column is that column) and the terms and their units; the caller quotes the
// model (model.hpp, "Errors").
Result<ModelUnit> CheckModelUnits(const std::string& expression,
                                  const std::vector<std::string>& names,
                                  const std::vector<std::optional<PhysicalUnit>>& units,
                                  const std::vector<double>& values, double muparser_value);

}  // namespace internal
}  // namespace metro
