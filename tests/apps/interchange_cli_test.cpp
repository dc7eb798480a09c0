// calibrate export --to kalibr|openvins|basalt|realsense and calibrate import on the bundled
// session's fit: the files and their sidecars, the round trip, the flags and the refusals.
#ifdef METRO_CALIBRATE_EXE
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "metro/calibration/calibration_io.hpp"
#include "support/bundled_fit.hpp"
#include "support/run_program.hpp"
#include "support/temp_file.hpp"

namespace metro {
namespace {

testing::ProgramRun Calibrate(const std::string& args) {
  return testing::RunProgram(METRO_CALIBRATE_EXE, args);
}

TEST_CASE("calibrate export and import: estimator intrinsics, sidecar and round trip",
          "[apps][interchange]") {
  const std::string fit = testing::BundledFit("");
  const std::string dir = testing::MakeScratchFolder("metro_interchange_cli");
  const Result<Calibration> original = LoadCalibration(fit);
  REQUIRE(original.ok());
  const SensorModel& want = original.value().FindTag(2)->gyro->model;
  for (const char* format : {"kalibr", "openvins", "basalt", "realsense"}) {
    INFO(format);
    const std::string file = dir + "out." + format, back = dir + "back." + format + ".json";
    testing::ProgramRun r =
        Calibrate("export " + fit + " --to " + format + " --sensor 2 -o " + file);
    INFO(r.err);
    REQUIRE(r.exit_code == 0);
    // The bundled tag has a temperature term: named.
    CHECK_THAT(r.err, Catch::Contains("cannot hold the accelerometer bias temperature term"));
    CHECK(std::filesystem::exists(file + ".covariance.json"));
    r = Calibrate("import " + file + " --from " + format + " --sensor 2 -o " + back);
    REQUIRE(r.exit_code == 0);
    const Result<Calibration> imported = LoadCalibration(back);
    INFO((imported.ok() ? "" : imported.error().ToString()));
    REQUIRE(imported.ok());
    // Gyroscope misalignment terms (rad, no unit change): the fit's to 1e-12.
    const SensorModel& got = imported.value().FindTag(2)->gyro->model;
    for (size_t i = 0; i < 6; ++i) {
      CHECK(got.misalignment[i] == Approx(want.misalignment[i]).epsilon(1e-12));
    }
  }
  // px4 keeps its file; the sidecar only when asked.
  testing::ProgramRun r = Calibrate("export " + fit + " --to px4 --sensor 2 -o " + dir +
                                    "t.params --covariance " + dir + "t.cov.json");
  REQUIRE(r.exit_code == 0);
  CHECK(std::filesystem::exists(dir + "t.cov.json"));
  r = Calibrate("import " + dir + "t.params --from px4 --covariance " + dir + "t.cov.json");
  INFO(r.err);
  CHECK(r.exit_code == 0);
  CHECK_THAT(r.err, Catch::Contains("not carried: the misalignment"));
}

TEST_CASE("calibrate import flags implausible gains and refuses malformed files",
          "[apps][interchange]") {
  testing::TempFile yaml(
      "imu0:\n  model: scale-misalignment\n  accelerometers:\n    M:\n    - [1, 0, 0]\n"
      "    - [0, 1, 0]\n    - [0, 0, 1]\n  gyroscopes:\n    A:\n    - [0, 0, 0]\n    - [0, 0, "
      "0]\n    - [0, 0, 0]\n    C_gyro_i:\n    - [1, 0, 0]\n    - [0, 1, 0]\n    - [0, 0, 1]\n"
      "    M:\n    - [0.45, 0, 0]\n    - [0, 0.5, 0]\n    - [0, 0, 0.48]\n");
  testing::ProgramRun r = Calibrate("import " + yaml.path() + " --from kalibr");
  CHECK(r.exit_code == 0);
  CHECK_THAT(r.err, Catch::Contains("implausible gyroscope gain: imu0.gyroscopes.M[0][0] = 0.45"));
  CHECK_THAT(r.err, Catch::Contains("standard uncertainties are unknown"));
  testing::TempFile bad("imu0:\n  model: scale-misalignment\n  gyroscope: {}\n");
  r = Calibrate("import " + bad.path() + " --from kalibr");
  CHECK(r.exit_code == 2);
  CHECK_THAT(r.err, Catch::Contains(bad.path() +
                                    ":3:3: imu0.gyroscope: unknown key (nearest: gyroscopes)"));
  r = Calibrate("import " + bad.path() + " --from vins");
  CHECK(r.exit_code == 2);
  CHECK_THAT(r.err, Catch::Contains("expected kalibr, openvins"));
}

}  // namespace
}  // namespace metro
#endif
