// Rounding of a stated result per JCGM 100:2008 7.2.6: the uncertainty to (at most) two
// significant digits, the estimate rounded to the same decimal place.
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

}  // namespace metro
