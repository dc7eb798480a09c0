// Gyroscope bias at rest from one static record (gyro_bias.hpp): recovery of a simulated bias
// with the stated uncertainty covering it over many seeds (white noise from the calibration
// simulator, and AR(1) noise, where the i.i.d. s/sqrt(n) would cover far too rarely), and the
// refusals of records that are not one static record.
#include "metro/calibration/gyro_bias.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <pcg_random.hpp>
#include <random>

#include "metro/calibration/calibration_io.hpp"
#include "metro/io/session_io.hpp"
#include "metro/sim/calibration_session.hpp"
#include "support/run_program.hpp"
#include "support/temp_file.hpp"

namespace metro {
namespace {

CalibrationOptions BiasAtRest() {
  CalibrationOptions o;
  o.fit_accel = false;
  o.gyro_model = ModelKind::kBias;
  return o;
}

// One pose held for `still_s` (the simulator's first pose is twice dwell_s): a static record
// with the simulator's drawn truth and white noise.
SimulatedSession StaticRecord(uint64_t seed, double still_s) {
  SimulationOptions so;
  so.seed = seed;
  so.poses = 1;
  so.dwell_s = still_s / 2;
  return SimulateCalibrationSession(so).value();
}

// A session of raw gyroscope counts b + AR(1) noise (phi per sample, stationary sd sd_lsb),
// rounded, at 100 Hz: a filtered or correlated record whose mean's u is not s / sqrt(n).
Session Ar1Record(uint64_t seed, const Eigen::Vector3d& bias_lsb, double phi, double sd_lsb,
                  size_t n) {
  pcg64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  Session s;
  s.path = "ar1.csv";
  s.rows = static_cast<int64_t>(n);
  s.columns = {"t_s", "sensor", "gx_lsb", "gy_lsb", "gz_lsb"};
  Tag tag;
  tag.sensor = 1;
  Eigen::Vector3d e = Eigen::Vector3d::Zero();
  for (int a = 0; a < 3; ++a) e[a] = sd_lsb * normal(rng);
  std::vector<double> v[3];
  for (size_t k = 0; k < n; ++k) {
    tag.t_s.push_back(static_cast<double>(k) * 0.01);
    tag.line.push_back(static_cast<uint32_t>(k + 2));
    for (int a = 0; a < 3; ++a) {
      e[a] = phi * e[a] + std::sqrt(1 - phi * phi) * sd_lsb * normal(rng);
      v[a].push_back(std::round(bias_lsb[a] + e[a]));
    }
  }
  for (int a = 0; a < 3; ++a) {
    Quantity q;
    q.name = std::string("g") + "xyz"[a] + "_lsb";
    q.unit = "LSB";
    q.values = v[a];
    tag.quantities.push_back(q);
  }
  s.tags.push_back(tag);
  return s;
}

}  // namespace

TEST_CASE("Gyro bias at rest: the simulator's bias recovered with its u", "[calibration]") {
  const SimulatedSession sim = StaticRecord(3, 60.0);
  REQUIRE(CheckCalibrationColumns({&sim.session}, BiasAtRest()).ok());
  Result<Calibration> cal = CalibrateSessions({&sim.session}, BiasAtRest());
  REQUIRE(cal.ok());
  const TagCalibration& t = cal.value().tags.at(0);
  CHECK_FALSE(t.accel.has_value());
  REQUIRE(t.gyro.has_value());
  const SensorCalibration& g = *t.gyro;
  CHECK(g.model.kind == ModelKind::kBias);
  CHECK(g.model.input_unit == "LSB");
  CHECK(g.model.scale[0] == Approx(1.0 / 131.0));  // datasheet: 131 LSB/(deg/s) at 250 deg/s
  CHECK(g.scale_u.isZero());
  // White noise of 0.005 deg/s/sqrt(Hz) over 50 Hz: sd 0.0354 deg/s = 4.6 LSB per sample;
  // the mean of n samples has u = sd / sqrt(n) (closed form), n = 60 s x 100 Hz.
  const double n = static_cast<double>(sim.session.tags[0].size());
  const double expected_u = 0.005 * std::sqrt(50.0) * 131.0 / std::sqrt(n);
  for (int a = 0; a < 3; ++a) {
    INFO("axis " << a);
    CHECK(g.bias_u[a] == Approx(expected_u).epsilon(0.2));
    CHECK(std::abs(g.model.bias[a] - sim.truth.gyro.bias[a]) < 4 * g.bias_u[a]);
  }
  CHECK(g.dof > 100);
  CHECK(g.coverage_factor_95 == Approx(1.96).margin(0.02));
  // calibration.json round trip keeps the bias-only gyroscope without an accelerometer.
  Result<Calibration> back = CalibrationFromJson(FormatCalibrationJson(cal.value()), "c.json");
  REQUIRE(back.ok());
  CHECK_FALSE(back.value().tags.at(0).accel.has_value());
  CHECK(back.value().tags.at(0).gyro->model.bias == g.model.bias);
}

// JCGM 100:2008 G.3: U = k95 u covers the true bias about 95 % of the time.
TEST_CASE("Gyro bias at rest: coverage over 200 seeds of white and AR(1) noise", "[calibration]") {
  int inside_white = 0, inside_ar = 0, inside_iid = 0, trials = 0;
  const Eigen::Vector3d bias_lsb(-1234.4, 56.7, 2600.2);
  for (uint64_t seed = 1; seed <= 200; ++seed) {
    const SimulatedSession sim = StaticRecord(seed, 20.0);
    Result<Calibration> white = CalibrateSessions({&sim.session}, BiasAtRest());
    REQUIRE(white.ok());
    const Session ar = Ar1Record(seed, bias_lsb, 0.9, 6.0, 3000);
    Result<Calibration> correlated = CalibrateSessions({&ar}, BiasAtRest());
    REQUIRE(correlated.ok());
    const SensorCalibration& gw = *white.value().tags[0].gyro;
    const SensorCalibration& ga = *correlated.value().tags[0].gyro;
    for (int a = 0; a < 3; ++a) {
      ++trials;
      inside_white += std::abs(gw.model.bias[a] - sim.truth.gyro.bias[a]) <=
                      gw.coverage_factor_95 * gw.bias_u[a];
      inside_ar += std::abs(ga.model.bias[a] - bias_lsb[a]) <= ga.coverage_factor_95 * ga.bias_u[a];
      // What s / sqrt(n) would have claimed: 6 / sqrt(3000) against the true
      // 6 sqrt((1 + phi) / (1 - phi) / n), 4.4 times smaller.
      inside_iid += std::abs(ga.model.bias[a] - bias_lsb[a]) <= 1.96 * 6.0 / std::sqrt(3000.0);
    }
  }
  const double white_rate = static_cast<double>(inside_white) / trials;
  const double ar_rate = static_cast<double>(inside_ar) / trials;
  const double iid_rate = static_cast<double>(inside_iid) / trials;
  std::printf(
      "gyro bias at rest: coverage white %.1f %%, AR(1) %.1f %% (i.i.d. u: %.1f %%) of %d\n",
      100 * white_rate, 100 * ar_rate, 100 * iid_rate, trials);
  // 600 trials: the binomial sd of a 95 % rate is 0.9 %; 92 .. 98 % is more than 3 sd.
  CHECK(white_rate >= 0.92);
  CHECK(white_rate <= 0.98);
  CHECK(ar_rate >= 0.92);
  CHECK(ar_rate <= 0.98);
  CHECK(iid_rate < 0.6);  // The test can fail: an i.i.d. u would not pass it.
}

TEST_CASE("Gyro bias at rest refuses what is not one static record", "[calibration]") {
  // The multi-pose session moves: named with the time and the offset.
  SimulationOptions so;
  so.seed = 5;
  so.poses = 6;
  const SimulatedSession moving = SimulateCalibrationSession(so).value();
  Status s = CheckCalibrationColumns({&moving.session}, BiasAtRest());
  REQUIRE_FALSE(s.ok());
  CHECK(s.error().message.find("the record is not at rest") != std::string::npos);
  CHECK(s.error().file == moving.session.path);
  // Two records of one tag.
  const SimulatedSession a = StaticRecord(1, 20.0), b = StaticRecord(2, 20.0);
  s = CheckCalibrationColumns({&a.session, &b.session}, BiasAtRest());
  REQUIRE_FALSE(s.ok());
  CHECK(s.error().message.find("from one static record") != std::string::npos);
  // No gyroscope columns.
  Session accel_only = a.session;
  auto& q = accel_only.tags[0].quantities;
  q.erase(std::remove_if(q.begin(), q.end(), [](const Quantity& x) { return x.name[0] == 'g'; }),
          q.end());
  s = CheckCalibrationColumns({&accel_only}, BiasAtRest());
  REQUIRE_FALSE(s.ok());
  CHECK(s.error().message.find("no gyroscope columns") != std::string::npos);
  // Options: accel none takes the bias model only.
  CalibrationOptions o = BiasAtRest();
  o.gyro_model = ModelKind::kScale;
  std::string why;
  CHECK_FALSE(o.IsValid(&why));
  CHECK(why.find("give the gyroscope model bias") != std::string::npos);
}

#ifdef METRO_CALIBRATE_EXE
TEST_CASE("calibrate fit --gyro-model bias --accel-model none", "[calibration][apps]") {
  const SimulatedSession sim = StaticRecord(9, 30.0);
  testing::TempFile record(FormatSessionCsv(sim.session));
  const std::string out = "metro_gyro_bias.json";
  std::remove(out.c_str());
  auto run = [](const std::string& args) { return testing::RunProgram(METRO_CALIBRATE_EXE, args); };
  testing::ProgramRun r =
      run("fit " + record.path() + " --gyro-model bias --accel-model none -o " + out);
  REQUIRE(r.exit_code == 0);
  CHECK(r.err.find("gyro bias at rest x: ") != std::string::npos);
  Result<Calibration> cal = LoadCalibration(out);
  REQUIRE(cal.ok());
  const SensorCalibration& g = *cal.value().tags.at(0).gyro;
  for (int a = 0; a < 3; ++a) {
    CHECK(std::abs(g.model.bias[a] - sim.truth.gyro.bias[a]) < 4 * g.bias_u[a]);
  }
  // The existing --model spelling: --model bias --accel-model none is the same request.
  r = run("fit " + record.path() + " --model bias --accel-model none -o - -q");
  REQUIRE(r.exit_code == 0);
  CHECK(nlohmann::json::parse(r.out)["tags"][0]["gyro"]["bias"][0].get<double>() ==
        g.model.bias[0]);
  std::remove(out.c_str());
  // Input problems exit 2.
  r = run("fit " + record.path() + " --gyro-model scale --accel-model none -o x.json");
  CHECK(r.exit_code == 2);
  CHECK(r.err.find("give --gyro-model bias") != std::string::npos);
  const std::string moving = std::string(METRO_SOURCE_DIR) + "/datasets/calibration_session.csv";
  r = run("fit " + moving + " --gyro-model bias --accel-model none -o x.json");
  CHECK(r.exit_code == 2);
  CHECK(r.err.find("the record is not at rest") != std::string::npos);
  testing::TempFile no_gyro("t_s,ax_lsb,ay_lsb,az_lsb\n0,1,2,3\n0.01,1,2,3\n");
  r = run("fit " + no_gyro.path() + " --gyro-model bias --accel-model none -o x.json");
  CHECK(r.exit_code == 2);
  CHECK(r.err.find("no gyroscope columns") != std::string::npos);
  CHECK_FALSE(std::ifstream("x.json").good());
}
#endif

}  // namespace metro
