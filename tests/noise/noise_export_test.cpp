// The noise export (issue #40 step 1) and its reading back (step 3): Kalibr's published
// discretization, unit conversions and reductions in closed form, a round trip of every
// format through the comparison, refusals by name, and coverage on Kalibr's discrete model.
#include "metro/noise/noise_export.hpp"

#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <thread>
#include <vector>

#include "metro/noise/allan.hpp"
#include "metro/noise/noise_config_reader.hpp"
#include "metro/noise/noise_fit.hpp"
#include "noise/allan_report_json.hpp"
#include "support/coverage_bounds.hpp"
#include "support/noise_generators.hpp"

namespace metro {
namespace {

constexpr double kDegToRad = M_PI / 180.0;
constexpr double kG0 = 9.80665;

// An axis whose fit found N and K with these values and u (the report's units).
NoiseExportAxis Axis(const std::string& quantity, const std::string& unit, double n, double u_n,
                     double k, double u_k, double rate_hz = 400.0) {
  NoiseExportAxis a;
  a.quantity = quantity;
  a.unit = unit;
  a.allan.estimator = "oadev";
  a.allan.sample_period.rate_hz = rate_hz;
  a.allan.sample_period.tau0_s = 1.0 / rate_hz;
  auto set = [&](NoiseTerm t, double v, double u) {
    AllanNoiseTermReport& r = a.allan.noise[static_cast<size_t>(t)];
    r.value = v;
    r.u = u;
    r.supported = true;
    r.model_rejected = false;
  };
  set(NoiseTerm::kRandomWalk, n, u_n);
  set(NoiseTerm::kRateRandomWalk, k, u_k);
  return a;
}

// Three accelerometer axes in g and three gyroscope axes in deg/s, all terms different.
NoiseExportInput SixAxes() {
  NoiseExportInput in;
  in.source = "test record";
  in.axes = {Axis("ax_g", "g", 2.0e-4, 1e-6, 6.0e-6, 1e-6),
             Axis("ay_g", "g", 2.5e-4, 2e-6, 7.0e-6, 2e-6),
             Axis("az_g", "g", 2.2e-4, 1.5e-6, 5.0e-6, 1e-6),
             Axis("gx_dps", "deg/s", 1.1e-2, 1e-4, 1.4e-4, 3e-5),
             Axis("gy_dps", "deg/s", 1.0e-2, 1e-4, 1.6e-4, 4e-5),
             Axis("gz_dps", "deg/s", 1.2e-2, 2e-4, 1.5e-4, 3e-5)};
  return in;
}

const ExportedNoiseValue& Find(const NoiseExport& e, const std::string& key) {
  for (const ExportedNoiseValue& v : e.values) {
    if (v.key == key) return v;
  }
  FAIL("no key " << key);
  return e.values.front();
}

TEST_CASE("Kalibr's discrete conversion at 500 Hz", "[export]") {
  // Kalibr wiki "IMU Noise Model": sigma_d = sigma * sqrt(rate); the published pair at 500 Hz.
  CHECK(std::fabs(DiscreteWhiteSigma(0.039813853765, 500.0) - 0.890264834649) < 1e-10);
  CHECK(std::fabs(DiscreteWhiteSigma(0.00861190257109, 500.0) - 0.192567995646) < 1e-10);
  // The bias walk goes the other way: sigma_bd = sigma_b / sqrt(rate).
  CHECK(DiscreteBiasWalkSigma(DiscreteWhiteSigma(3e-3, 500.0), 500.0) ==
        Approx(3e-3 * std::sqrt(500.0) / std::sqrt(500.0)));
  CHECK(DiscreteBiasWalkSigma(1.0, 400.0) == Approx(0.05));
}

TEST_CASE("Kalibr export: units to SI, max and rms over the axes", "[export]") {
  const NoiseExportInput in = SixAxes();
  NoiseExportOptions o;
  Result<NoiseExport> e = ExportNoise(in, o);
  REQUIRE(e.ok());
  CHECK(e.value().rate_hz == 400.0);
  // max: the largest axis (ay for accel N and K; gz for gyro N, gy for gyro K) with its own u.
  const ExportedNoiseValue& an = Find(e.value(), "accelerometer_noise_density");
  CHECK(an.value == Approx(2.5e-4 * kG0).epsilon(1e-14));
  CHECK(an.u == Approx(2e-6 * kG0).epsilon(1e-14));
  CHECK(an.unit == "m/s^2/sqrt(Hz)");
  CHECK(an.low95 == Approx(an.value - 1.959963984540054 * an.u));
  CHECK(Find(e.value(), "accelerometer_random_walk").value == Approx(7.0e-6 * kG0));
  CHECK(Find(e.value(), "accelerometer_random_walk").unit == "m/s^3/sqrt(Hz)");
  CHECK(Find(e.value(), "gyroscope_noise_density").value == Approx(1.2e-2 * kDegToRad));
  CHECK(Find(e.value(), "gyroscope_noise_density").u == Approx(2e-4 * kDegToRad));
  CHECK(Find(e.value(), "gyroscope_random_walk").value == Approx(1.6e-4 * kDegToRad));
  CHECK(Find(e.value(), "gyroscope_random_walk").unit == "rad/s^2/sqrt(Hz)");
  CHECK(e.value().text.find("update_rate: 400\n") != std::string::npos);
  CHECK(e.value().text.find("rostopic: /imu0\n") != std::string::npos);
  CHECK(e.value().text.find("max over the axes (--axis-reduction max, the default)") !=
        std::string::npos);
  // rms: sqrt(mean v^2), u^2 = sum (v_i u_i)^2 / (n r)^2 (JCGM 100:2008 5.1.2).
  o.reduction = AxisReduction::kRms;
  e = ExportNoise(in, o);
  REQUIRE(e.ok());
  const double r = std::sqrt((1.1e-2 * 1.1e-2 + 1.0e-2 * 1.0e-2 + 1.2e-2 * 1.2e-2) / 3.0);
  const double ur = std::sqrt(std::pow(1.1e-2 * 1e-4, 2) + std::pow(1.0e-2 * 1e-4, 2) +
                              std::pow(1.2e-2 * 2e-4, 2)) /
                    (3.0 * r);
  CHECK(Find(e.value(), "gyroscope_noise_density").value == Approx(r * kDegToRad));
  CHECK(Find(e.value(), "gyroscope_noise_density").u == Approx(ur * kDegToRad));
}

TEST_CASE("Discrete formats: PX4 per EKF2 step, ROS per-sample variance", "[export]") {
  const NoiseExportInput in = SixAxes();
  NoiseExportOptions o;
  o.format = NoiseExportFormat::kPx4Ekf2;
  o.px4_predict_rate_hz = 250.0;
  Result<NoiseExport> e = ExportNoise(in, o);
  REQUIRE(e.ok());
  CHECK(Find(e.value(), "EKF2_GYR_NOISE").value == Approx(1.2e-2 * kDegToRad * std::sqrt(250.0)));
  CHECK(Find(e.value(), "EKF2_ACC_B_NOISE").value == Approx(7.0e-6 * kG0 * std::sqrt(250.0)));
  CHECK(Find(e.value(), "EKF2_ACC_B_NOISE").unit == "m/s^3");
  o.format = NoiseExportFormat::kRos;
  e = ExportNoise(in, o);
  REQUIRE(e.ok());
  // Per-sample variance of white noise N at rate f: N^2 f, per axis; u = 2 N f u(N).
  const ExportedNoiseValue& gyy = Find(e.value(), "angular_velocity_covariance[4]");
  CHECK(gyy.value == Approx(std::pow(1.0e-2 * kDegToRad, 2) * 400.0));
  CHECK(gyy.u == Approx(2.0 * 1.0e-2 * kDegToRad * 400.0 * 1e-4 * kDegToRad));
  CHECK(Find(e.value(), "linear_acceleration_covariance[8]").value ==
        Approx(std::pow(2.2e-4 * kG0, 2) * 400.0));
}

TEST_CASE("Every format round-trips through noise-compare with ratio 1", "[export]") {
  const NoiseExportInput in = SixAxes();
  for (NoiseExportFormat f : kAllNoiseExportFormats) {
    for (AxisReduction reduction : {AxisReduction::kMax, AxisReduction::kRms}) {
      INFO(NoiseExportFormatName(f) << " " << AxisReductionName(reduction));
      NoiseExportOptions o;
      o.format = f;
      o.reduction = reduction;
      const Result<NoiseExport> e = ExportNoise(in, o);
      REQUIRE(e.ok());
      const Result<NoiseConfigFile> read = ReadNoiseConfig(e.value().text, "exported");
      REQUIRE(read.ok());
      const Result<NoiseExportFormat> detected = DetectNoiseConfigFormat(read.value());
      REQUIRE(detected.ok());
      CHECK(detected.value() == f);
      const Result<NoiseComparison> c = CompareNoiseConfig(read.value(), in, o);
      REQUIRE(c.ok());
      REQUIRE(c.value().rows.size() == e.value().values.size());
      CHECK(c.value().rows.size() == (f == NoiseExportFormat::kBasalt ? 12u
                                      : f == NoiseExportFormat::kRos  ? 6u
                                                                      : 4u));
      for (const NoiseComparisonRow& r : c.value().rows) {
        INFO(r.key);
        CHECK(std::fabs(r.ratio - 1.0) < 1e-12);
        CHECK(std::fabs(r.e_n) < 1e-9);
      }
    }
  }
}

TEST_CASE("A config inflated x200 reads ratio 200 and its E_n", "[export]") {
  const NoiseExportInput in = SixAxes();
  NoiseExportOptions o;
  o.format = NoiseExportFormat::kVins;
  Result<NoiseExport> e = ExportedNoiseValues(in, o);
  REQUIRE(e.ok());
  const ExportedNoiseValue& gyr_n = Find(e.value(), "gyr_n");
  std::string text;
  for (const ExportedNoiseValue& v : e.value().values) {
    const double x = v.key == "gyr_n" ? 200.0 * v.value : v.value;
    char line[128];
    std::snprintf(line, sizeof(line), "%s: %.17g\n", v.key.c_str(), x);
    text += line;
  }
  const Result<NoiseConfigFile> read = ReadNoiseConfig(text, "vins.yaml");
  REQUIRE(read.ok());
  const Result<NoiseComparison> c = CompareNoiseConfig(read.value(), in, o);
  REQUIRE(c.ok());
  for (const NoiseComparisonRow& r : c.value().rows) {
    if (r.key != "gyr_n") continue;
    CHECK(r.ratio == Approx(200.0));
    // E_n = (x - X) / (2 u(X)) (ISO 13528:2015 9.7 with U_x = 0).
    CHECK(r.e_n == Approx(199.0 * gyr_n.value / (2.0 * gyr_n.u)));
  }
}

TEST_CASE("Unresolved terms and unusable units are refused by name", "[export]") {
  NoiseExportOptions o;
  SECTION("K not supported") {
    NoiseExportInput in = SixAxes();
    AllanNoiseTermReport& k =
        in.axes[5].allan.noise[static_cast<size_t>(NoiseTerm::kRateRandomWalk)];
    k.supported = false;
    k.value = std::nan("");
    const Result<NoiseExport> e = ExportNoise(in, o);
    REQUIRE_FALSE(e.ok());
    CHECK(e.error().message ==
          "gz_dps rate_random_walk (K): not resolved by the record: the fit does not support the "
          "term (value null, supported false); metro does not fill it in");
    CHECK(e.error().kind == ErrorKind::kInput);
    // ROS carries no bias walk: the same record exports.
    o.format = NoiseExportFormat::kRos;
    CHECK(ExportNoise(in, o).ok());
  }
  SECTION("B and K joint") {
    NoiseExportInput in = SixAxes();
    in.axes[0].allan.noise[static_cast<size_t>(NoiseTerm::kRateRandomWalk)].supported = false;
    in.axes[0].allan.b_k = AllanBkReport{true, 0.9, 1.0, 0.5, 1e-5, 1e-5};
    const Result<NoiseExport> e = ExportNoise(in, o);
    REQUIRE_FALSE(e.ok());
    CHECK(e.error().message.find("ax_g rate_random_walk (K)") == 0);
    CHECK(e.error().message.find("cannot separate B and K") != std::string::npos);
  }
  SECTION("model rejected") {
    NoiseExportInput in = SixAxes();
    in.axes[3].allan.noise[static_cast<size_t>(NoiseTerm::kRandomWalk)].model_rejected = true;
    const Result<NoiseExport> e = ExportNoise(in, o);
    REQUIRE_FALSE(e.ok());
    CHECK(e.error().message.find("gx_dps random_walk (N)") == 0);
    CHECK(e.error().message.find("model was rejected") != std::string::npos);
  }
  SECTION("LSB") {
    NoiseExportInput in = SixAxes();
    in.axes[3].quantity = "gx_lsb";
    in.axes[3].unit = "LSB";
    const Result<NoiseExport> e = ExportNoise(in, o);
    REQUIRE_FALSE(e.ok());
    CHECK(e.error().message.find("gx_lsb is in LSB: the estimators' files take rad/s") == 0);
  }
  SECTION("a vector format without the three axes") {
    NoiseExportInput in = SixAxes();
    in.axes.erase(in.axes.begin() + 1);
    o.format = NoiseExportFormat::kBasalt;
    const Result<NoiseExport> e = ExportNoise(in, o);
    REQUIRE_FALSE(e.ok());
    CHECK(e.error().message ==
          "basalt holds one value per axis and needs the three axes; the record has ax_g az_g");
  }
  SECTION("no gyroscope") {
    NoiseExportInput in = SixAxes();
    in.axes.resize(3);
    const Result<NoiseExport> e = ExportNoise(in, o);
    REQUIRE_FALSE(e.ok());
    CHECK(e.error().message == "the record has no gyroscope axis with an Allan analysis (--allan)");
  }
  SECTION("unknown format and reduction") {
    const Result<NoiseExportFormat> f = ParseNoiseExportFormat("kalibr2");
    REQUIRE_FALSE(f.ok());
    CHECK(f.error().message ==
          "unknown noise export format 'kalibr2'; expected one of kalibr, openvins, basalt, vins, "
          "orbslam3, gtsam, px4-ekf2, ros");
    CHECK_FALSE(ParseAxisReduction("mean").ok());
    o.rostopic = "/imu0 # x";
    std::string why;
    CHECK_FALSE(o.IsValid(&why));
    CHECK(why == "rostopic '/imu0 # x' is not a ROS name (letters, digits, _, / and ~)");
    CHECK(ExportNoise(SixAxes(), o).error().message == why);
  }
}

TEST_CASE("The report's N and K gain their standard names and SI form", "[export]") {
  // A gyroscope N of 0.6 deg/sqrt(h) = 0.01 deg/s*sqrt(s): Kalibr's gyroscope_noise_density
  // 0.01 pi/180 rad/s/sqrt(Hz), one-sided density sqrt(2) times that.
  AllanNoiseTermReport n;
  n.value = 0.01;
  n.u = 0.001;
  n.unit = "deg/s*sqrt(s)";
  n.supported = true;
  const std::optional<StandardNoiseName> arw = StandardNoiseNameOf(NoiseTerm::kRandomWalk, n);
  REQUIRE(arw);
  CHECK(arw->name == "angle_random_walk");
  CHECK(arw->kalibr_key == "gyroscope_noise_density");
  CHECK(arw->unit == "rad/s/sqrt(Hz)");
  CHECK(arw->value == Approx(0.01 * kDegToRad));
  CHECK(arw->u == Approx(0.001 * kDegToRad));
  CHECK(arw->density_one_sided == Approx(std::sqrt(2.0) * 0.01 * kDegToRad));
  AllanNoiseTermReport k;
  k.value = 1e-5;
  k.unit = "g/sqrt(s)";
  const std::optional<StandardNoiseName> aw = StandardNoiseNameOf(NoiseTerm::kRateRandomWalk, k);
  REQUIRE(aw);
  CHECK(aw->name == "acceleration_random_walk");
  CHECK(aw->kalibr_key == "accelerometer_random_walk");
  CHECK(aw->unit == "m/s^3/sqrt(Hz)");
  CHECK(aw->value == Approx(1e-5 * kG0));
  CHECK(std::isnan(aw->density_one_sided));
  k.unit = "LSB/sqrt(s)";
  CHECK_FALSE(StandardNoiseNameOf(NoiseTerm::kRateRandomWalk, k));
  CHECK_FALSE(StandardNoiseNameOf(NoiseTerm::kBiasInstability, n));
}

TEST_CASE("The standard names are written beside N and K and the JSON still round-trips",
          "[export]") {
  // A gyroscope in deg/s with white noise and a random walk (Kalibr's model): the written
  // "standard" is the term in rad/s per sqrt(Hz); reading the JSON back and writing it again
  // gives the same text (the key is derived, never read).
  const double dt = 0.01, n = 0.01, k = 0.001;
  AllanOptions options;
  options.threads = 1;
  const Result<AllanCurve> curve =
      ComputeAllan(testing::KalibrImuRate(size_t{1} << 18, dt, n, k, 77), dt, options);
  REQUIRE(curve.ok());
  const Result<NoiseFit> fit = FitNoiseTerms(curve.value());
  REQUIRE(fit.ok());
  const AllanReport report = MakeAllanReport(curve.value(), fit.value(), "deg/s");
  const nlohmann::ordered_json j = ToJsonValue(report);
  const auto& rw = j["noise"]["random_walk"];
  REQUIRE(rw.contains("standard"));
  CHECK(rw["standard"]["name"] == "angle_random_walk");
  CHECK(rw["standard"]["kalibr_key"] == "gyroscope_noise_density");
  CHECK(rw["standard"]["value"].get<double>() ==
        Approx(rw["value"].get<double>() * kDegToRad).epsilon(1e-14));
  CHECK(rw["standard"]["density_one_sided"].get<double>() ==
        Approx(std::sqrt(2.0) * rw["value"].get<double>() * kDegToRad).epsilon(1e-14));
  CHECK_FALSE(j["noise"]["bias_instability"].contains("standard"));
  const std::string text = j.dump(2);
  const Result<AllanReport> read =
      ReadJsonText<AllanReport>(text, "a.json", &AllanReportFromJsonValue);
  REQUIRE(read.ok());
  CHECK(ToJsonValue(read.value()).dump(2) == text);
}

// --- Coverage on Kalibr's discrete model ---------------------------------------------------

// allan_variance_ros's simulator (issue #40): 400 Hz, SI units.
constexpr double kRateHz = 400.0;
constexpr double kAccN = 0.0025019929573561175;   // m/s^2/sqrt(Hz)
constexpr double kAccK = 6.972435158192731e-05;   // m/s^3/sqrt(Hz)
constexpr double kGyrN = 0.0001888339269965301;   // rad/s/sqrt(Hz)
constexpr double kGyrK = 2.5565313322052523e-06;  // rad/s^2/sqrt(Hz)

NoiseExportAxis SimulatedAxis(const std::string& quantity, const std::string& unit, double n,
                              double k, size_t samples, uint64_t seed, std::string* why) {
  const double dt = 1.0 / kRateHz;
  AllanOptions options;
  options.threads = 1;
  NoiseExportAxis a;
  a.quantity = quantity;
  a.unit = unit;
  const Result<AllanCurve> curve =
      ComputeAllan(testing::KalibrImuRate(samples, dt, n, k, seed), dt, options);
  if (!curve.ok()) {
    *why = curve.error().message;
    return a;
  }
  const Result<NoiseFit> fit = FitNoiseTerms(curve.value());
  if (!fit.ok()) {
    *why = fit.error().message;
    return a;
  }
  a.allan = MakeAllanReport(curve.value(), fit.value(), unit);
  a.allan.sample_period.rate_hz = kRateHz;
  a.allan.sample_period.tau0_s = dt;
  return a;
}

struct CoverageCounts {
  int records = 0;
  int refused = 0;
  std::array<int, 4> within95{};            // accel N, accel K, gyro N, gyro K
  std::array<double, 4> sum_z{}, sum_z2{};  // z = (value - truth) / u
  std::string first_refusal;
};

// One accelerometer and one gyroscope axis per record (a reduction over axes of equal truth
// would not estimate the truth), exported as Kalibr's imu.yaml.
CoverageCounts RunKalibrCoverage(int records, double hours, uint64_t seed0) {
  const size_t samples = static_cast<size_t>(hours * 3600.0 * kRateHz);
  std::vector<CoverageCounts> per(2);
  auto work = [&](int thread) {
    CoverageCounts& c = per[static_cast<size_t>(thread)];
    for (int r = thread; r < records; r += 2) {
      ++c.records;
      const uint64_t seed = seed0 + 2 * static_cast<uint64_t>(r);
      std::string why;
      NoiseExportInput in;
      in.source = "simulated";
      in.axes = {SimulatedAxis("ax_mps2", "m/s^2", kAccN, kAccK, samples, seed, &why),
                 SimulatedAxis("gx_rads", "rad/s", kGyrN, kGyrK, samples, seed + 1, &why)};
      const Result<NoiseExport> e =
          why.empty() ? ExportNoise(in, NoiseExportOptions()) : Result<NoiseExport>(MakeError(why));
      if (!e.ok()) {
        ++c.refused;
        if (c.first_refusal.empty()) c.first_refusal = e.error().message;
        continue;
      }
      const std::array<double, 4> truth = {kAccN, kAccK, kGyrN, kGyrK};
      for (size_t i = 0; i < 4; ++i) {
        const ExportedNoiseValue& v = e.value().values[i];
        c.within95[i] += truth[i] >= v.low95 && truth[i] <= v.high95 ? 1 : 0;
        const double z = (v.value - truth[i]) / v.u;
        c.sum_z[i] += z;
        c.sum_z2[i] += z * z;
      }
    }
  };
  std::thread other(work, 1);
  work(0);
  other.join();
  CoverageCounts total;
  for (const CoverageCounts& c : per) {
    total.records += c.records;
    total.refused += c.refused;
    for (size_t i = 0; i < 4; ++i) {
      total.within95[i] += c.within95[i];
      total.sum_z[i] += c.sum_z[i];
      total.sum_z2[i] += c.sum_z2[i];
    }
    if (total.first_refusal.empty()) total.first_refusal = c.first_refusal;
  }
  std::printf(
      "Kalibr imu.yaml coverage, %d records of %.2g h at 400 Hz: refused %d; within the "
      "stated 95 %% interval: accel N %d, accel K %d, gyro N %d, gyro K %d%s%s\n",
      total.records, hours, total.refused, total.within95[0], total.within95[1], total.within95[2],
      total.within95[3],
      total.first_refusal.empty() ? "" : "; first refusal: ", total.first_refusal.c_str());
  const double n = std::max(1, total.records - total.refused);
  std::printf(
      "  z = (value - truth) / u, mean/rms: accel N %.2f/%.2f, accel K %.2f/%.2f, gyro N "
      "%.2f/%.2f, gyro K %.2f/%.2f\n",
      total.sum_z[0] / n, std::sqrt(total.sum_z2[0] / n), total.sum_z[1] / n,
      std::sqrt(total.sum_z2[1] / n), total.sum_z[2] / n, std::sqrt(total.sum_z2[2] / n),
      total.sum_z[3] / n, std::sqrt(total.sum_z2[3] / n));
  std::fflush(stdout);
  return total;
}

int EnvInt(const char* name, int fallback) {
  const char* v = std::getenv(name);
  return v != nullptr ? std::atoi(v) : fallback;
}

TEST_CASE("Kalibr imu.yaml holds the simulator's truth: a quick look", "[export]") {
  // 16 records of 2 h: each value within its 95 % interval in at least MinCount(16, 0.95)
  // records (a false alarm at 2e-4 per bound, support/coverage_bounds.hpp).
  const CoverageCounts c = RunKalibrCoverage(16, 2.0, 40000);
  const int min = testing::MinCount(c.records, 0.95);
  for (size_t i = 0; i < 4; ++i) {
    INFO("value " << i << "; first refusal: " << c.first_refusal);
    CHECK(c.within95[i] >= min);
  }
}

TEST_CASE("Kalibr imu.yaml coverage over 20 seeds, measurement run", "[.][export-coverage]") {
  // Issue #40 asks each value within its stated 95 % interval on >= 19 of 20 seeds. An
  // interval of exactly 95 % coverage meets that with probability P(Bin(20, 0.95) >= 19) =
  // 0.736 per value (0.29 for all four at once), so the run prints whether it is met and
  // asserts the binomial bound at the record count instead (a refusal counts as a miss).
  // METRO_EXPORT_RECORDS (default 20), METRO_EXPORT_HOURS (default 3); figures: docs/noise.md.
  const int records = EnvInt("METRO_EXPORT_RECORDS", 20);
  const double hours = EnvInt("METRO_EXPORT_HOURS", 3);
  const CoverageCounts c = RunKalibrCoverage(records, hours, 40000);
  bool issue_criterion = true;
  for (size_t i = 0; i < 4; ++i) {
    INFO("value " << i << "; first refusal: " << c.first_refusal);
    CHECK(c.within95[i] >= testing::MinCount(records, 0.95));
    issue_criterion = issue_criterion && 20 * c.within95[i] >= 19 * records;
  }
  std::printf(
      "  issue #40 criterion (each of the four within its 95 %% interval on >= 95 %% of "
      "the records): %s\n",
      issue_criterion ? "met" : "not met");
}

}  // namespace
}  // namespace metro
