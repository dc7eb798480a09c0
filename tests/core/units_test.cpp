// Units through UDUNITS-2: conversions against their definitions (SI Brochure 2019; CGPM
// 1901 standard gravity), metro's aliases, and the refusals.
#include "metro/core/units.hpp"

#include <catch2/catch.hpp>
#include <cmath>
#include <thread>
#include <vector>

namespace metro {
namespace {

PhysicalUnit U(const std::string& text) {
  auto u = PhysicalUnit::Parse(text);
  if (!u.ok()) FAIL(u.error().ToString());
  return u.value();
}

UnitConversion Conv(const std::string& from, const std::string& to) {
  auto c = U(from).ConversionTo(U(to));
  REQUIRE(c.has_value());
  return *c;
}

TEST_CASE("Angle, rate and acceleration conversions match their definitions", "[core][units]") {
  // 30 deg = pi/6 rad = 0.5235987755982988 rad.
  CHECK(Conv("deg", "rad").ConvertValue(30.0) == Approx(0.5235987755982988).epsilon(1e-15));
  CHECK(Conv("rad", "deg").ConvertValue(0.5235987755982988) == Approx(30.0).epsilon(1e-15));
  // 1 g_n = 9.80665 m/s^2 exactly (CGPM 1901); g0 and mps2 are metro aliases.
  CHECK(Conv("g_n", "m/s^2").ConvertValue(1.0) == Approx(9.80665).epsilon(1e-15));
  CHECK(Conv("g0", "mps2").ConvertValue(2.0) == Approx(19.6133).epsilon(1e-15));
  CHECK(Conv("mg_n", "m/s^2").factor == Approx(9.80665e-3).epsilon(1e-15));
  // deg/s and its alias dps: 90 deg/s = pi/2 rad/s.
  CHECK(Conv("deg/s", "rad/s").ConvertValue(90.0) == Approx(M_PI / 2).epsilon(1e-15));
  CHECK(Conv("dps", "rad/s").factor == Approx(M_PI / 180).epsilon(1e-15));
  CHECK(Conv("dps", "deg/s").IsIdentity());
  // Offset scale: 20 degC = 293.15 K, a difference converts by the factor alone.
  const UnitConversion c = Conv("degC", "K");
  CHECK(c.ConvertValue(20.0) == Approx(293.15).epsilon(1e-14));
  CHECK(c.ConvertDifference(0.5) == Approx(0.5).epsilon(1e-14));
  CHECK_FALSE(c.IsIdentity());
  // mg is the milligram (JCGM 101 9.3): 1 mg = 1e-6 kg.
  CHECK(Conv("mg", "kg").factor == Approx(1e-6).epsilon(1e-15));
}

TEST_CASE("Bare g is the gram; standard gravity is g_n or g0", "[core][units]") {
  CHECK(U("g").ConvertibleTo(U("kg")));
  CHECK_FALSE(U("g").ConvertibleTo(U("m/s^2")));
  CHECK(U("g0").ConvertibleTo(U("m/s^2")));
  // UDUNITS alone would read g0 as g^0 = 1: metro's alias must not be dimensionless.
  CHECK_FALSE(U("g0").IsDimensionless());
  CHECK(U("g0/s").ConvertibleTo(U("m/s^3")));
}

TEST_CASE("Plane angles and counts are dimensionless; rad is the same unit as 1", "[core][units]") {
  CHECK(U("rad").SameAs(PhysicalUnit::One()));
  CHECK(U("LSB").SameAs(U("1")));
  CHECK(U("deg").IsDimensionless());
  CHECK_FALSE(U("deg").SameAs(U("rad")));
  CHECK_FALSE(U("m").IsDimensionless());
  CHECK(U("%").ConversionTo(U("1"))->factor == Approx(0.01));
}

TEST_CASE("Products, powers and roots of units", "[core][units]") {
  CHECK(U("cm").Multiply(U("cm")).value().SameAs(U("cm^2")));
  CHECK(U("kg").Divide(U("m^3")).value().SameAs(U("kg/m^3")));
  CHECK(U("degC").Multiply(U("1/degC")).value().SameAs(U("1")));
  auto cubed = U("m").Raise(3);
  REQUIRE(cubed.ok());
  CHECK(cubed.value().SameAs(U("m3")));
  auto root = U("m^2/s^2").Root(2);
  REQUIRE(root.ok());
  CHECK(root.value().SameAs(U("m/s")));
  CHECK_FALSE(U("m").Root(2).ok());
  CHECK_FALSE(U("s").ConversionTo(U("m")).has_value());
}

TEST_CASE("Unknown and empty units are refused with the text", "[core][units]") {
  auto bad = PhysicalUnit::Parse("furlongz");
  REQUIRE_FALSE(bad.ok());
  CHECK(bad.error().message.find("unknown unit 'furlongz'") != std::string::npos);
  CHECK_FALSE(PhysicalUnit::Parse("").ok());
  CHECK_FALSE(PhysicalUnit::Parse("m//s").ok());
  CHECK(U(" deg ").ToString() == "deg");
}

TEST_CASE("Units may be parsed and converted from several threads", "[core][units]") {
  std::vector<std::thread> threads;
  std::vector<double> results(4, 0.0);
  for (size_t t = 0; t < results.size(); ++t) {
    threads.emplace_back([t, &results] {
      double sum = 0.0;
      for (int i = 0; i < 200; ++i) {
        auto a = PhysicalUnit::Parse("deg/s");
        auto b = PhysicalUnit::Parse("rad/s");
        if (a.ok() && b.ok()) sum += a.value().ConversionTo(b.value())->factor;
      }
      results[t] = sum;
    });
  }
  for (auto& thread : threads) thread.join();
  for (double r : results) CHECK(r == Approx(200 * M_PI / 180));
}

}  // namespace
}  // namespace metro
