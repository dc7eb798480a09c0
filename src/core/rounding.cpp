#include "metro/core/rounding.hpp"

#include <fmt/format.h>

#include <cmath>

namespace metro {

RoundedResult RoundForStatement(double value, double u, int significant) {
  if (!std::isfinite(u) || u <= 0.0) {
    return {fmt::format("{:.6g}", value), std::isfinite(u) ? "0" : "nan"};
  }
  // Decimal exponent of u's leading digit, then the last kept decimal place.
  int exponent = static_cast<int>(std::floor(std::log10(u)));
  double scaled = std::round(u / std::pow(10.0, exponent - significant + 1));
  if (scaled >= std::pow(10.0, significant)) ++exponent;  // 0.0996 -> 0.10
  const int last_place = exponent - significant + 1;      // 10^last_place is the resolution
  const int decimals = last_place < 0 ? -last_place : 0;
  const double step = std::pow(10.0, last_place);
  const double u_rounded = std::round(u / step) * step;
  const double v_rounded = std::round(value / step) * step;
  return {fmt::format("{:.{}f}", v_rounded == 0.0 ? 0.0 : v_rounded, decimals),
          fmt::format("{:.{}f}", u_rounded, decimals)};
}

}  // namespace metro
