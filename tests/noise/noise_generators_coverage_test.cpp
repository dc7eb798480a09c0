// The noise fit on generators written apart from the model (issue #36 part 8,
// tests/support/noise_generators.hpp): point-sampled Kasdin flicker, an integrating sampler,
// Kalibr's discrete model. Figures and the command: docs/noise.md section 4b.
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <string>
#include <thread>
#include <vector>

#include "metro/noise/allan.hpp"
#include "metro/noise/noise_fit.hpp"
#include "support/noise_generators.hpp"

namespace metro {
namespace {

constexpr double kTau0 = 0.01;  // 100 Hz

// The truth of noise_fit_coverage_test.cpp (deg/s units): N = 0.005, B/N cross at 1 s,
// K/B at 15 s.
constexpr double kN = 0.005;
const double kB = kN / std::sqrt(2.0 * std::log(2.0) / M_PI);
const double kK = kB * std::sqrt(3.0 * 2.0 * std::log(2.0) / M_PI / 15.0);

TEST_CASE("Point-sampled Kasdin flicker reads 1/ln2 times the IEEE 952 factor at m = 1",
          "[noise]") {
  // Closed form (see the generator's comment): AVAR(1) = B^2 int_0^1/2 2 sin(pi nu) dnu
  // = (2 / pi) B^2 = (1 / ln2) (2 ln2 / pi) B^2; at m = 16 within 0.5 % of the IEEE 952 factor.
  // 24 records of 2^15: the mean of AVAR(1) scatters ~0.3 %, of AVAR(16) ~2 %.
  const double b = 0.01;
  AllanOptions o;
  o.m_list = {1, 16};
  o.threads = 1;
  double sum1 = 0.0, sum16 = 0.0;
  const int records = 24;
  for (int r = 0; r < records; ++r) {
    const Result<AllanCurve> c =
        ComputeAllan(testing::KasdinFlickerPointSampled(size_t{1} << 15, b, 300 + r), kTau0, o);
    REQUIRE(c.ok());
    sum1 += c.value().dev[0] * c.value().dev[0] / records;
    sum16 += c.value().dev[1] * c.value().dev[1] / records;
  }
  const double ieee = 2.0 * std::log(2.0) / M_PI * b * b;
  CHECK(sum1 / ieee == Approx(1.0 / std::log(2.0)).epsilon(0.015));
  CHECK(sum16 / ieee == Approx(1.0046).epsilon(0.08));
}

TEST_CASE("Kalibr's discrete white noise and bias walk have the closed-form Allan variance",
          "[noise]") {
  // AVAR(m) = sigma_w^2 / tau + sigma_b^2 tau / 3 + sigma_b^2 tau0^2 / (6 tau) (the walk
  // point-sampled), at m = 1 and m = 64 over 24 records of 2^14 samples.
  const double sw = 0.003, sb = 0.002;
  AllanOptions o;
  o.m_list = {1, 64};
  o.threads = 1;
  double sum1 = 0.0, sum64 = 0.0;
  const int records = 24;
  for (int r = 0; r < records; ++r) {
    const Result<AllanCurve> c =
        ComputeAllan(testing::KalibrImuRate(size_t{1} << 14, kTau0, sw, sb, 900 + r), kTau0, o);
    REQUIRE(c.ok());
    sum1 += c.value().dev[0] * c.value().dev[0] / records;
    sum64 += c.value().dev[1] * c.value().dev[1] / records;
  }
  auto avar = [&](double tau) {
    return sw * sw / tau + sb * sb * tau / 3.0 + sb * sb * kTau0 * kTau0 / (6.0 * tau);
  };
  CHECK(sum1 == Approx(avar(0.01)).epsilon(0.02));
  CHECK(sum64 == Approx(avar(0.64)).epsilon(0.06));
}

struct GeneratorStats {
  int records = 0, fit_failures = 0;
  std::array<int, 5> reported{}, within_1u{}, within_2u{};
  int rejected = 0, untested = 0;
  int k_or_joint = 0;  // K in the model, or B and K reported jointly (NoiseFit::bk_joint)
};

using Generator = std::function<std::vector<double>(size_t n, uint64_t seed)>;

struct NamedGenerator {
  const char* name;
  Generator make;
};

std::vector<NamedGenerator> Generators() {
  return {{"point-sampled (Kasdin)",
           [](size_t n, uint64_t seed) {
             return testing::PointSampledNbk(n, kTau0, kN, kB, kK, seed);
           }},
          {"integrating sampler (x8)",
           [](size_t n, uint64_t seed) {
             return testing::IntegratingNbk(n, kTau0, kN, kB, kK, seed, 8);
           }},
          {"Kalibr + Kasdin flicker",
           [](size_t n, uint64_t seed) { return testing::KalibrNbk(n, kTau0, kN, kB, kK, seed); }}};
}

GeneratorStats Run(const Generator& make, size_t n, int records, uint64_t seed0) {
  const std::array<double, 5> truth = {0.0, kN, kB, kK, 0.0};
  std::vector<GeneratorStats> per(2);
  auto work = [&](int thread) {
    GeneratorStats& s = per[static_cast<size_t>(thread)];
    for (int r = thread; r < records; r += 2) {
      ++s.records;
      AllanOptions options;
      options.threads = 1;
      const Result<AllanCurve> curve =
          ComputeAllan(make(n, seed0 + static_cast<uint64_t>(r)), kTau0, options);
      if (!curve.ok()) {  // no Catch assertion off the main thread
        ++s.fit_failures;
        continue;
      }
      const Result<NoiseFit> fit = FitNoiseTerms(curve.value());
      if (!fit.ok()) {
        ++s.fit_failures;
        continue;
      }
      const NoiseModelCheck& c = fit.value().model_check;
      s.untested += c.tested ? 0 : 1;
      s.rejected += c.tested && c.rejected ? 1 : 0;
      s.k_or_joint +=
          fit.value().term(NoiseTerm::kRateRandomWalk).supported || fit.value().bk_joint ? 1 : 0;
      for (size_t t = 0; t < 5; ++t) {
        const NoiseTermEstimate& e = fit.value().terms[t];
        if (!e.supported) continue;
        ++s.reported[t];
        if (!(truth[t] > 0.0)) continue;
        const double z = std::fabs(e.value - truth[t]) / e.u;
        s.within_1u[t] += z <= 1.0 ? 1 : 0;
        s.within_2u[t] += z <= 2.0 ? 1 : 0;
      }
    }
  };
  std::thread other(work, 1);
  work(0);
  other.join();
  GeneratorStats total;
  for (const GeneratorStats& s : per) {
    total.records += s.records;
    total.fit_failures += s.fit_failures;
    total.rejected += s.rejected;
    total.untested += s.untested;
    total.k_or_joint += s.k_or_joint;
    for (size_t t = 0; t < 5; ++t) {
      total.reported[t] += s.reported[t];
      total.within_1u[t] += s.within_1u[t];
      total.within_2u[t] += s.within_2u[t];
    }
  }
  return total;
}

void Print(const char* name, const char* duration, const GeneratorStats& s) {
  const double n = s.records;
  std::printf(
      "%s %s, %d records: N 1u/2u %.0f/%.0f %%, B %.0f/%.0f %%, K found %d (or B,K joint: %d), "
      "1u/2u %.0f/%.0f %%; spurious Q %d, R %d; model rejected %d, untested %d, fit failures "
      "%d\n",
      duration, name, s.records, 100.0 * s.within_1u[1] / n, 100.0 * s.within_2u[1] / n,
      100.0 * s.within_1u[2] / n, 100.0 * s.within_2u[2] / n, s.reported[3], s.k_or_joint,
      100.0 * s.within_1u[3] / n, 100.0 * s.within_2u[3] / n, s.reported[0], s.reported[4],
      s.rejected, s.untested, s.fit_failures);
  std::fflush(stdout);
}

TEST_CASE("N + B + K on independent generators: a quick look", "[noise][slow]") {
  // 6 records of 20 min per generator. With so few records only gross failures can be
  // asserted: no fit fails; N (the best-determined term) within 2u in at least 4 of 6
  // (P(< 4) = 0.2 % at 95 %); a spurious Q or R in at most 2 of the 18 fits and the model
  // rejected in at most 2 of 18 (each 1 % under a correct model: P(> 2) < 0.1 %).
  int spurious = 0, rejected = 0;
  for (const NamedGenerator& g : Generators()) {
    const GeneratorStats s = Run(g.make, 120000, 6, 41000);
    Print(g.name, "20min", s);
    INFO(g.name);
    CHECK(s.fit_failures == 0);
    CHECK(s.within_2u[1] >= 4);
    spurious += s.reported[0] + s.reported[4];
    rejected += s.rejected;
  }
  CHECK(spurious <= 2);
  CHECK(rejected <= 2);
}

int EnvInt(const char* name, int fallback) {
  const char* v = std::getenv(name);
  return v != nullptr ? std::atoi(v) : fallback;
}

TEST_CASE("N + B + K on independent generators: coverage over 1 h records",
          "[.][coverage][noise]") {
  // Issue #36 targets per generator: K found in >= 85 % of records, a spurious R or Q in at
  // most 2 of 40, each term within u in 62-74 % and within 2u in 92-98 %. The figures are
  // printed for docs/noise.md; the assertions are the targets widened by two binomial
  // standard deviations at the record count (METRO_NOISE_GEN_RECORDS, default 100, the
  // issue's minimum; docs/noise.md 4b has two blocks of 100).
  const int records = EnvInt("METRO_NOISE_GEN_RECORDS", 100);
  const uint64_t seed = static_cast<uint64_t>(EnvInt("METRO_NOISE_GEN_SEED", 52000));
  const double sd68 = std::sqrt(0.683 * 0.317 / records);
  const double sd95 = std::sqrt(0.954 * 0.046 / records);
  for (const NamedGenerator& g : Generators()) {
    const GeneratorStats s = Run(g.make, 360000, records, seed);
    Print(g.name, "1h", s);
    INFO(g.name);
    CHECK(s.fit_failures == 0);
    CHECK(s.k_or_joint >= 0.85 * records - 2.0 * std::sqrt(0.15 * 0.85 * records));
    CHECK(s.reported[0] + s.reported[4] <= 2.0 * records / 40.0 + 2.0);
    for (size_t t : {size_t{1}, size_t{2}, size_t{3}}) {
      INFO("term " << t);
      CHECK(s.within_1u[t] >= (0.62 - 2.0 * sd68) * records);
      CHECK(s.within_1u[t] <= (0.74 + 2.0 * sd68) * records);
      CHECK(s.within_2u[t] >= (0.92 - 2.0 * sd95) * records);
    }
  }
}

}  // namespace
}  // namespace metro
