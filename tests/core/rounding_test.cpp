#include "metro/core/rounding.hpp"

#include <catch2/catch.hpp>
#include <cmath>

namespace metro {
namespace {

TEST_CASE("GUM 7.2.6 rounding keeps two significant digits of u", "[core][rounding]") {
  // GUM 7.2.6 example: m_s = 100,021 47 g with u_c = 0,35 mg.
  auto a = RoundForStatement(100.02147, 0.00035);
  CHECK(a.value == "100.02147");
  CHECK(a.uncertainty == "0.00035");
  // Thesis Table 8.3, yaw: 0.18821 deg, s(mean) 0.00087 deg.
  auto b = RoundForStatement(0.188214, 0.000872);
  CHECK(b.value == "0.18821");
  CHECK(b.uncertainty == "0.00087");
  // Carry into a new digit: 0.0996 -> 0.10, value to two decimals.
  auto c = RoundForStatement(1.23456, 0.0996);
  CHECK(c.value == "1.23");
  CHECK(c.uncertainty == "0.10");
  // Large uncertainties round to integers.
  auto d = RoundForStatement(50000838.0, 31.66);
  CHECK(d.value == "50000838");
  CHECK(d.uncertainty == "32");
  auto e = RoundForStatement(1234.0, 0.0);
  CHECK(e.uncertainty == "0");
}

TEST_CASE("Coverage interval ends are printed to digits that tell them apart", "[core][rounding]") {
  // Issue #25: "{:.6g}" printed the H.1 end gauge's 99 % interval as [5.00007e+07, 5.00009e+07].
  // Width 185.5 nm: two significant digits put the last digit at the tens.
  const RoundedInterval a = RoundInterval(50000745.3, 50000930.8);
  CHECK(a.low == "50000750");
  CHECK(a.high == "50000930");
  // Width 0.01229 (0.012 to two digits): the last digit at 10^-3, the high end carries.
  const RoundedInterval b = RoundInterval(0.98764, 0.99993);
  CHECK(b.low == "0.988");
  CHECK(b.high == "1.000");
  // Three significant digits of the width (0.0123): one digit further.
  const RoundedInterval c = RoundInterval(0.98764, 0.99993, 3);
  CHECK(c.low == "0.9876");
  CHECK(c.high == "0.9999");
  // Nothing to tell apart: plain.
  const RoundedInterval d = RoundInterval(2.0, 2.0);
  CHECK(d.low == "2");
  CHECK(d.high == "2");
}

TEST_CASE("JCGM 100 7.2.2 concise notation", "[core][rounding]") {
  // The GUM's own example (7.2.2): m_S = 100.021 47(35) g.
  CHECK(ConciseNotation(100.02147, 0.00035) == "100.02147(35)");
  // issue #21: calibrate report printed "826.6026 (50)" (read as u = 0.0050) for u = 49.5.
  CHECK(ConciseNotation(826.6026, 49.5) == "827(50)");
  // u spans the decimal point: written out in the value's units (7.2.2, second form).
  CHECK(ConciseNotation(826.6026, 4.95) == "826.6(5.0)");
  CHECK(ConciseNotation(12.34, 1.46) == "12.3(1.5)");
  CHECK(ConciseNotation(0.5, 3.2) == "0.5(3.2)");
  CHECK(ConciseNotation(123.4, 25.3) == "123(25)");
  CHECK(ConciseNotation(826.6, 495.0) == "830(500)");  // u = 5.0 x 10^2: u as is
  // Two significant digits, the carry into a new digit (0.0996 -> 0.10).
  CHECK(ConciseNotation(1.23456, 0.0996) == "1.23(10)");
  CHECK(ConciseNotation(0.188214, 0.000872) == "0.18821(87)");
  CHECK(ConciseNotation(0.188214, 0.000872, 1) == "0.1882(9)");
  // Negative values and a value that rounds to zero (never "-0.0000").
  CHECK(ConciseNotation(-0.0123456, 0.00045) == "-0.01235(45)");
  CHECK(ConciseNotation(-3.9e-13, 1.2e-13) == "-3.9(1.2)e-13");
  CHECK(ConciseNotation(-0.00004, 0.0012) == "0.0000(12)");
  // Exponent notation when fixed would need more than six decimals or zeros beyond the
  // hundreds: the mantissa carries one digit before the point.
  CHECK(ConciseNotation(0.00000000000039, 0.00000000000012) == "3.9(1.2)e-13");
  CHECK(ConciseNotation(1.23456789e-9, 1.2e-13) == "1.23457(12)e-9");
  CHECK(ConciseNotation(2.0e-15, 1.2e-13) == "0.0(1.2)e-13");
  CHECK(ConciseNotation(1.5e12, 3.04e10) == "1.500(30)e12");
  CHECK(ConciseNotation(0.0000012345, 0.0000000021) == "1.2345(21)e-6");
  // GUM H.1: l = 50 000 838 nm, u = 32 nm stays fixed (below 1e9).
  CHECK(ConciseNotation(50000838.0, 31.66) == "50000838(32)");
  // No uncertainty, or none that can be printed.
  CHECK(ConciseNotation(1234.5, 0.0) == "1234.5 (u = 0)");
  CHECK(ConciseNotation(1234.5, std::nan("")) == "1234.5 (u = nan)");
  CHECK(ConciseNotation(std::nan(""), 0.5) == "nan (u = 0.5)");
  // More digits than a double holds (the calibration fuzzer's 1e300 with u = 1e-300 overflowed
  // value / step): both printed as they are.
  CHECK(ConciseNotation(1e300, 1e-300) == "1.0000000000000001e+300 (u = 1e-300)");
  CHECK(ConciseNotation(68.6, 1e-300) == "68.599999999999994 (u = 1e-300)");
  CHECK(ConciseNotation(-1e308, 1e308) == "-1.0(1.0)e308");
}

}  // namespace
}  // namespace metro
