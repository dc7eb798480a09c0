#include "metro/noise/edf.hpp"

#include <catch2/catch.hpp>
#include <cmath>

namespace metro {
namespace {

TEST_CASE("Greenhall-Riley EDF equals the exact Gaussian EDF in closed-form cases", "[noise]") {
  // Non-overlapping ADEV, white PM (alpha = 2): the second differences z_k of white phase at
  // stride m have autocovariances 6, -4, 1 (lags 0, 1, 2), so for M terms
  //   edf = 2 E[sum z^2]^2 / Var[sum z^2] = 36 M^2 / (36 M + 32 (M - 1) + 2 (M - 2))
  //       = M / (35/18 - 1/M), which is Greenhall & Riley case 4 with a0 = C(8,4)/C(4,2)^2.
  for (int64_t m : {1, 4, 16, 100}) {
    const int64_t n_phase = 10001;
    const double big_m = static_cast<double>((n_phase - 1) / m - 1);
    const double exact = 36.0 * big_m * big_m / (70.0 * big_m - 36.0);
    const Result<double> edf = GreenhallRileyEdf(2, 2, m, n_phase, false, false);
    REQUIRE(edf.ok());
    CHECK(edf.value() == Approx(exact).epsilon(1e-9));
  }
  // Non-overlapping ADEV, white FM (alpha = 0), m >= 34 so that F = infinity: the first
  // differences of independent tau-averages have autocovariances 2, -1, so
  //   edf = 2 (2M)^2 / (2 (4M + 2(M - 1))) = 2 M^2 / (3M - 1).
  for (int64_t m : {34, 100, 1000}) {
    const int64_t n_phase = 200001;
    const double big_m = static_cast<double>((n_phase - 1) / m - 1);
    const Result<double> edf = GreenhallRileyEdf(0, 2, m, n_phase, false, false);
    REQUIRE(edf.ok());
    CHECK(edf.value() == Approx(2.0 * big_m * big_m / (3.0 * big_m - 1.0)).epsilon(1e-9));
  }
}

TEST_CASE("Greenhall-Riley EDF agrees with the simple SP 1065 Table 5 forms", "[noise]") {
  // The closed forms are approximations (Howe, Allan & Barnes 1981); the general method must
  // stay within 30 % of them over the usual range m <= N / 5. The flicker PM form is left out:
  // it ignores the measurement bandwidth that Greenhall-Riley's b0 + b1 ln(m) carries, and
  // differs by up to 60 % at N = 20001 (the general method matches Stable32 on the OCXO).
  for (int64_t n_phase : {101, 1001, 20001}) {
    for (int alpha : {2, 0, -1, -2}) {
      for (int64_t m : {1, 2, 8, 20, 64, 200, 1000}) {
        if (m > (n_phase - 1) / 5) continue;
        const Result<double> gr = GreenhallRileyEdf(alpha, 2, m, n_phase, true, false);
        const Result<double> simple = SimpleOadevEdf(alpha, m, n_phase);
        REQUIRE(gr.ok());
        REQUIRE(simple.ok());
        INFO("N = " << n_phase << " alpha = " << alpha << " m = " << m);
        CHECK(std::fabs(gr.value() / simple.value() - 1.0) < 0.3);
      }
    }
  }
  // The white FM form at m = 1 is exact for discrete white frequency noise: 2/3 (N - 2)
  // asymptotically (autocovariances 2, -1 of first differences).
  CHECK(SimpleOadevEdf(0, 1, 100001).value() == Approx(2.0 / 3.0 * 100000).epsilon(1e-3));
}

TEST_CASE("Chi-squared interval brackets the deviation as SP 1065 5.3.2 says", "[noise]") {
  // For large nu, chi2_p(nu) ~ nu + z_p sqrt(2 nu), so the interval is about
  // s (1 -+ z / sqrt(2 nu)); at 68.3 % z = 1.
  const Result<DeviationInterval> ci = ChiSquaredInterval(1.0, 20000.0, 0.683);
  REQUIRE(ci.ok());
  CHECK(ci.value().low == Approx(1.0 - 1.0 / std::sqrt(40000.0)).epsilon(2e-4));
  CHECK(ci.value().high == Approx(1.0 + 1.0 / std::sqrt(40000.0)).epsilon(2e-4));
  // nu = 2: chi2 quantiles are -2 ln(1 - p): exact.
  const Result<DeviationInterval> two = ChiSquaredInterval(3.0, 2.0, 0.9);
  REQUIRE(two.ok());
  CHECK(two.value().low == Approx(3.0 * std::sqrt(2.0 / (-2.0 * std::log(0.05)))).epsilon(1e-9));
  CHECK(two.value().high == Approx(3.0 * std::sqrt(2.0 / (-2.0 * std::log(0.95)))).epsilon(1e-9));
}

TEST_CASE("EDF and interval refuse bad input with a message", "[noise]") {
  CHECK(GreenhallRileyEdf(3, 2, 1, 100, true, false).error().message ==
        "EDF: noise exponent alpha = 3 is outside [-4, 2]");
  CHECK(GreenhallRileyEdf(-3, 2, 1, 100, true, false).error().message ==
        "EDF: alpha = -3 needs a difference order d > 2 (alpha + 2d > 1)");
  CHECK(GreenhallRileyEdf(0, 4, 1, 100, true, false).error().message ==
        "EDF: difference order d = 4 is not 1..3");
  CHECK(GreenhallRileyEdf(0, 2, 0, 100, true, false).error().message ==
        "EDF: averaging factor m = 0 is below 1");
  CHECK(GreenhallRileyEdf(0, 2, 60, 100, true, false).error().message ==
        "EDF: 100 phase points are fewer than the filter length L = 121 at m = 60");
  CHECK(SimpleOadevEdf(3, 1, 100).error().message == "simple EDF: alpha = 3 is outside [-2, 2]");
  CHECK(SimpleOadevEdf(0, 60, 100).error().message ==
        "simple EDF: 100 phase points are too few for m = 60");
  CHECK(ChiSquaredInterval(1.0, 0.0, 0.683).error().message ==
        "confidence interval: EDF 0 is not a positive number");
  CHECK(ChiSquaredInterval(1.0, 5.0, 1.5).error().message ==
        "confidence interval: level 1.5 is not in (0, 1)");
  CHECK(ChiSquaredInterval(-1.0, 5.0, 0.5).error().message ==
        "confidence interval: deviation -1 is not >= 0");
}

}  // namespace
}  // namespace metro
