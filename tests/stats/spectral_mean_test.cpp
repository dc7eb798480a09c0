#include "metro/stats/spectral_mean.hpp"

#include <catch2/catch.hpp>
#include <cmath>
#include <pcg_random.hpp>
#include <random>
#include <vector>

namespace metro {
namespace {

// x_t = phi_1 x_{t-1} + phi_2 x_{t-2} + e_t, e ~ N(0, 1), after a burn-in of 1000.
std::vector<double> Ar2(double phi1, double phi2, size_t n, uint64_t seed) {
  pcg64 rng(seed);
  std::normal_distribution<double> g;
  double x1 = 0.0, x2 = 0.0;
  std::vector<double> x(n);
  for (size_t i = 0; i < n + 1000; ++i) {
    const double v = phi1 * x1 + phi2 * x2 + g(rng);
    x2 = x1;
    x1 = v;
    if (i >= 1000) x[i - 1000] = v;
  }
  return x;
}

TEST_CASE("AR spectral u of the mean: white noise gives sigma / sqrt(n)", "[stats][u_mean]") {
  const size_t n = 100000;
  const std::vector<double> x = Ar2(0.0, 0.0, n, 11);
  auto r = ArSpectralMeanUncertainty(x.data(), n);
  REQUIRE(r.ok());
  // sigma = 1; R = sqrt(1/(2n) + 1/n) = 0.4 %: 2 % is 5 R.
  CHECK(r.value().u_mean == Approx(1.0 / std::sqrt(n)).epsilon(0.02));
  CHECK(r.value().order <= 3);
}

TEST_CASE("AR spectral u of the mean: AR(1) closed form sigma_e / ((1 - phi) sqrt(n))",
          "[stats][u_mean]") {
  // S(0) = sigma_e^2 / (1 - phi)^2 = sigma^2 (1 + phi) / (1 - phi), sigma^2 the marginal
  // variance. R = sqrt(1/(2n) + (1 + phi)/(n (1 - phi))) = 0.6 % at phi = 0.5, n = 1e5.
  for (double phi : {0.5, 0.9}) {
    const size_t n = 200000;
    const std::vector<double> x = Ar2(phi, 0.0, n, 5 + static_cast<uint64_t>(10 * phi));
    auto r = ArSpectralMeanUncertainty(x.data(), n);
    REQUIRE(r.ok());
    const double exact = 1.0 / ((1.0 - phi) * std::sqrt(static_cast<double>(n)));
    const double rel = std::sqrt(0.5 / n + (1.0 + phi) / (n * (1.0 - phi)));
    INFO("phi " << phi << " order " << r.value().order);
    CHECK(std::abs(r.value().u_mean / exact - 1.0) < 4.0 * rel);
    CHECK(r.value().phi.at(0) == Approx(phi).margin(0.01));
  }
}

TEST_CASE("AR spectral dof follow the delta method's closed forms for AR(1) and AR(2)",
          "[stats][u_mean]") {
  SECTION("AR(1): R^2 = 1/(2n) + (1 + phi)/(n (1 - phi))") {
    const size_t n = 500;
    const std::vector<double> x = Ar2(0.8, 0.0, n, 21);
    ArSpectralOptions o;
    o.max_order = 1;
    auto r = ArSpectralMeanUncertainty(x.data(), n, o);
    REQUIRE(r.ok());
    REQUIRE(r.value().order == 1);
    const double phi = r.value().phi[0];
    const double r2 = 0.5 / n + (1.0 + phi) / (n * (1.0 - phi));
    CHECK(r.value().dof == Approx(0.5 / r2).epsilon(1e-12));
    // u from the bias-corrected A(1) = 1 - phi - (1 + 3 phi)/n.
    const double a1 = 1.0 - phi - (1.0 + 3.0 * phi) / n;
    CHECK(r.value().u_mean ==
          Approx(std::sqrt(r.value().innovation_variance / (a1 * a1) / n)).epsilon(1e-12));
  }
  SECTION("AR(2): 1' sigma^2 Gamma^-1 1 = 2 (1 + phi_2)(1 - phi_1 - phi_2)") {
    const size_t n = 5000;
    const std::vector<double> x = Ar2(1.2, -0.3, n, 22);
    ArSpectralOptions o;
    o.max_order = 2;
    auto r = ArSpectralMeanUncertainty(x.data(), n, o);
    REQUIRE(r.ok());
    REQUIRE(r.value().order == 2);
    const double p1 = r.value().phi[0], p2 = r.value().phi[1];
    CHECK(p1 == Approx(1.2).margin(0.03));
    CHECK(p2 == Approx(-0.3).margin(0.03));
    const double a1 = 1.0 - p1 - p2;
    const double q = 2.0 * (1.0 + p2) * a1;
    const double r2 = 0.5 / n + q / (n * a1 * a1);
    CHECK(r.value().dof == Approx(0.5 / r2).epsilon(1e-9));
  }
}

TEST_CASE("AR spectral u of the mean refuses what it cannot fit", "[stats][u_mean]") {
  const std::vector<double> three = {1.0, 2.0, 3.0};
  CHECK_FALSE(ArSpectralMeanUncertainty(three.data(), three.size()).ok());
  const std::vector<double> constant(50, 2.5);
  auto r = ArSpectralMeanUncertainty(constant.data(), constant.size());
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().message.find("constant") != std::string::npos);
}

}  // namespace
}  // namespace metro
