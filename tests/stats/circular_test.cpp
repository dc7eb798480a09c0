#include "metro/stats/circular.hpp"

#include <catch2/catch.hpp>
#include <cmath>

namespace metro {
namespace {

TEST_CASE("Circular statistics of angles, closed forms", "[stats]") {
  // {0, 90} deg: C = S = 1/2, mean 45 deg, R = sqrt(1/2), circular std = sqrt(-2 ln R) =
  // sqrt(ln 2) rad (Mardia & Jupp 2.3.2); with n - 1: sqrt(2 ln 2) rad.
  CircularStatistics c = CircularStatisticsDeg({0.0, 90.0});
  CHECK(c.mean_deg == Approx(45.0).margin(1e-12));
  CHECK(c.resultant_length == Approx(std::sqrt(0.5)).epsilon(1e-14));
  CHECK(c.std_deg == Approx(std::sqrt(std::log(2.0)) * 180.0 / M_PI).epsilon(1e-13));
  CHECK(c.sample_std_deg == Approx(std::sqrt(2.0 * std::log(2.0)) * 180.0 / M_PI).epsilon(1e-13));
  // Across the +-180 cut: +179.95 and -179.95 are 0.1 deg apart around 180. For a spread of
  // +-d the circular std is d (1 + O(d^2)), here 0.05 deg to 1e-7 relative, and the sample
  // std 0.05 sqrt(2) (a linear pool says mean 0, std 254.5).
  c = CircularStatisticsDeg({179.95, -179.95});
  CHECK(std::abs(c.mean_deg) == Approx(180.0).margin(1e-9));
  CHECK(c.std_deg == Approx(0.05).epsilon(1e-6));
  CHECK(c.sample_std_deg == Approx(0.05 * std::sqrt(2.0)).epsilon(1e-6));
  // Opposite directions: no mean direction (R = 0).
  c = CircularStatisticsDeg({0.0, 180.0});
  CHECK(std::isnan(c.mean_deg));
  CHECK(c.resultant_length == Approx(0.0).margin(1e-15));
  CHECK(std::isnan(CircularStatisticsDeg({}).mean_deg));
}

}  // namespace
}  // namespace metro
