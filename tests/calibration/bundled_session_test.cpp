// The bundled calibration session (datasets/calibration_session.csv + .truth.json, written by
// `characterize simulate --kind calibration` in datasets/regenerate.sh): `calibrate fit`
// recovers the truth the simulation used within 3 u, and the command reproduces the files byte
// for byte.
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <string>

#include "metro/calibration/calibrate.hpp"
#include "metro/calibration/calibration_io.hpp"
#include "metro/core/file.hpp"
#include "metro/io/session_io.hpp"
#include "support/run_program.hpp"

namespace metro {
namespace {

const std::string kSession = std::string(METRO_SOURCE_DIR) + "/datasets/calibration_session.csv";

// One sensor's truth as the sidecar states it (calibration.json's keys).
SensorModel TruthModel(const nlohmann::json& j, ImuSensor sensor) {
  SensorModel m;
  m.sensor = sensor;
  m.kind = ModelKind::kFull;
  m.input_unit = j.at("input_unit").get<std::string>();
  for (int a = 0; a < 3; ++a) {
    m.bias[a] = j.at("bias").at(a).get<double>();
    m.scale[a] = j.at("scale").at(a).get<double>();
  }
  m.misalignment = j.at("misalignment").get<std::vector<double>>();
  if (j.contains("temperature")) {
    m.has_temperature = true;
    m.t_ref_c = j.at("temperature").at("t_ref_c").get<double>();
    for (int a = 0; a < 3; ++a) {
      m.bias_per_c[a] = j.at("temperature").at("bias_per_c").at(a).get<double>();
    }
  }
  return m;
}

// |estimate - truth| <= k u for every constant the fit estimated; the bias at the fit's t_ref_c.
void CheckWithin(const SensorCalibration& c, const SensorModel& truth, double k) {
  const SensorModel& m = c.model;
  auto check = [&](const std::string& name, double estimate, double true_value, double u) {
    INFO(ImuSensorName(truth.sensor)
         << " " << name << ": " << estimate << " truth " << true_value << " u " << u);
    CHECK(u > 0);
    CHECK(std::abs(estimate - true_value) <= k * u);
  };
  for (int a = 0; a < 3; ++a) {
    const std::string axis(1, "xyz"[a]);
    check("b0_" + axis, m.bias[a], truth.BiasAt(m.t_ref_c)[a], c.bias_u[a]);
    check("k_" + axis, m.scale[a], truth.scale[a], c.scale_u[a]);
    REQUIRE(m.has_temperature);
    check("b1_" + axis, m.bias_per_c[a], truth.bias_per_c[a], c.bias_per_c_u[a]);
  }
  REQUIRE(m.misalignment.size() == truth.misalignment.size());
  for (size_t i = 0; i < m.misalignment.size(); ++i) {
    check("misalignment " + std::to_string(i), m.misalignment[i], truth.misalignment[i],
          c.misalignment_u[i]);
  }
}

}  // namespace

TEST_CASE("calibrate fit recovers the bundled session's truth within 3 u", "[calibration]") {
  Result<std::string> truth_text = ReadFile(kSession + ".truth.json");
  REQUIRE(truth_text.ok());
  const nlohmann::json truth = nlohmann::json::parse(truth_text.value());
  CHECK(truth["schema"] == "metro.calibration-truth/1");
  Result<Session> session = LoadSession(kSession);
  REQUIRE(session.ok());
  REQUIRE(session.value().tags.size() == 1);
  CHECK(session.value().tags[0].sensor == truth["sensor"].get<int>());
  CHECK(session.value().rows == truth["rows"].get<int64_t>());
  CalibrationOptions o;  // calibrate fit's defaults: +-2 g, +-250 deg/s, standard gravity
  REQUIRE(truth["accel_fs_g"].get<double>() == o.accel_fs_g);
  REQUIRE(truth["gyro_fs_dps"].get<double>() == o.gyro_fs_dps);
  REQUIRE(truth["gravity_mps2"].get<double>() == o.gravity_mps2);
#ifdef METRO_CALIBRATE_EXE
  // `calibrate fit` itself, as the README runs it.
  const std::string out = "metro_bundled_calibration.json";
  testing::ProgramRun run =
      testing::RunProgram(METRO_CALIBRATE_EXE, "fit " + kSession + " -o " + out + " -q");
  REQUIRE(run.exit_code == 0);
  Result<Calibration> cal = LoadCalibration(out);
  std::remove(out.c_str());
#else
  Result<Calibration> cal = CalibrateSessions({&session.value()}, o);
#endif
  if (!cal.ok()) FAIL(cal.error().ToString());
  const TagCalibration& t = cal.value().tags.at(0);
  REQUIRE(t.accel.has_value());
  REQUIRE(t.gyro.has_value());
  // Every pose, table run and rotation of the record is found and used.
  int statics = 0, tables = 0;
  for (const Segment& s : t.gyro->segments) {
    statics += s.kind == SegmentKind::kStatic ? 1 : 0;
    tables += s.kind == SegmentKind::kTable ? 1 : 0;
  }
  const int poses = truth["poses"].get<int>();
  CHECK(statics >= poses);
  CHECK(tables == poses * static_cast<int>(truth["table_rates_dps"].size()));
  CHECK(t.accel->segments.size() >= static_cast<size_t>(poses));
  CheckWithin(*t.accel, TruthModel(truth["accel"], ImuSensor::kAccel), 3.0);
  CheckWithin(*t.gyro, TruthModel(truth["gyro"], ImuSensor::kGyro), 3.0);
  CHECK(t.accel->reduced_chi2 == Approx(1.0).margin(0.5));
  CHECK(t.gyro->reduced_chi2 == Approx(1.0).margin(0.5));
}

#ifdef METRO_CHARACTERIZE_EXE
// The command of datasets/regenerate.sh, to a scratch file.
TEST_CASE("The bundled calibration session regenerates byte for byte", "[calibration][apps]") {
  const std::string out = "metro_regenerated_calibration_session.csv";
  testing::ProgramRun r = testing::RunProgram(
      METRO_CHARACTERIZE_EXE, "simulate --kind calibration --seed 25 --sensor 2 -o " + out);
  REQUIRE(r.exit_code == 0);
  for (const std::string suffix : {"", ".truth.json"}) {
    Result<std::string> bundled = ReadFile(kSession + suffix);
    Result<std::string> fresh = ReadFile(out + suffix);
    REQUIRE(bundled.ok());
    REQUIRE(fresh.ok());
    CHECK(bundled.value() == fresh.value());
    std::remove((out + suffix).c_str());
  }
  // What --kind calibration cannot write is refused, nothing written.
  r = testing::RunProgram(METRO_CHARACTERIZE_EXE,
                          "simulate --kind calibration --format receiver -o " + out);
  CHECK(r.exit_code == 2);
  CHECK(r.err ==
        "error: --kind calibration writes session.csv (raw LSB columns): drop --format receiver\n");
  r = testing::RunProgram(METRO_CHARACTERIZE_EXE,
                          "simulate --kind calibration --sensor 1 --sensor 2 -o " + out);
  CHECK(r.exit_code == 2);
  CHECK(r.err == "error: --kind calibration simulates one tag: give one --sensor\n");
  r = testing::RunProgram(METRO_CHARACTERIZE_EXE,
                          "simulate --kind calibration --pose-dwell-s 0 -o " + out);
  CHECK(r.exit_code == 2);
  CHECK(r.err.find("--pose-dwell-s") != std::string::npos);
  CHECK_FALSE(ReadFile(out).ok());
  CHECK_FALSE(ReadFile(out + ".truth.json").ok());
  // The regenerate script holds the same command.
  Result<std::string> script = ReadFile(std::string(METRO_SOURCE_DIR) + "/datasets/regenerate.sh");
  REQUIRE(script.ok());
  CHECK(script.value().find("simulate --kind calibration --seed 25 --sensor 2") !=
        std::string::npos);
}
#endif

}  // namespace metro
