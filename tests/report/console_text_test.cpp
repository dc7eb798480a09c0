// Console text: grouped warnings and table rounding (issue #25 point 6).
#include "metro/report/console_text.hpp"

#include <catch2/catch.hpp>

namespace metro {
namespace {

TEST_CASE("Warnings that differ only in their numbers are grouped with a count", "[report]") {
  const std::vector<WarningLine> lines = {
      {"sensor 2 qw", "n_eff = 351.5 < n/2 = 2323.5: autocorrelated, u_mean (3.7e-08, 9.0 dof)"},
      {"sensor 2 qx", "n_eff = 278.6 < n/2 = 2329.5: autocorrelated, u_mean (1.63e-05, 104 dof)"},
      {"sensor 2 qz", "drift: u of the mean 7.8e-05, more than 2x the autoregressive 3.5e-05"},
      {"sensor 3 qw", "n_eff = 12 < n/2 = 50: autocorrelated, u_mean (-2.5E+3, 9 dof)"},
      {"input", "3 rows rejected"},
      {"sensor 3 yaw_deg", "n_eff = 1.5 < n/2 = 7: autocorrelated, u_mean (0.1, 2 dof)"},
  };
  const std::string text = GroupedWarnings(lines);
  CHECK(text ==
        "  sensor 2 qw: n_eff = 351.5 < n/2 = 2323.5: autocorrelated, u_mean (3.7e-08, 9.0 dof)\n"
        "    and 3 more like it: sensor 2 qx; sensor 3 qw, yaw_deg\n"
        "  sensor 2 qz: drift: u of the mean 7.8e-05, more than 2x the autoregressive 3.5e-05\n"
        "  input: 3 rows rejected\n");
  // A digit inside a word ("gx2") is not a number: a different word is a
  // different kind.
  const std::string apart = GroupedWarnings({{"a", "gx2 is stale"}, {"b", "gx3 is stale"}});
  CHECK(apart == "  a: gx2 is stale\n  b: gx3 is stale\n");
  CHECK(GroupedWarnings({}).empty());
}

TEST_CASE("Table rounding switches to exponent notation past six decimals", "[report]") {
  // GUM 7.2.6 rounding first (u to two digits, the mean to the same place) ...
  RoundedResult r = RoundForTable(0.999999704, 3.7e-8);
  CHECK(r.value == "0.999999704");  // |mean| >= 0.001 stays fixed
  CHECK(r.uncertainty == "3.7e-08");
  r = RoundForTable(-1.83e-9, 3.9e-13);
  CHECK(r.value == "-1.83000e-09");  // last digit at 1e-14, as u's
  CHECK(r.uncertainty == "3.9e-13");
  // ... and nothing changes up to six decimals.
  r = RoundForTable(-0.0000183, 0.0000163);
  CHECK(r.value == "-0.000018");
  CHECK(r.uncertainty == "0.000016");
  r = RoundForTable(12.3456, 0.012);
  CHECK(r.value == "12.346");
  CHECK(r.uncertainty == "0.012");
  // A mean that rounds to zero stays "0.00000000".
  r = RoundForTable(1e-12, 3.7e-8);
  CHECK(r.value == "0.000000000");
  CHECK(r.uncertainty == "3.7e-08");
}

TEST_CASE("Console numbers use exponent notation below 0.001", "[report]") {
  CHECK(ConsoleNumber(0.000122) == "1.22e-04");
  CHECK(ConsoleNumber(0.0122) == "0.0122");
  CHECK(ConsoleNumber(-3.9e-13) == "-3.90e-13");
  CHECK(ConsoleNumber(12.345) == "12.3");
  CHECK(ConsoleNumber(2.5e7) == "2.50e+07");
  CHECK(ConsoleNumber(0.0) == "0");
}

}  // namespace
}  // namespace metro
