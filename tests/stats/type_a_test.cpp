#include "metro/stats/type_a.hpp"

#include <boost/math/distributions/students_t.hpp>
#include <catch2/catch.hpp>
#include <cmath>
#include <pcg_random.hpp>
#include <random>
#include <string>
#include <vector>

namespace metro {
namespace {

// Zhang's AR(1) test series, 40 values, for the autocorrelation-aware u(mean) of N. F. Zhang,
// "Calculation of the uncertainty of the mean of autocorrelated measurements", Metrologia 43
// (2006) S276 (method in docs/type-a.md).
const std::vector<double> kZhang = {10.720, 9.604,  8.076,  9.778,  9.275,  11.098, 12.365, 11.155,
                                    11.885, 10.940, 11.828, 10.956, 10.438, 10.223, 9.745,  11.923,
                                    11.896, 11.593, 10.970, 10.009, 9.842,  11.801, 11.709, 12.945,
                                    12.573, 12.190, 12.354, 11.497, 10.956, 9.175,  9.629,  9.952,
                                    12.483, 11.300, 10.330, 12.609, 11.197, 10.929, 9.338,  9.421};

TEST_CASE("Type A reproduces Zhang 2006 autocorrelated example", "[stats][type_a]") {
  auto r = EvaluateTypeA(kZhang.data(), kZhang.size());
  REQUIRE(r.ok());
  const TypeAResult& a = r.value();
  CHECK(a.n == 40);
  CHECK(a.dof == 39);
  CHECK(a.mean == Approx(10.917675).margin(5e-7));
  CHECK(a.std == Approx(1.163614).margin(5e-7));
  CHECK(a.std_of_mean == Approx(0.183984).margin(5e-7));
  CHECK(a.rho1 == Approx(0.490258).margin(5e-7));
  CHECK(a.cutoff_lag == 1);
  CHECK(a.std_of_mean_autocorr == Approx(0.257314).margin(5e-7));
  CHECK(a.n_eff == Approx(20.45).margin(5e-3));
  CHECK_FALSE(a.cutoff_reached_limit);
}

TEST_CASE("Type A of 1..n matches the closed forms", "[stats][type_a]") {
  // mean (n+1)/2, variance n(n+1)/12 for the integers 1..n.
  const int n = 1001;
  std::vector<double> x(n);
  for (int i = 0; i < n; ++i) x[i] = i + 1;
  TypeAOptions no_ac;
  no_ac.autocorrelation = false;
  auto r = EvaluateTypeA(x.data(), x.size(), no_ac);
  REQUIRE(r.ok());
  CHECK(r.value().mean == Approx(501.0).epsilon(1e-15));
  CHECK(r.value().variance == Approx(n * (n + 1) / 12.0).epsilon(1e-14));
  CHECK(r.value().variance_of_mean == Approx(n * (n + 1) / 12.0 / n).epsilon(1e-14));
}

TEST_CASE("Type A is stable on a large offset", "[stats][type_a]") {
  // Values 1e9 + {0.1, 0.2, 0.3} * k pattern: a naive sum of squares loses every digit.
  std::vector<double> x;
  for (int k = 0; k < 3000; ++k) x.push_back(1e9 + 0.1 * (k % 3));
  TypeAOptions no_ac;
  no_ac.autocorrelation = false;
  auto r = EvaluateTypeA(x.data(), x.size(), no_ac);
  REQUIRE(r.ok());
  // Exact variance of the repeating {0, 0.1, 0.2}: mean 0.1, sum of squares per period
  // 0.02, so s^2 = 1000 * 0.02 / 2999.
  CHECK(r.value().variance == Approx(1000 * 0.02 / 2999.0).epsilon(1e-6));
  CHECK(r.value().mean - 1e9 == Approx(0.1).epsilon(1e-6));
}

TEST_CASE("A deterministic pattern gets the classical u of the mean, with a note",
          "[stats][type_a][u_mean]") {
  // 0, 0.02, 0.04, 0.01, 0.03 repeated: an AR(4) predicts it exactly, and its spectral density
  // at zero (about 2e-17 once) is no uncertainty; s / sqrt(n) stands, with 199 dof.
  std::vector<double> x;
  for (int k = 0; k < 200; ++k) x.push_back(0.01 * ((k * 7) % 5));
  auto r = EvaluateTypeA(x.data(), x.size(), TypeAOptions{});
  REQUIRE(r.ok());
  // Per period: values 0..0.04 in 0.01 steps, mean 0.02, sum of squares 0.001.
  const double s2 = 40 * 0.001 / 199.0;
  CHECK(r.value().u_mean == Approx(std::sqrt(s2 / 200.0)).epsilon(1e-9));
  CHECK(r.value().u_mean_dof == 199.0);
  CHECK(r.value().u_mean_method == kUMeanClassical);
  CHECK_THAT(r.value().u_mean_note, Catch::Contains("deterministic pattern"));
}

TEST_CASE("FFT autocorrelation equals the direct sums", "[stats][type_a]") {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> normal;
  std::vector<double> x(5003);
  double prev = 0.0;
  for (double& v : x) v = prev = 0.9 * prev + normal(rng);
  std::vector<double> rho(200);
  Autocorrelation(x.data(), x.size(), 199, rho.data());
  double mean = 0.0;
  for (double v : x) mean += v;
  mean /= x.size();
  double c0 = 0.0;
  for (double v : x) c0 += (v - mean) * (v - mean);
  for (size_t k : {size_t{1}, size_t{5}, size_t{17}, size_t{100}, size_t{199}}) {
    double ck = 0.0;
    for (size_t i = 0; i + k < x.size(); ++i) ck += (x[i] - mean) * (x[i + k] - mean);
    CHECK(rho[k] == Approx(ck / c0).margin(1e-12));
  }
}

// Zhang's variance factor computed by definition: direct lag sums, Bartlett band, no FFT.
double DirectVarianceFactor(const std::vector<double>& x, double confidence, size_t* cutoff) {
  const double n = static_cast<double>(x.size());
  double mean = 0.0;
  for (double v : x) mean += v;
  mean /= n;
  double c0 = 0.0;
  for (double v : x) c0 += (v - mean) * (v - mean);
  const boost::math::students_t t_dist(n - 1.0);
  const double t_q = boost::math::quantile(boost::math::complement(t_dist, (1 - confidence) / 2));
  double factor = 1.0, sum_rho2 = 0.0;
  for (size_t k = 1; k <= x.size() / 4; ++k) {
    double ck = 0.0;
    for (size_t i = 0; i + k < x.size(); ++i) ck += (x[i] - mean) * (x[i + k] - mean);
    const double rho = ck / c0;
    if (std::abs(rho) <= t_q * std::sqrt((1.0 + 2.0 * sum_rho2) / n)) {
      *cutoff = k - 1;
      return factor;
    }
    factor += 2.0 * (1.0 - static_cast<double>(k) / n) * rho;
    sum_rho2 += rho * rho;
  }
  *cutoff = x.size() / 4;
  return factor;
}

TEST_CASE("Blocked FFT lags give the n_eff of the direct definition", "[stats][type_a]") {
  // Slowly decaying AR(1) series: cut-offs below and above the first FFT block (2048 lags),
  // so both the first block and the longer retry are exercised against direct sums.
  for (const double phi : {0.99, 0.99999}) {
    std::mt19937_64 rng(11);
    std::normal_distribution<double> normal;
    std::vector<double> x(30011);
    double prev = 0.0;
    for (double& v : x) v = prev = phi * prev + normal(rng);
    // phi near 1: add a slow drift so the correlation outlasts the first block.
    if (phi > 0.999) {
      for (size_t i = 0; i < x.size(); ++i) x[i] += 0.01 * static_cast<double>(i);
    }
    size_t cutoff = 0;
    const double factor = DirectVarianceFactor(x, 0.95, &cutoff);
    auto r = EvaluateTypeA(x.data(), x.size(), TypeAOptions{});
    REQUIRE(r.ok());
    CHECK(r.value().cutoff_lag == static_cast<int64_t>(cutoff));
    CHECK(r.value().variance_factor == Approx(factor).epsilon(1e-9));
    if (phi > 0.999) CHECK(cutoff > 2048);
    if (phi < 0.999) CHECK((cutoff > 8 && cutoff < 2048));
  }
}

TEST_CASE("n_eff of simulated AR(1) series matches theory", "[stats][type_a]") {
  // For AR(1) with coefficient phi the asymptotic variance factor is (1 + phi)/(1 - phi),
  // so n_eff = n (1 - phi)/(1 + phi). phi = 0.8 needs lags well past the direct range,
  // exercising the FFT path. Averaged over 40 series the relative error of the mean n_eff
  // is a few percent (the truncated sum slightly underestimates F).
  std::mt19937_64 rng(2024);
  std::normal_distribution<double> normal;
  const double phi = 0.8;
  const size_t n = 20000;
  double sum_ratio = 0.0;
  const int series = 40;
  for (int s = 0; s < series; ++s) {
    std::vector<double> x(n);
    double prev = normal(rng) / std::sqrt(1 - phi * phi);
    for (double& v : x) v = prev = phi * prev + normal(rng);
    auto r = EvaluateTypeA(x.data(), n);
    REQUIRE(r.ok());
    sum_ratio += r.value().n_eff / n;
    CHECK(r.value().n_eff < n / 2.0);
  }
  const double expected = (1 - phi) / (1 + phi);
  CHECK(sum_ratio / series == Approx(expected).epsilon(0.10));
}

TEST_CASE("White noise keeps n_eff near n", "[stats][type_a]") {
  std::mt19937_64 rng(99);
  std::normal_distribution<double> normal;
  std::vector<double> x(10000);
  for (double& v : x) v = normal(rng);
  auto r = EvaluateTypeA(x.data(), x.size());
  REQUIRE(r.ok());
  CHECK(r.value().n_eff > 0.9 * x.size());
  CHECK(r.value().cutoff_lag <= 2);
}

// Independent reference in long double: plain two-pass mean and variance, direct O(n K) lag
// sums about the mean, and Zhang's Bartlett-band rule written out (no FFT, no shortcuts).
struct Reference {
  long double mean = 0, variance = 0, factor = 1, n_eff = 0, std_of_mean_autocorr = 0;
  size_t cutoff = 0;
  bool reached_limit = true;
};

Reference LongDoubleReference(const std::vector<double>& x) {
  const size_t n = x.size();
  const long double dn = static_cast<long double>(n);
  Reference ref;
  long double sum = 0;
  for (double v : x) sum += v;
  ref.mean = sum / dn;
  // One refinement: at 1e6 the long double sum above is off by ~1e-12 in the mean, enough
  // to move lag sums about it by ~1e-12 of themselves through the end terms. The
  // differences x - mean are exact in long double, so their mean is the correction.
  long double residual = 0;
  for (double v : x) residual += static_cast<long double>(v) - ref.mean;
  ref.mean += residual / dn;
  std::vector<long double> d(n);
  for (size_t i = 0; i < n; ++i) d[i] = static_cast<long double>(x[i]) - ref.mean;
  long double c0 = 0;
  for (long double v : d) c0 += v * v;
  ref.variance = c0 / (dn - 1);  // JCGM 100:2008 4.2.2
  // t quantile in double, as a user would take it from a table; the rule is what matters.
  const boost::math::students_t t_dist(static_cast<double>(n) - 1.0);
  const long double t_q = boost::math::quantile(boost::math::complement(t_dist, 0.025));
  long double sum_rho2 = 0;
  ref.cutoff = n / 4;
  for (size_t k = 1; k <= n / 4; ++k) {
    long double ck = 0;
    for (size_t i = 0; i + k < n; ++i) ck += d[i] * d[i + k];
    const long double rho = ck / c0;
    if (std::fabs(rho) <= t_q * std::sqrt((1 + 2 * sum_rho2) / dn)) {
      ref.cutoff = k - 1;
      ref.reached_limit = false;
      break;
    }
    ref.factor += 2 * (1 - static_cast<long double>(k) / dn) * rho;  // Zhang (2006)
    sum_rho2 += rho * rho;
  }
  ref.n_eff = dn / ref.factor;
  ref.std_of_mean_autocorr = std::sqrt(ref.factor * ref.variance / dn);
  return ref;
}

double RelativeDifference(double value, long double reference) {
  return static_cast<double>(std::fabs((value - reference) / reference));
}

TEST_CASE("Type A agrees with a long double reference to 1e-13", "[stats][type_a][slow]") {
  // Kinds of series in a session: white (gyro), AR(1) 0.3 (az), AR(1) 0.9 (needs the FFT
  // lags), a temp_c-like drift quantised to 0.001 (cut-off beyond the first FFT block, so
  // the longer block is used from the start), and a large offset 1e6 + AR(1) noise.
  const size_t n = 24001;
  std::mt19937_64 rng(20240611);
  std::normal_distribution<double> normal;
  auto ar1 = [&](double phi, double offset, double scale) {
    std::vector<double> x(n);
    double prev = 0.0;
    for (double& v : x) v = offset + scale * (prev = phi * prev + normal(rng));
    return x;
  };
  struct Case {
    std::string name;
    std::vector<double> x;
  };
  std::vector<Case> cases = {{"white", ar1(0.0, 0.25, 1.0)},
                             {"ar1_0.3", ar1(0.3, 0.98, 0.002)},
                             {"ar1_0.9", ar1(0.9, -0.1, 0.01)},
                             {"offset_1e6", ar1(0.5, 1e6, 1e-3)}};
  std::vector<double> drift(n);
  double walk = 0.0;
  for (size_t i = 0; i < n; ++i) {
    // Warm-up ramp plus a slow random walk, read out with 0.001 resolution.
    walk += 0.002 * normal(rng);
    const double t = static_cast<double>(i) / static_cast<double>(n);
    drift[i] = std::round((25.0 + 2.0 * (1.0 - std::exp(-3.0 * t)) + walk) * 1000.0) / 1000.0;
  }
  cases.push_back({"drift", drift});

  for (const Case& c : cases) {
    INFO(c.name);
    const Reference ref = LongDoubleReference(c.x);
    auto r = EvaluateTypeA(c.x.data(), c.x.size());
    REQUIRE(r.ok());
    const TypeAResult& a = r.value();
    // The mean's rounding scales with the data, not with the mean: compare on |mean| + s.
    CHECK(std::fabs(a.mean - ref.mean) / (std::fabs(ref.mean) + std::sqrt(ref.variance)) < 2e-13);
    CHECK(RelativeDifference(a.variance, ref.variance) < 2e-13);
    CHECK(a.cutoff_lag == static_cast<int64_t>(ref.cutoff));
    CHECK(a.cutoff_reached_limit == ref.reached_limit);
    CHECK(RelativeDifference(a.variance_factor, ref.factor) < 2e-13);
    CHECK(RelativeDifference(a.n_eff, ref.n_eff) < 2e-13);
    CHECK(RelativeDifference(a.std_of_mean_autocorr, ref.std_of_mean_autocorr) < 2e-13);
    if (c.name == "white") CHECK(a.cutoff_lag <= 2);
    if (c.name == "ar1_0.9") CHECK((a.cutoff_lag > 8 && a.cutoff_lag < 2048));
    if (c.name == "drift") CHECK(a.cutoff_lag > 2048);
  }
}

TEST_CASE("Type A rejects too few or non-finite observations", "[stats][type_a]") {
  const double one = 1.0;
  auto r1 = EvaluateTypeA(&one, 1);
  REQUIRE_FALSE(r1.ok());
  CHECK(r1.error().message == "1 observation: a Type A evaluation needs at least 2");
  const std::vector<double> bad = {1.0, NAN, 2.0};
  auto r2 = EvaluateTypeA(bad.data(), bad.size());
  REQUIRE_FALSE(r2.ok());
  CHECK(r2.error().message == "observation 2 is not finite");
  // The finiteness check goes through the sum: an infinity late in the series is still named.
  std::vector<double> inf_late(1001, 1.0);
  inf_late[997] = -INFINITY;
  auto r3 = EvaluateTypeA(inf_late.data(), inf_late.size());
  REQUIRE_FALSE(r3.ok());
  CHECK(r3.error().message == "observation 998 is not finite");
  // Finite values whose sum overflows: an error, not an infinite mean.
  const std::vector<double> huge = {1.5e308, 1.6e308, 1.0};
  auto r4 = EvaluateTypeA(huge.data(), huge.size());
  REQUIRE_FALSE(r4.ok());
  CHECK(r4.error().message == "the sum of the 3 observations overflows double precision");
  // A finite sum whose squared deviations overflow (issue #20: u = inf, then NaN, exit 0).
  const std::vector<double> wide = {1e308, -1e308, 1e308, -1e308};
  auto r5 = EvaluateTypeA(wide.data(), wide.size());
  REQUIRE_FALSE(r5.ok());
  CHECK(r5.error().message.rfind("the sum of squared deviations of the 4 observations "
                                 "overflows double precision",
                                 0) == 0);
  // Deviations of 1e150 still square below the largest double: evaluated, exactly.
  const std::vector<double> large = {1e150, -1e150, 1e150, -1e150};
  auto r6 = EvaluateTypeA(large.data(), large.size());
  REQUIRE(r6.ok());
  CHECK(r6.value().mean == 0.0);
  CHECK(r6.value().std == Approx(std::sqrt(4.0 / 3.0) * 1e150).epsilon(1e-14));
}

// Stationary AR(1) with unit innovations, started from its stationary distribution.
std::vector<double> Ar1Series(double phi, size_t n, pcg64* rng) {
  std::normal_distribution<double> g;
  std::vector<double> x(n);
  double v = g(*rng) / std::sqrt(1.0 - phi * phi);
  for (size_t i = 0; i < n; ++i) {
    if (i > 0) v = phi * v + g(*rng);
    x[i] = v;
  }
  return x;
}

double T975(double dof) {
  return boost::math::quantile(boost::math::complement(boost::math::students_t(dof), 0.025));
}

TEST_CASE("u_mean of AR(1) matches the closed form sigma/sqrt(n) sqrt((1+phi)/(1-phi))",
          "[stats][type_a][u_mean]") {
  // Asymptotic u of the mean of AR(1) with marginal sigma: sigma/sqrt(n) sqrt((1+phi)/(1-phi)).
  pcg64 rng(2024);
  const double phi = 0.9;
  const size_t n = 20000;
  const std::vector<double> x = Ar1Series(phi, n, &rng);
  auto r = EvaluateTypeA(x.data(), n);
  REQUIRE(r.ok());
  const TypeAResult& a = r.value();
  const double sigma = 1.0 / std::sqrt(1.0 - phi * phi);
  const double exact = sigma / std::sqrt(static_cast<double>(n)) * std::sqrt((1 + phi) / (1 - phi));
  // Relative standard uncertainty of the estimate (AR(1) fit): R = sqrt(1/(2n) +
  // (1+phi)/(n(1-phi))) = 3.1 %; AIC may pick a longer model (larger R), so 4 R.
  const double rel = std::sqrt(0.5 / n + (1 + phi) / (n * (1 - phi)));
  CHECK(a.u_mean_method == std::string(kUMeanArSpectral));
  CHECK(a.u_mean == Approx(exact).epsilon(4.0 * rel));
  CHECK(a.u_mean_dof <= 0.5 / (rel * rel) * 1.05);
  CHECK_FALSE(a.drift_detected);
  CHECK(a.autocorr_computed);
}

TEST_CASE("u_mean covers the true mean of AR(1) 95 % of the time",
          "[stats][type_a][u_mean][slow]") {
  // Issue #21 part 2: mean +- t(u_mean_dof) u_mean must cover the true mean (0) in
  // 95 +- 2 % of the records for AR(1) up to phi = 0.9 at n >= 200, and below 98.5 % for
  // white noise. 2000 records per case (binomial standard deviation 0.5 points). Zhang's
  // std_of_mean_autocorr with n_eff - 1 dof is counted beside it (about 82 % at phi = 0.9,
  // n = 200, the report).
  const int records = 2000;
  for (double phi : {0.0, 0.5, 0.9}) {
    for (size_t n : {200u, 2000u}) {
      pcg64 rng(42 + n + static_cast<uint64_t>(phi * 100));
      int covered = 0, covered_zhang = 0, drift = 0;
      for (int k = 0; k < records; ++k) {
        const std::vector<double> x = Ar1Series(phi, n, &rng);
        auto r = EvaluateTypeA(x.data(), n);
        REQUIRE(r.ok());
        const TypeAResult& a = r.value();
        if (std::abs(a.mean) <= T975(a.u_mean_dof) * a.u_mean) ++covered;
        if (std::abs(a.mean) <= T975(std::max(1.0, a.n_eff - 1.0)) * a.std_of_mean_autocorr) {
          ++covered_zhang;
        }
        drift += a.drift_detected ? 1 : 0;
      }
      const double coverage = 100.0 * covered / records;
      const double coverage_zhang = 100.0 * covered_zhang / records;
      WARN("AR(1) phi " << phi << " n " << n << ": u_mean covers " << coverage << " %, Zhang "
                        << coverage_zhang << " %, drift flagged " << drift);
      CHECK(coverage >= 93.0);
      CHECK(coverage <= (phi == 0.0 ? 98.5 : 97.0));
      CHECK(drift <= records / 100);
    }
  }
}

TEST_CASE("Terms that cannot be computed are flagged, not 0 or n", "[stats][type_a][u_mean]") {
  SECTION("n = 3") {
    const std::vector<double> x = {1.0, 2.0, 4.0};
    auto r = EvaluateTypeA(x.data(), x.size());
    REQUIRE(r.ok());
    CHECK_FALSE(r.value().autocorr_computed);
    CHECK(r.value().autocorr_note.find("n = 3") != std::string::npos);
    // u_mean is the classical s/sqrt(n) with n - 1 dof: s^2 = 7/3.
    CHECK(r.value().u_mean_available);
    CHECK(r.value().u_mean == Approx(std::sqrt(7.0 / 3.0 / 3.0)).epsilon(1e-14));
    CHECK(r.value().u_mean_dof == 2.0);
    CHECK(r.value().u_mean_method == std::string(kUMeanClassical));
  }
  SECTION("a constant series") {
    const std::vector<double> x(500, 0.25);
    auto r = EvaluateTypeA(x.data(), x.size());
    REQUIRE(r.ok());
    CHECK_FALSE(r.value().autocorr_computed);
    CHECK_FALSE(r.value().u_mean_available);
    CHECK(r.value().autocorr_note.find("constant") != std::string::npos);
  }
  SECTION("n = 4 is computed") {
    const std::vector<double> x = {1.0, 2.0, 4.0, 3.0};
    auto r = EvaluateTypeA(x.data(), x.size());
    REQUIRE(r.ok());
    CHECK(r.value().autocorr_computed);
    CHECK(r.value().u_mean_method == std::string(kUMeanArSpectral));
  }
}

// ---------------------------------------------------------------- digitized readings (#36)

// GTC's type_a.estimate_digitized with independent readings (autocorrelation off).
TypeAResult Digitized(const std::vector<double>& x, double step, bool truncated = false) {
  TypeAOptions options;
  options.autocorrelation = false;
  options.quantization_step = step;
  options.truncated = truncated;
  auto r = EvaluateTypeA(x.data(), x.size(), options);
  if (!r.ok()) FAIL(r.error().ToString());
  return r.value();
}

TEST_CASE("Digitized readings reproduce GTC's four estimate_digitized examples",
          "[stats][type_a][digitized]") {
  // GTC (MSL), type_a.estimate_digitized doctests, after Willink, Metrologia 44 (2007) 73:
  // step 0.0001; ureal(value, u, df) as GTC prints them.
  struct Example {
    std::vector<double> x;
    double value, u;
    double dof;
    const char* method;
  };
  const std::vector<Example> examples = {
      // Readings between -0.0055 and -0.0057 (two steps): s / sqrt(N).
      {{-0.0056, -0.0055, -0.0056, -0.0056, -0.0056, -0.0057, -0.0057, -0.0056, -0.0056, -0.0057,
        -0.0057},
       -0.005627272727272727,
       1.9497827808661e-05,
       10,
       kUMeanClassical},
      // Between -0.0056 and -0.0057 (one step): max(s^2 / N, (x_mid - mean)^2 / 3), here s^2/N.
      {{-0.0056, -0.0056, -0.0056, -0.0056, -0.0056, -0.0057, -0.0057, -0.0056, -0.0056, -0.0057,
        -0.0057},
       -0.005636363636363636,
       1.52120004824377e-05,
       10,
       kUMeanClassical},
      // No spread, N = 11: step / sqrt(12).
      {std::vector<double>(11, -0.0056), -0.0056, 2.8867513459481e-05, 10, kUMeanDigitized},
      // No spread, N = 3: sqrt(1.3 / 12) step.
      {std::vector<double>(3, -0.0056), -0.0056, 3.2914029430219e-05, 2, kUMeanDigitized},
  };
  for (size_t k = 0; k < examples.size(); ++k) {
    INFO("example " << k + 1);
    const Example& e = examples[k];
    const TypeAResult r = Digitized(e.x, 0.0001);
    CHECK(r.mean == Approx(e.value).epsilon(1e-12));
    REQUIRE(r.u_mean_available);
    CHECK(r.u_mean == Approx(e.u).epsilon(1e-12));
    CHECK(r.u_mean_dof == e.dof);
    CHECK(r.u_mean_method == std::string(e.method));
  }
}

TEST_CASE("Digitized readings follow Willink's rules in closed form",
          "[stats][type_a][digitized]") {
  // No spread: u = sqrt(c/12) step, c = 6.4, 1.3, 1.0 for N = 2, 3, >= 4 (any N >= 4).
  for (const auto& [n, c] : {std::pair<size_t, double>{2, 6.4}, {3, 1.3}, {4, 1.0}, {500, 1.0}}) {
    INFO("N = " << n);
    const TypeAResult r = Digitized(std::vector<double>(n, 12.34), 0.01);
    CHECK(r.u_mean == Approx(std::sqrt(c / 12.0) * 0.01).epsilon(1e-14));
    CHECK(r.u_mean_dof == static_cast<double>(n - 1));
    CHECK(r.u_mean_note.find("Willink") != std::string::npos);
    // The classical numbers keep their meaning: s = 0.
    CHECK(r.std_of_mean == 0.0);
  }
  // One step where the middle term wins: 99 readings of 0 and one of 1 (step 1): mean 0.01,
  // s^2/N = 0.01^2 (s^2 = (99 * 0.01^2 + 0.99^2) / 99 = 0.01), (0.5 - 0.01)^2 / 3 larger.
  std::vector<double> lopsided(100, 0.0);
  lopsided[37] = 1.0;
  const TypeAResult one = Digitized(lopsided, 1.0);
  CHECK(one.u_mean == Approx(0.49 / std::sqrt(3.0)).epsilon(1e-14));
  CHECK(one.u_mean_method == std::string(kUMeanDigitized));
  CHECK(DigitizedUMean(100, 1.0, 0.0, 1.0, 0.01, 0.01) == Approx(0.49 / std::sqrt(3.0)));
  // Truncated readings: the mean is raised by half a step (GTC's truncate), u unchanged.
  const TypeAResult cut = Digitized(std::vector<double>(5, 2.0), 0.5, true);
  CHECK(cut.mean == 2.25);
  CHECK(cut.u_mean == Approx(0.5 / std::sqrt(12.0)).epsilon(1e-14));
  // Without a step a constant series has no u of the mean for any n (n <= 3 gave 0).
  for (size_t n : {2, 3, 4}) {
    const std::vector<double> x(n, 7.0);
    auto r = EvaluateTypeA(x.data(), x.size());
    REQUIRE(r.ok());
    CHECK_FALSE(r.value().u_mean_available);
    CHECK(r.value().autocorr_note.find("constant series") != std::string::npos);
  }
  // A spread wider than one step is not touched by the step: the same numbers as without it.
  const std::vector<double> wide = {1.0, 2.0, 4.0, 3.0, 2.0, 1.0, 3.0, 4.0};
  TypeAOptions with_step;
  with_step.quantization_step = 1.0;
  auto a = EvaluateTypeA(wide.data(), wide.size(), with_step);
  auto b = EvaluateTypeA(wide.data(), wide.size());
  REQUIRE((a.ok() && b.ok()));
  CHECK(a.value().u_mean == b.value().u_mean);
  CHECK(a.value().u_mean_method == b.value().u_mean_method);
  // A step that is not positive and finite, or truncation without a step, is refused.
  TypeAOptions bad;
  bad.truncated = true;
  CHECK_FALSE(EvaluateTypeA(wide.data(), wide.size(), bad).ok());
  bad.quantization_step = -1.0;
  CHECK_FALSE(EvaluateTypeA(wide.data(), wide.size(), bad).ok());
}

TEST_CASE("A drift the AR fit absorbs is caught by the batch-means check",
          "[stats][type_a][u_mean]") {
  // AR(1) 0.9 plus a linear drift of D per sample (2.2 marginal sigma over the record).
  // Batch means of b = 10 batches of m samples step by D m; the sample variance of b
  // equally spaced values with step h is h^2 b (b + 1) / 12, so u_batch^2 = (D m)^2
  // (b + 1) / 12 plus the noise's u of the mean^2 (AR(1) closed form sigma^2 (1+phi) /
  // ((1-phi) n), sigma^2 = 1/0.19); 20 %: a 9-dof estimate with a trend-noise cross term.
  pcg64 rng(77);
  const size_t n = 10000;
  std::vector<double> x = Ar1Series(0.9, n, &rng);
  const double drift = 5e-4;
  for (size_t i = 0; i < n; ++i) x[i] += drift * static_cast<double>(i);
  auto r = EvaluateTypeA(x.data(), n);
  REQUIRE(r.ok());
  const TypeAResult& a = r.value();
  const double m = static_cast<double>(n / kStationarityBatches);
  const double u_noise = std::sqrt(19.0 / 0.19 / static_cast<double>(n));
  const double trend = drift * m * std::sqrt((kStationarityBatches + 1) / 12.0);
  const double expected = std::hypot(trend, u_noise);
  CHECK(a.drift_detected);
  CHECK(a.u_mean_method == std::string(kUMeanBatchMeans));
  CHECK(a.u_mean == a.u_mean_batch);
  CHECK(a.u_mean_dof == kStationarityBatches - 1);
  CHECK(a.u_mean_batch == Approx(expected).epsilon(0.2));
  CHECK(a.u_mean_ar < 0.5 * a.u_mean);
  // Zhang's contract is untouched.
  CHECK(a.std_of_mean_autocorr == Approx(std::sqrt(a.variance_factor * a.variance / n)));
}

}  // namespace
}  // namespace metro
