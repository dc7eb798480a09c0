#include "metro/stats/spectral_mean.hpp"

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <pcg_random.hpp>
#include <random>
#include <string>
#include <utility>
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

namespace metro {
namespace {

// Burg's method the textbook way (Brockwell & Davis 2002, 5.1.2), in 80-bit arithmetic: the
// reference for both ways metro forms Burg's sums. Returns the innovation variance and
// A(1) = 1 - sum phi at the AIC order, with the same order cap.
struct ReferenceBurg {
  int order = 0;
  long double innovation_variance = 0.0L;
  long double a1 = 1.0L;
};

ReferenceBurg ReferenceBurgFit(const std::vector<double>& x) {
  using Ld = long double;
  const size_t n = x.size();
  Ld mean = 0.0L;
  for (double v : x) mean += v;
  mean /= static_cast<Ld>(n);
  std::vector<Ld> f(n), b(n);
  Ld e0 = 0.0L;
  for (size_t i = 0; i < n; ++i) {
    f[i] = x[i] - mean;
    e0 += f[i] * f[i];
  }
  b = f;
  const int cap = std::max(
      1, std::min(static_cast<int>(std::floor(10.0 * std::log10(n))), static_cast<int>(n / 10)));
  std::vector<Ld> phi, next;
  Ld e = e0 / static_cast<Ld>(n);
  Ld best_aic = static_cast<Ld>(n) * std::log(e);
  ReferenceBurg best;
  best.innovation_variance = e;
  for (int p = 1; p <= cap; ++p) {
    Ld num = 0.0L, den = 0.0L;
    for (size_t t = static_cast<size_t>(p); t < n; ++t) {
      num += f[t] * b[t - 1];
      den += f[t] * f[t] + b[t - 1] * b[t - 1];
    }
    const Ld k = 2.0L * num / den;
    next.assign(static_cast<size_t>(p), 0.0L);
    for (int j = 1; j < p; ++j) next[j - 1] = phi[j - 1] - k * phi[p - j - 1];
    next[p - 1] = k;
    phi.swap(next);
    for (size_t t = n - 1; t >= static_cast<size_t>(p); --t) {
      const Ld ft = f[t];
      f[t] = ft - k * b[t - 1];
      b[t] = b[t - 1] - k * ft;
    }
    e *= 1.0L - k * k;
    const Ld aic = static_cast<Ld>(n) * std::log(e) + 2.0L * p;
    if (aic < best_aic) {
      best_aic = aic;
      best.order = p;
      best.innovation_variance = e;
      best.a1 = 1.0L;
      for (Ld v : phi) best.a1 -= v;
    }
  }
  return best;
}

}  // namespace

TEST_CASE("AR spectral: Burg's sums from lag products agree with an 80-bit lattice",
          "[stats][u_mean]") {
  // Series where Burg's sums cancel most: near unit roots, a random walk, a smooth
  // doubly-integrated series, a large offset, quantized readings, short records. Both of
  // metro's ways must give the reference's order, and innovation variance and A(1) to 1e-9
  // (the double lattice is off by up to about 2e-9 itself on the random walk).
  pcg64 rng(2026);
  std::normal_distribution<double> g;
  std::vector<std::pair<std::string, std::vector<double>>> cases;
  for (size_t n : {12u, 200u, 5000u, 100000u}) {
    std::vector<double> walk(n), smooth(n), offset(n), quantized(n);
    double s = 0.0, s1 = 0.0, s2 = 0.0, r = 0.0;
    for (size_t i = 0; i < n; ++i) {
      s += g(rng);
      walk[i] = s;
      s1 = 0.99 * s1 + g(rng);
      s2 = 0.99 * s2 + s1;
      smooth[i] = s2 + 1e-3 * g(rng);
      r = 0.999 * r + g(rng);
      offset[i] = 1000.0 + r;
      quantized[i] = std::round(50.0 * std::sin(0.01 * static_cast<double>(i)) + 3.0 * g(rng));
    }
    cases.emplace_back("random walk n=" + std::to_string(n), walk);
    cases.emplace_back("smooth n=" + std::to_string(n), smooth);
    cases.emplace_back("AR(1) 0.999 + 1000 n=" + std::to_string(n), offset);
    cases.emplace_back("quantized sine n=" + std::to_string(n), quantized);
    cases.emplace_back("AR(2) n=" + std::to_string(n), Ar2(1.2, -0.5, n, n));
  }
  for (const auto& [name, x] : cases) {
    CAPTURE(name);
    const ReferenceBurg ref = ReferenceBurgFit(x);
    for (auto method :
         {ArSpectralOptions::Method::kLagProducts, ArSpectralOptions::Method::kLattice}) {
      CAPTURE(static_cast<int>(method));
      ArSpectralOptions o;
      o.method = method;
      auto r = ArSpectralMeanUncertainty(x.data(), x.size(), o);
      REQUIRE(r.ok());
      CHECK(r.value().order == ref.order);
      const double e_ref = static_cast<double>(ref.innovation_variance);
      const double a1_ref = static_cast<double>(ref.a1);
      const double a1 = 1.0 - r.value().sum_phi;
      const double tol = method == ArSpectralOptions::Method::kLagProducts ? 1e-9 : 5e-9;
      CHECK(std::abs(r.value().innovation_variance / e_ref - 1.0) < tol);
      CHECK(std::abs(a1 / a1_ref - 1.0) < tol);
    }
  }
}

}  // namespace metro
