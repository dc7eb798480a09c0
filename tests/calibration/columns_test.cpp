// The columns a calibration needs: a session without them is bad input named with its file
// and the missing columns (calibrate fit exits 2), checked before any fitting.
#include "metro/io/columns.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cstdio>
#include <string>

#include "metro/calibration/calibrate.hpp"
#include "metro/core/file.hpp"
#include "metro/io/session_io.hpp"
#include "metro/sim/calibration_session.hpp"
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
        "part.csv: sensor 1: the accelerometer calibration needs ax_lsb, ay_lsb, az_lsb; missing "
        "az_lsb");

  Session part_gyro = Simulated(3);
  part_gyro.path = "gyro.csv";
  Erase(&part_gyro, "gx_lsb");
  Erase(&part_gyro, "gz_lsb");
  s = CheckCalibrationColumns({&part_gyro}, o);
  REQUIRE_FALSE(s.ok());
  CHECK(s.error().message ==
        "sensor 1: the gyroscope calibration needs gx_lsb, gy_lsb, gz_lsb; missing gx_lsb, "
        "gz_lsb (or --accel-only)");
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
             Catch::StartsWith("sensor 1: no gyroscope columns while good.csv has them: records of "
                               "one tag are fitted together; log gx_lsb gy_lsb gz_lsb (or gx_dps "
                               "gy_dps gz_dps, or gx_rads gy_rads gz_rads) in every record"));
  // Another sensor's columns do not matter when only sensor 2 is calibrated.
  CalibrationOptions sensor2;
  sensor2.sensor = 2;
  CHECK(CheckCalibrationColumns({&no_accel}, sensor2).ok());
}

// A session of one tag with the named columns (values do not matter: the check reads names).
Session WithColumns(const std::string& path, const std::vector<std::string>& names) {
  Session s;
  s.path = path;
  Tag tag;
  for (int i = 0; i < 20; ++i) {
    tag.t_s.push_back(0.01 * i);
    tag.line.push_back(static_cast<uint32_t>(i + 2));
  }
  for (const std::string& n : names) {
    Quantity q;
    q.name = n;
    q.unit = ClassifyColumn(n).UnitSymbol();
    q.values.assign(tag.t_s.size(), 0.0);
    tag.quantities.push_back(q);
  }
  s.tags.push_back(tag);
  return s;
}

TEST_CASE("A partial axis family is named with its missing columns", "[calibration]") {
  CalibrationOptions o;
  // One gyroscope axis is a valid session, but not a calibration record: the accelerometer
  // is checked first.
  const Session gz_only = WithColumns("gz.csv", {"gz_dps"});
  Status s = CheckCalibrationColumns({&gz_only}, o);
  REQUIRE_FALSE(s.ok());
  CHECK(s.error().ToString() ==
        "gz.csv: sensor 1: no accelerometer columns: the calibrator needs ax_lsb ay_lsb az_lsb "
        "(or ax_g ay_g az_g, or ax_mps2 ay_mps2 az_mps2) in static poses");

  // With the accelerometer complete, the gyroscope family is two columns short.
  const Session accel_gz = WithColumns("accel_gz.csv", {"ax_g", "ay_g", "az_g", "gz_dps"});
  s = CheckCalibrationColumns({&accel_gz}, o);
  REQUIRE_FALSE(s.ok());
  CHECK(s.error().ToString() ==
        "accel_gz.csv: sensor 1: the gyroscope calibration needs gx_dps, gy_dps, gz_dps; missing "
        "gx_dps, gy_dps (or --accel-only)");
  CalibrationOptions accel_only;
  accel_only.fit_gyro = false;
  CHECK(CheckCalibrationColumns({&accel_gz}, accel_only).ok());

  // Two accelerometer axes.
  const Session axy = WithColumns("axy.csv", {"ax_g", "ay_g"});
  s = CheckCalibrationColumns({&axy}, o);
  REQUIRE_FALSE(s.ok());
  CHECK(s.error().ToString() ==
        "axy.csv: sensor 1: the accelerometer calibration needs ax_g, ay_g, az_g; missing az_g");
  CHECK_FALSE(CheckCalibrationColumns({&axy}, accel_only).ok());  // Needed in any case.

  // The same through CalibrateTag, which reads the family without the check first.
  Result<TagCalibration> r = CalibrateTag({&axy.tags.front()}, o);
  REQUIRE_FALSE(r.ok());
  CHECK_THAT(r.error().message,
             Catch::Contains("sensor 1: the accelerometer calibration needs ax_g, ay_g, az_g; "
                             "missing az_g"));

  // A complete family in one unit is used even when another unit's family is partial.
  const Session mixed = WithColumns("mixed.csv", {"ax_lsb", "ay_lsb", "az_lsb", "az_g", "gx_rads",
                                                  "gy_rads", "gz_rads", "gx_dps"});
  CHECK(CheckCalibrationColumns({&mixed}, o).ok());
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

TEST_CASE("calibrate fit exits 2 naming the missing columns of a partial family",
          "[calibration][apps]") {
  // Sessions with part of an axis family load (docs/formats.md); the calibrator refuses them.
  const std::string path = "metro_cal_partial.csv";
  const std::string out = "metro_cal_partial.json";
  std::string text = "t_s,ax_g,ay_g,gx_dps,gy_dps,gz_dps\n";
  for (int i = 0; i < 50; ++i) text += fmt::format("{},0,0,0,0,0\n", 0.01 * i);
  REQUIRE(WriteFileAtomically(path, text).ok());
  testing::ProgramRun r = testing::RunProgram(METRO_CALIBRATE_EXE, "fit " + path + " -o " + out);
  CHECK(r.exit_code == 2);
  CHECK_THAT(r.err, Catch::Contains("error: " + path +
                                    ": sensor 1: the accelerometer calibration needs ax_g, ay_g, "
                                    "az_g; missing az_g"));
  CHECK_FALSE(ReadFile(out).ok());

  text = "t_s,ax_g,ay_g,az_g,gz_dps\n";
  for (int i = 0; i < 50; ++i) text += fmt::format("{},0,0,1,0\n", 0.01 * i);
  REQUIRE(WriteFileAtomically(path, text).ok());
  r = testing::RunProgram(METRO_CALIBRATE_EXE, "fit " + path + " -o " + out);
  CHECK(r.exit_code == 2);
  CHECK_THAT(r.err, Catch::Contains("error: " + path +
                                    ": sensor 1: the gyroscope calibration needs gx_dps, gy_dps, "
                                    "gz_dps; missing gx_dps, gy_dps (or --accel-only)"));
  CHECK_FALSE(ReadFile(out).ok());
  std::remove(path.c_str());
}
TEST_CASE("calibrate fit --segments: annotated poses, and a bad file named by line and column",
          "[calibration][apps]") {
  // The simulator's poses: pose 0 still for 6 s, then 2 s of hand rotation and 3 s still
  // for each of the other 25 (pose i >= 1 still from 5 i + 3 to 5 i + 6 s).
  const std::string path = "metro_cal_segments_session.csv";
  const std::string segments = "metro_cal_segments.csv";
  const std::string out = "metro_cal_segments.json";
  REQUIRE(WriteFileAtomically(path, FormatSessionCsv(Simulated(7))).ok());
  std::string text = "kind,start_s,end_s\n";
  text += "static,0.5,5.5\n";
  for (int i = 1; i < 26; ++i) text += fmt::format("static,{},{}\n", 5 * i + 3.5, 5 * i + 5.5);
  REQUIRE(WriteFileAtomically(segments, text).ok());
  testing::ProgramRun r = testing::RunProgram(
      METRO_CALIBRATE_EXE, "fit " + path + " --segments " + segments + " -o " + out);
  CHECK(r.exit_code == 0);
  INFO(r.err);
  Result<std::string> json = ReadFile(out);
  REQUIRE(json.ok());
  CHECK(json.value().find("annotated (" + segments + " line 2)") != std::string::npos);

  REQUIRE(WriteFileAtomically(segments, "kind,start_s,end_s\nstatic,0.5,later\n").ok());
  r = testing::RunProgram(METRO_CALIBRATE_EXE,
                          "fit " + path + " --segments " + segments + " -o " + out + ".2");
  CHECK(r.exit_code == 2);
  CHECK_THAT(r.err, Catch::Contains(segments + ":2:3: end_s 'later' is not a number"));
  CHECK_FALSE(ReadFile(out + ".2").ok());
  for (const std::string& f : {path, segments, out}) std::remove(f.c_str());
}
#endif

}  // namespace
}  // namespace metro
