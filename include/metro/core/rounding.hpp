// Rounding of a stated result per JCGM 100:2008 7.2.6: the uncertainty to (at most) two
// significant digits, the estimate rounded to the same decimal place; and the concise
// notation of JCGM 100:2008 7.2.2, the one way metro prints a value with its standard
// uncertainty in brackets.
#pragma once

#include <string>

namespace metro {

struct RoundedResult {
  std::string value;        // e.g. "0.18821"
  std::string uncertainty;  // e.g. "0.00087"
};

// `significant` digits of u (2 by GUM 7.2.6). u <= 0 or non-finite: the value with 6
// significant digits and uncertainty "0" or "nan".
RoundedResult RoundForStatement(double value, double u, int significant = 2);

// JCGM 100:2008 7.2.2 concise notation "y(u)": u rounded to `significant` digits (7.2.6),
// y rounded to the same decimal place, and the bracket holds u in the units of the last
// digit of y:
//   (100.02147, 0.00035) -> "100.02147(35)"     u below one: its digits only
//   (826.6026, 4.95)     -> "826.6(5.0)"        u spans the decimal point: written out
//   (826.6026, 49.5)     -> "827(50)"           last digit of y in the units: u as is
//   (3.9e-13, 1.2e-13)   -> "3.9(1.2)e-13"      exponent notation (below)
// Exponent notation "m(u_m)eE" is used when fixed notation would need more than six
// decimals (last digit below 1e-6), trailing zeros beyond the hundreds (last digit above
// 100) or |y| >= 1e9; E is the decimal exponent of the larger of |y| and u, so the mantissa
// has one digit before the point. A value that rounds to zero prints as "0.0(1.2)", never
// "-0.0". u = 0: "y (u = 0)" with y to 6 significant digits; u non-finite or negative:
// "y (u = nan)"; y non-finite: "nan (u = ...)" with u to 2 significant digits.
std::string ConciseNotation(double value, double u, int significant = 2);

// A coverage interval [low, high] printed so that its ends tell apart: both rounded to the
// decimal place of the `significant`-th significant digit of the width high - low (the
// rounding of RoundForStatement with the width in place of u), so the ends differ in at
// least `significant` digits: [50000745.3, 50000930.8] -> "50000750", "50000930" where
// "{:.6g}" printed 5.00007e+07 twice. A width <= 0 or a non-finite end: "{:.6g}" each.
struct RoundedInterval {
  std::string low;
  std::string high;
};
RoundedInterval RoundInterval(double low, double high, int significant = 2);

}  // namespace metro
