// calibrate export on the bundled session's fit: PX4 and ArduPilot files, what they cannot
// hold on stderr, refusals with exit 2.
#ifdef METRO_CALIBRATE_EXE
#include <catch2/catch.hpp>
#include <string>

#include "support/bundled_fit.hpp"
#include "support/run_program.hpp"

namespace metro {
namespace {

testing::ProgramRun Calibrate(const std::string& args) {
  return testing::RunProgram(METRO_CALIBRATE_EXE, args);
}

TEST_CASE("calibrate export writes PX4 and ArduPilot parameters and names what they lack",
          "[apps][export]") {
  const std::string fit = testing::BundledFit("");
  testing::ProgramRun r = Calibrate("export " + fit + " --to ardupilot --sensor 2 -o -");
  INFO(r.err);
  REQUIRE(r.exit_code == 0);
  for (const char* name : {"INS_ACCOFFS_X,", "INS_ACCSCAL_Z,", "INS_GYROFFS_Y,"}) {
    CHECK_THAT(r.out, Catch::Contains(name));
  }
  // The bundled tag has cross-axis terms and a gyroscope scale: named on stderr.
  CHECK_THAT(r.err, Catch::Contains("ardupilot cannot hold the misalignment"));
  CHECK_THAT(r.err, Catch::Contains("gyroscope's scale factors"));
  r = Calibrate("export " + fit + " --to px4 --sensor 2 --px4-accel-device-id 2490378 -o -");
  REQUIRE(r.exit_code == 0);
  CHECK_THAT(r.out, Catch::Contains("1\t1\tCAL_ACC0_ID\t2490378\t6"));
  CHECK_THAT(r.out, Catch::Contains("CAL_GYRO0_ID not written"));
  r = Calibrate("export " + fit + " --to vins --sensor 2 -o -");
  CHECK(r.exit_code == 2);
  CHECK_THAT(r.err, Catch::Contains("expected px4 or ardupilot"));
  r = Calibrate("export " + fit + " --to px4 --sensor 9 -o -");
  CHECK(r.exit_code == 2);
  CHECK_THAT(r.err, Catch::Contains("no sensor 9"));
}

}  // namespace
}  // namespace metro
#endif
