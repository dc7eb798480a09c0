// The columns a calibration needs: a session without them is bad input named with its file
// and the missing columns (calibrate fit exits 2), checked before any fitting.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cstdio>
#include <string>

#include "metro/calibration/calibrate.hpp"
#include "metro/calibration/simulate.hpp"
#include "metro/core/file.hpp"
#include "metro/io/session_io.hpp"
#include "support/run_program.hpp"

namespace metro {
namespace {

Session Simulated(uint64_t seed) {
  SimulationOptions so;
  so.seed = seed;
  Result<SimulatedSession> sim = SimulateCalibrationSession(so);
  REQUIRE(sim.ok());
  return std::move(sim).value().session;
}

void Erase(Session* s, const std::string& name) {
  auto& q = s->tags.front().quantities;
  const size_t before = q.size();
  q.erase(std::remove_if(q.begin(), q.end(), [&](const Quantity& x) { return x.name == name; }),
          q.end());
  REQUIRE(q.size() + 1 == before);
}

TEST_CASE("Calibration columns are checked with the file and the columns named", "[calibration]") {
  Session good = Simulated(3);
  good.path = "good.csv";
  CalibrationOptions o;
  CHECK(CheckCalibrationColumns({&good}, o).ok());

  Session no_accel = Simulated(3);
  no_accel.path = "no_accel.csv";
  for (const char* n : {"ax_lsb", "ay_lsb", "az_lsb"}) Erase(&no_accel, n);
  Status s = CheckCalibrationColumns({&no_accel}, o);
  REQUIRE_FALSE(s.ok());
  CHECK(s.error().file == "no_accel.csv");
  CHECK_THAT(s.error().message, Catch::StartsWith("sensor 1: no accelerometer columns: the "
                                                  "calibrator needs ax_lsb ay_lsb az_lsb"));

  Session part_accel = Simulated(3);
  part_accel.path = "part.csv";
  Erase(&part_accel, "az_lsb");
  s = CheckCalibrationColumns({&part_accel}, o);
  REQUIRE_FALSE(s.ok());
  CHECK(s.error().ToString() ==
        "part.csv: sensor 1: missing accelerometer column(s) az_lsb: the calibrator needs all "
        "three axes");

  Session part_gyro = Simulated(3);
  part_gyro.path = "gyro.csv";
  Erase(&part_gyro, "gx_lsb");
  Erase(&part_gyro, "gz_lsb");
  s = CheckCalibrationColumns({&part_gyro}, o);
  REQUIRE_FALSE(s.ok());
  CHECK(s.error().message ==
        "sensor 1: missing gyroscope column(s) gx_lsb gz_lsb: the calibrator needs all three "
        "axes (or --accel-only)");
  CalibrationOptions accel_only;
  accel_only.fit_gyro = false;
  CHECK(CheckCalibrationColumns({&part_gyro}, accel_only).ok());

  // One record of the tag without the gyroscope while another has it.
  Session no_gyro = Simulated(4);
  no_gyro.path = "no_gyro.csv";
  for (const char* n : {"gx_lsb", "gy_lsb", "gz_lsb"}) Erase(&no_gyro, n);
  CHECK(CheckCalibrationColumns({&no_gyro}, o).ok());  // Accelerometer only, with a warning.
  s = CheckCalibrationColumns({&good, &no_gyro}, o);
  REQUIRE_FALSE(s.ok());
  CHECK(s.error().file == "no_gyro.csv");
  CHECK_THAT(s.error().message,
             Catch::StartsWith("sensor 1: no gyroscope columns (gx_lsb gy_lsb gz_lsb, gx_dps.. or "
                               "gx_rads..) while good.csv has them"));
  // Another sensor's columns do not matter when only sensor 2 is calibrated.
  CalibrationOptions sensor2;
  sensor2.sensor = 2;
  CHECK(CheckCalibrationColumns({&no_accel}, sensor2).ok());
}

#ifdef METRO_CALIBRATE_EXE
TEST_CASE("calibrate fit exits 2 naming the file and the missing columns", "[calibration][apps]") {
  Session no_accel = Simulated(5);
  for (const char* n : {"ax_lsb", "ay_lsb", "az_lsb"}) Erase(&no_accel, n);
  const std::string path = "metro_cal_no_accel.csv";
  const std::string out = "metro_cal_no_accel.json";
  REQUIRE(WriteFileAtomically(path, FormatSessionCsv(no_accel)).ok());
  testing::ProgramRun r = testing::RunProgram(METRO_CALIBRATE_EXE, "fit " + path + " -o " + out);
  CHECK(r.exit_code == 2);
  CHECK(r.err.find("error: " + path + ": sensor 1: no accelerometer columns") != std::string::npos);
  CHECK_FALSE(ReadFile(out).ok());  // Nothing written.

  // Two records of the tag, the second without the gyroscope.
  const std::string with_gyro = "metro_cal_with_gyro.csv";
  REQUIRE(WriteFileAtomically(with_gyro, FormatSessionCsv(Simulated(5))).ok());
  Session no_gyro = Simulated(6);
  for (const char* n : {"gx_lsb", "gy_lsb", "gz_lsb"}) Erase(&no_gyro, n);
  REQUIRE(WriteFileAtomically(path, FormatSessionCsv(no_gyro)).ok());
  r = testing::RunProgram(METRO_CALIBRATE_EXE, "fit " + with_gyro + " " + path + " -o " + out);
  CHECK(r.exit_code == 2);
  CHECK(r.err.find("error: " + path + ": sensor 1: no gyroscope columns") != std::string::npos);
  CHECK_FALSE(ReadFile(out).ok());
  std::remove(with_gyro.c_str());
  std::remove(path.c_str());
  std::remove(out.c_str());
}
#endif

}  // namespace
}  // namespace metro
