#include "metro/core/rounding.hpp"

#include <catch2/catch.hpp>

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

}  // namespace
}  // namespace metro
