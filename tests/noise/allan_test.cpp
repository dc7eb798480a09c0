#include "metro/noise/allan.hpp"

#include <catch2/catch.hpp>
#include <cmath>
#include <string>
#include <vector>

#include "metro/noise/edf.hpp"
#include "noise/noise_simulation.hpp"
#include "noise/noise_test_data.hpp"

namespace metro {
namespace {

using testing::ExternalDataPath;
using testing::ReadStable32;

const std::vector<double> kNbs14 = {892, 809, 823, 798, 671, 644, 883, 903, 677};

double Dev(const std::vector<double>& y, int64_t m, AllanEstimator e) {
  const std::vector<double> x = PhaseFromRate(y, 1.0);
  return std::sqrt(AllanVariances(x, 1.0, {m}, e, 1)[0]);
}

TEST_CASE("NBS14 nine-point set matches the published statistics", "[noise]") {
  // NIST SP 1065 (Riley) test suite, tau0 = 1.
  CHECK(Dev(kNbs14, 1, AllanEstimator::kOadev) == Approx(91.22945).epsilon(1e-7));
  CHECK(Dev(kNbs14, 2, AllanEstimator::kOadev) == Approx(85.95287).epsilon(1e-7));
  CHECK(Dev(kNbs14, 2, AllanEstimator::kAdev) == Approx(115.8082).epsilon(1e-6));
  CHECK(Dev(kNbs14, 2, AllanEstimator::kMdev) == Approx(74.78849).epsilon(1e-7));
  CHECK(Dev(kNbs14, 1, AllanEstimator::kHdev) == Approx(70.80608).epsilon(1e-7));
  CHECK(Dev(kNbs14, 1, AllanEstimator::kOhdev) == Approx(70.80608).epsilon(1e-7));
  // At m = 1 the Allan estimators coincide.
  CHECK(Dev(kNbs14, 1, AllanEstimator::kAdev) == Approx(91.22945).epsilon(1e-7));
  CHECK(Dev(kNbs14, 1, AllanEstimator::kMdev) == Approx(91.22945).epsilon(1e-7));
}

TEST_CASE("Estimators are blind to the rate mean and to a large bias", "[noise]") {
  std::vector<double> biased = kNbs14;
  for (double& v : biased) v += 1.0e9;
  for (AllanEstimator e : {AllanEstimator::kOadev, AllanEstimator::kMdev, AllanEstimator::kOhdev}) {
    CHECK(Dev(biased, 1, e) == Approx(Dev(kNbs14, 1, e)).epsilon(1e-6));
  }
}

TEST_CASE("An alternating rate has a closed-form Allan variance", "[noise]") {
  // y = +1, -1, +1, ... with tau0 = 0.5 s integrates to x = 0, 0.5, 0, 0.5, ...: the second
  // difference at lag m is +-2 * 0.5 = +-1 for odd m and 0 for even m, so
  // AVAR(m tau0) = 1 / (2 (m tau0)^2) = 2 / m^2 (odd m), 0 (even m).
  std::vector<double> y(1000);
  for (size_t i = 0; i < y.size(); ++i) y[i] = (i % 2 == 0) ? 1.0 : -1.0;
  const std::vector<double> x = PhaseFromRate(y, 0.5);
  const std::vector<double> v = AllanVariances(x, 0.5, {1, 2, 3, 4, 7}, AllanEstimator::kOadev, 1);
  CHECK(v[0] == Approx(2.0));
  CHECK(v[1] == Approx(0.0).margin(1e-20));
  CHECK(v[2] == Approx(2.0 / 9));
  CHECK(v[3] == Approx(0.0).margin(1e-20));
  CHECK(v[4] == Approx(2.0 / 49));
}

TEST_CASE("Regenerated NBS 1000-point frequency data reproduce PHASE.DAT", "[noise]") {
  const std::vector<double> phase_dat =
      testing::ReadNumberColumn(ExternalDataPath("nbs14_phasedat_stable32/PHASE.DAT"));
  REQUIRE(phase_dat.size() == 1001);
  const std::vector<double> x = PhaseFromRate(testing::Nbs1000Frequency(), 1.0);
  REQUIRE(x.size() == 1001);
  double max_err = 0.0;
  for (size_t i = 0; i < x.size(); ++i) max_err = std::max(max_err, std::fabs(x[i] - phase_dat[i]));
  CHECK(max_err < 1e-12);
  CHECK(x[1] == Approx(0.08511601).epsilon(1e-7));
}

struct Stable32Case {
  const char* file;
  AllanEstimator estimator;
};

TEST_CASE("PHASE.DAT deviations and confidence intervals match Stable32", "[noise]") {
  // Tolerances (SOURCE.md): sigma 1e-4, Min/Max 1e-3 relative; Stable32's alpha is 0.
  const std::vector<double> y = testing::Nbs1000Frequency();
  for (const Stable32Case& c :
       {Stable32Case{"phase_dat_adev_octave.txt", AllanEstimator::kAdev},
        Stable32Case{"phase_dat_oadev_octave.txt", AllanEstimator::kOadev},
        Stable32Case{"phase_dat_mdev_octave.txt", AllanEstimator::kMdev},
        Stable32Case{"phase_dat_hdev_octave.txt", AllanEstimator::kHdev},
        Stable32Case{"phase_dat_ohdev_octave.txt", AllanEstimator::kOhdev}}) {
    INFO(c.file);
    const std::vector<testing::Stable32Row> rows =
        ReadStable32(ExternalDataPath(std::string("nbs14_phasedat_stable32/") + c.file));
    REQUIRE(rows.size() == 8);
    for (NoiseIdMethod id : {NoiseIdMethod::kFixed, NoiseIdMethod::kLag1Acf}) {
      AllanOptions options;
      options.estimator = c.estimator;
      options.noise_id = id;
      options.fixed_alpha = 0;
      const Result<AllanCurve> curve = ComputeAllan(y, 1.0, options);
      REQUIRE(curve.ok());
      const AllanCurve& a = curve.value();
      REQUIRE(a.size() == rows.size());  // Octave taus with Stable32's stop ratio.
      for (size_t i = 0; i < rows.size(); ++i) {
        INFO("m = " << rows[i].af);
        CHECK(a.m[i] == rows[i].af);
        CHECK(a.n_terms[i] == rows[i].n);
        CHECK(a.dev[i] == Approx(rows[i].sigma).epsilon(1e-4));
        if (id == NoiseIdMethod::kLag1Acf && a.alpha_source[i] == AlphaSource::kLag1Acf) {
          CHECK(a.alpha[i] == rows[i].alpha);
        }
        if (a.alpha[i] == rows[i].alpha) {
          CHECK(a.ci_low[i] == Approx(rows[i].min_sigma).epsilon(1e-3));
          CHECK(a.ci_high[i] == Approx(rows[i].max_sigma).epsilon(1e-3));
        }
      }
    }
  }
}

TEST_CASE("OCXO record deviations and intervals match Stable32", "[noise][slow]") {
  // Tolerances (SOURCE.md caveat): the adev run 2e-4, the other octave runs 2e-3 because
  // Stable32 was given a slightly different export. Intervals are checked with Stable32's
  // own alpha column and sigma (as allantools does), to 1e-3 relative.
  const std::vector<double> y = testing::OcxoFractionalFrequency();
  REQUIRE(y.size() == 19982);
  struct Case {
    const char* file;
    AllanEstimator estimator;
    double tol;
  };
  for (const Case& c : {Case{"adev_octave.txt", AllanEstimator::kAdev, 2e-4},
                        Case{"oadev_octave.txt", AllanEstimator::kOadev, 2e-3},
                        Case{"mdev_octave.txt", AllanEstimator::kMdev, 2e-3},
                        Case{"hdev_octave.txt", AllanEstimator::kHdev, 2e-3},
                        Case{"ohdev_octave.txt", AllanEstimator::kOhdev, 2e-3}}) {
    INFO(c.file);
    const std::vector<testing::Stable32Row> rows =
        ReadStable32(ExternalDataPath(std::string("ocxo_stable32/") + c.file));
    REQUIRE(!rows.empty());
    AllanOptions options;
    options.estimator = c.estimator;
    const Result<AllanCurve> curve = ComputeAllan(y, 1.0, options);
    REQUIRE(curve.ok());
    const AllanCurve& a = curve.value();
    REQUIRE(a.size() == rows.size());
    const EstimatorShape shape = ShapeOf(c.estimator);
    int agree = 0;
    for (size_t i = 0; i < rows.size(); ++i) {
      INFO("m = " << rows[i].af);
      CHECK(a.m[i] == rows[i].af);
      CHECK(a.n_terms[i] == rows[i].n);
      CHECK(a.dev[i] == Approx(rows[i].sigma).epsilon(c.tol));
      const Result<double> edf =
          GreenhallRileyEdf(rows[i].alpha, shape.d, rows[i].af, static_cast<int64_t>(y.size()) + 1,
                            shape.overlapping, shape.modified);
      REQUIRE(edf.ok());
      const Result<DeviationInterval> ci = ChiSquaredInterval(rows[i].sigma, edf.value(), 0.683);
      REQUIRE(ci.ok());
      CHECK(ci.value().low == Approx(rows[i].min_sigma).epsilon(1e-3));
      CHECK(ci.value().high == Approx(rows[i].max_sigma).epsilon(1e-3));
      if (a.alpha[i] == rows[i].alpha) ++agree;
    }
    INFO("noise id agrees with Stable32 in " << agree << " of " << rows.size() << " rows");
    CHECK(agree >= static_cast<int>(rows.size()) * 2 / 3);
  }
}

TEST_CASE("OCXO all-tau curves match Stable32 at every averaging factor", "[noise][slow]") {
  const std::vector<double> y = testing::OcxoFractionalFrequency();
  struct Case {
    const char* file;
    AllanEstimator estimator;
  };
  for (const Case& c : {Case{"stable32_oadev_alltau.txt", AllanEstimator::kOadev},
                        Case{"stable32_adev_alltau.txt", AllanEstimator::kAdev},
                        Case{"stable32_mdev_alltau.txt", AllanEstimator::kMdev},
                        Case{"stable32_hdev_alltau.txt", AllanEstimator::kHdev},
                        Case{"stable32_ohdev_alltau.txt", AllanEstimator::kOhdev}}) {
    INFO(c.file);
    const std::vector<testing::Stable32Row> rows =
        ReadStable32(ExternalDataPath(std::string("ocxo_stable32/") + c.file));
    AllanOptions options;
    options.estimator = c.estimator;
    options.taus.kind = TauSpacingKind::kAll;
    const Result<AllanCurve> curve = ComputeAllan(y, 1.0, options);
    REQUIRE(curve.ok());
    const AllanCurve& a = curve.value();
    REQUIRE(a.size() == rows.size());
    double worst = 0.0;
    for (size_t i = 0; i < rows.size(); ++i) {
      CHECK(a.m[i] == rows[i].af);
      CHECK(a.n_terms[i] == rows[i].n);
      worst = std::max(worst, std::fabs(a.dev[i] / rows[i].sigma - 1.0));
    }
    CHECK(worst < 2e-4);
  }
}

TEST_CASE("Tau spacings produce the documented averaging factors", "[noise]") {
  auto factors = [](const char* spacing, int64_t n, AllanEstimator e = AllanEstimator::kOadev) {
    const Result<TauSpacing> s = ParseTauSpacing(spacing);
    REQUIRE(s.ok());
    const Result<std::vector<int64_t>> m = AveragingFactors(e, s.value(), n, 0);
    REQUIRE(m.ok());
    return m.value();
  };
  CHECK(factors("octave", 1000) == std::vector<int64_t>{1, 2, 4, 8, 16, 32, 64, 128});
  CHECK(factors("octave", 1000, AllanEstimator::kAdev) ==
        std::vector<int64_t>{1, 2, 4, 8, 16, 32, 64, 128});
  CHECK(factors("decade:3", 1000) == std::vector<int64_t>{1, 2, 5, 10, 22, 46, 100, 215});
  CHECK(factors("decade:1", 100000) == std::vector<int64_t>{1, 10, 100, 1000, 10000});
  CHECK(factors("every", 40).size() == 10);
  const std::vector<int64_t> all = factors("all", 1000);
  // Stable32 thinning: 1..53 by 1, then by 2 up to 107, then by 3, ... (max_m = 250).
  CHECK(all[52] == 53);
  CHECK(all[53] == 55);
  CHECK(all[78] == 105);
  CHECK(all[79] == 107);
  CHECK(all[80] == 110);
  CHECK(all.back() <= 250);
}

TEST_CASE("Bad Allan input is refused with a message", "[noise]") {
  AllanOptions options;
  SECTION("non-finite sample") {
    std::vector<double> y(100, 1.0);
    y[17] = std::nan("");
    const Result<AllanCurve> r = ComputeAllan(y, 0.01, options);
    REQUIRE_FALSE(r.ok());
    CHECK(r.error().message == "rate sample 17 (0-based) is not finite (nan)");
  }
  SECTION("bad sample period") {
    const Result<AllanCurve> r = ComputeAllan(std::vector<double>(100, 1.0), 0.0, options);
    REQUIRE_FALSE(r.ok());
    CHECK(r.error().message == "sample period tau0 = 0 s is not a positive number");
  }
  SECTION("too few samples") {
    const Result<AllanCurve> r = ComputeAllan({1.0, 2.0, 3.0}, 1.0, options);
    REQUIRE_FALSE(r.ok());
    CHECK(r.error().message ==
          "3 samples are too few for oadev: at least 4 are needed (Stable32 stop ratio 4)");
  }
  SECTION("averaging factor without a term") {
    options.m_list = {1, 50};
    const Result<AllanCurve> r = ComputeAllan(std::vector<double>(99, 1.0), 1.0, options);
    REQUIRE_FALSE(r.ok());
    CHECK(r.error().message == "averaging factor m = 50 leaves no oadev term with 99 samples");
  }
  SECTION("invalid options") {
    options.confidence = 1.0;
    const Result<AllanCurve> r = ComputeAllan(std::vector<double>(100, 1.0), 1.0, options);
    REQUIRE_FALSE(r.ok());
    CHECK(r.error().message == "Allan options: confidence 1 is not in (0, 1)");
    std::string why;
    AllanOptions fixed;
    fixed.noise_id = NoiseIdMethod::kFixed;
    fixed.fixed_alpha = -3;
    CHECK_FALSE(fixed.IsValid(&why));
    CHECK(why == "fixed_alpha -3 is outside [-2, 2] for oadev");
    fixed.estimator = AllanEstimator::kOhdev;
    CHECK(fixed.IsValid(&why));
    AllanOptions capped;
    capped.max_points_noise_id = 29;
    CHECK_FALSE(capped.IsValid(&why));
    CHECK(why == "max_points_noise_id must be >= min_points_noise_id");
  }
  SECTION("unknown names") {
    CHECK(ParseAllanEstimator("allan").error().message ==
          "unknown Allan estimator 'allan': expected oadev, mdev, ohdev, adev or hdev");
    CHECK(ParseTauSpacing("decade:0").error().message ==
          "tau spacing 'decade:0': decade:K needs an integer K from 1 to 1000 points per decade");
    CHECK(ParseTauSpacing("log").error().message ==
          "unknown tau spacing 'log': expected octave, decade:K, all or every");
  }
}

TEST_CASE("The noise identification reads the first max_points_noise_id averages", "[noise]") {
  // White rate noise for the first 2000 samples, then a random walk of the rate 100 times
  // as strong: the whole record identifies as random-walk FM at m = 1, its first 2000
  // samples as white FM.
  std::vector<double> y = testing::PowerLawRate(0, 2000, 3);
  const std::vector<double> walk = testing::PowerLawRate(-2, 30000, 4);
  for (double v : walk) y.push_back(100.0 * v);
  AllanOptions options;
  options.m_list = {1};
  const Result<AllanCurve> all = ComputeAllan(y, 1.0, options);
  options.max_points_noise_id = 2000;
  const Result<AllanCurve> first = ComputeAllan(y, 1.0, options);
  REQUIRE(all.ok());
  REQUIRE(first.ok());
  CHECK(all.value().alpha[0] == -2);
  CHECK(first.value().alpha[0] == 0);
  CHECK(first.value().alpha_source[0] == AlphaSource::kLag1Acf);
  CHECK(first.value().dev[0] == all.value().dev[0]);
}

TEST_CASE("Threaded and single-threaded sums agree", "[noise]") {
  std::vector<double> y(300000);
  uint64_t s = 12345;
  for (double& v : y) {
    s = s * 6364136223846793005ULL + 1442695040888963407ULL;
    v = static_cast<double>(s >> 11) / 9007199254740992.0 - 0.5;
  }
  const std::vector<double> x = PhaseFromRate(y, 1.0);
  const std::vector<int64_t> m = {1, 3, 64, 1000, 50000};
  for (AllanEstimator e : {AllanEstimator::kOadev, AllanEstimator::kMdev, AllanEstimator::kOhdev}) {
    const std::vector<double> one = AllanVariances(x, 1.0, m, e, 1);
    const std::vector<double> four = AllanVariances(x, 1.0, m, e, 4);
    for (size_t k = 0; k < m.size(); ++k) CHECK(four[k] == Approx(one[k]).epsilon(1e-10));
  }
}

}  // namespace
}  // namespace metro
