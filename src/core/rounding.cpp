#include "metro/core/rounding.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>

namespace metro {
namespace {

// Decimal exponent of u's leading digit once u is rounded to `significant` digits
// (0.0996 at 2 digits -> 0.10 -> -1).
int RoundedExponent(double u, int significant) {
  int exponent = static_cast<int>(std::floor(std::log10(u)));
  const double scaled = std::round(u / std::pow(10.0, exponent - significant + 1));
  if (scaled >= std::pow(10.0, significant)) ++exponent;
  return exponent;
}

// "y(u)" in fixed notation with y and u already in the unit of the printed number, the last
// printed digit at 10^last_place (JCGM 100:2008 7.2.2).
std::string Concise(double value, double u, int last_place) {
  const double step = std::pow(10.0, last_place);
  const double digits_u = std::round(u / step);  // u in units of the last digit
  double v = std::round(value / step) * step;
  if (v == 0.0) v = 0.0;  // no "-0"
  const int decimals = last_place < 0 ? -last_place : 0;
  std::string bracket;
  if (last_place >= 0) {
    bracket = fmt::format("{:.0f}", digits_u * step);  // "827(50)", "830(500)"
  } else if (digits_u * step >= 1.0) {
    bracket = fmt::format("{:.{}f}", digits_u * step, decimals);  // "826.6(5.0)"
  } else {
    bracket = fmt::format("{:.0f}", digits_u);  // "100.02147(35)"
  }
  return fmt::format("{:.{}f}({})", v, decimals, bracket);
}

}  // namespace

RoundedResult RoundForStatement(double value, double u, int significant) {
  if (!std::isfinite(u) || u <= 0.0) {
    return {fmt::format("{:.6g}", value), std::isfinite(u) ? "0" : "nan"};
  }
  // Decimal exponent of u's leading digit, then the last kept decimal place.
  const int exponent = RoundedExponent(u, significant);
  const int last_place = exponent - significant + 1;  // 10^last_place is the resolution
  const int decimals = last_place < 0 ? -last_place : 0;
  const double step = std::pow(10.0, last_place);
  const double u_rounded = std::round(u / step) * step;
  const double v_rounded = std::round(value / step) * step;
  return {fmt::format("{:.{}f}", v_rounded == 0.0 ? 0.0 : v_rounded, decimals),
          fmt::format("{:.{}f}", u_rounded, decimals)};
}

RoundedInterval RoundInterval(double low, double high, int significant) {
  const double width = high - low;
  if (!std::isfinite(low) || !std::isfinite(high) || !(width > 0.0)) {
    return {fmt::format("{:.6g}", low), fmt::format("{:.6g}", high)};
  }
  const RoundedResult a = RoundForStatement(low, width, significant);
  const RoundedResult b = RoundForStatement(high, width, significant);
  return {a.value, b.value};
}

std::string ConciseNotation(double value, double u, int significant) {
  if (significant < 1) significant = 1;
  if (!std::isfinite(value)) {
    return std::isfinite(u) ? fmt::format("nan (u = {:.2g})", u) : "nan (u = nan)";
  }
  if (u == 0.0) return fmt::format("{:.6g} (u = 0)", value);
  if (!std::isfinite(u) || u < 0.0) return fmt::format("{:.6g} (u = nan)", value);
  const int exponent_u = RoundedExponent(u, significant);
  const int last_place = exponent_u - significant + 1;
  // The value's exponent after rounding to the last place (999.96(5) -> 1000.0).
  const double step = std::pow(10.0, last_place);
  const double v_rounded = std::round(value / step) * step;
  // A value more than 10^17 times its uncertainty has more digits than a double holds (and
  // value / step may overflow): print both in plain exponent form instead.
  if (!std::isfinite(v_rounded) || !std::isfinite(step) || step == 0.0 ||
      std::fabs(value) / u > 1e17) {
    return fmt::format("{:.17g} (u = {:.2g})", value, u);
  }
  const int exponent_v = v_rounded == 0.0
                             ? exponent_u
                             : static_cast<int>(std::floor(std::log10(std::fabs(v_rounded))));
  if (last_place >= -6 && last_place <= 2 && std::fabs(v_rounded) < 1e9) {
    return Concise(value, u, last_place);
  }
  // Exponent notation: y = m 10^E, u = u_m 10^E; the mantissa's last digit sits at
  // 10^(last_place - E), never above 10^0 since E >= exponent_u >= last_place.
  const int e = std::max(exponent_v, exponent_u);
  const double scale = std::pow(10.0, e);
  std::string mantissa = Concise(value / scale, u / scale, last_place - e);
  return fmt::format("{}e{}{}", mantissa, e < 0 ? "-" : "", std::abs(e));
}

}  // namespace metro
