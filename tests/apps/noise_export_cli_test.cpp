// End-to-end: characterize --allan --export, noise-export and noise-compare (issue #40):
// exit codes, the files, the refusals and the errors at file:line:column.
#include <fmt/format.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>

#include "support/noise_generators.hpp"
#include "support/run_program.hpp"
#include "support/temp_file.hpp"
#include "support/text_position.hpp"

namespace metro {
namespace {

testing::ProgramRun Characterize(const std::string& args) {
  return testing::RunProgram(METRO_CHARACTERIZE_EXE, args);
}

using testing::ReadText;

// 30 min at 100 Hz of Kalibr's discrete model on six axes in SI columns, N and K chosen so
// that K rules from ~10 s (sqrt(3) N / K = 10 s) and the fit resolves both.
std::string KalibrSession() {
  const size_t n = 180000;
  const double dt = 0.01, noise = 0.005, walk = std::sqrt(3.0) * 0.005 / 10.0;
  std::vector<std::vector<double>> axes;
  for (uint64_t seed = 0; seed < 6; ++seed) {
    axes.push_back(testing::KalibrImuRate(n, dt, noise, walk, 9100 + seed));
  }
  std::string csv = "t_s,sensor,ax_mps2,ay_mps2,az_mps2,gx_rads,gy_rads,gz_rads\n";
  for (size_t k = 0; k < n; ++k) {
    csv += fmt::format("{:.2f},1,{:.9e},{:.9e},{:.9e},{:.9e},{:.9e},{:.9e}\n", k * dt, axes[0][k],
                       axes[1][k], 9.80665 + axes[2][k], axes[3][k], axes[4][k], axes[5][k]);
  }
  return csv;
}

TEST_CASE("characterize exports noise files and compares them back", "[apps][export]") {
  const std::string dir = testing::MakeScratchFolder("metro_noise_export_cli");
  testing::TempFile session(KalibrSession());
  const std::string report = dir + "r.json", yaml = dir + "imu.yaml";
  testing::ProgramRun r = Characterize(session.path() + " --allan -o " + report +
                                       " --export kalibr --export-file " + yaml + " --quiet");
  INFO(r.err);
  REQUIRE(r.exit_code == 0);
  const std::string text = ReadText(yaml);
  CHECK(text.find("update_rate: 100\n") != std::string::npos);
  CHECK(text.find("# u: standard uncertainty (k = 1)") != std::string::npos);

  r = Characterize("noise-compare " + yaml + " " + report);
  INFO(r.err);
  REQUIRE(r.exit_code == 0);
  CHECK(r.out.find("(kalibr) against") != std::string::npos);
  CHECK(r.out.find("gyroscope_random_walk") != std::string::npos);

  for (const char* f : {"openvins", "basalt", "vins", "orbslam3", "gtsam", "px4-ekf2", "ros"}) {
    INFO(f);
    const std::string out = dir + "noise." + f;
    r = Characterize(
        fmt::format("noise-export {} --to {} -o {} --axis-reduction rms", report, f, out));
    REQUIRE(r.exit_code == 0);
    r = Characterize(fmt::format("noise-compare {} {} --axis-reduction rms", out, report));
    REQUIRE(r.exit_code == 0);
    CHECK(r.out.find(fmt::format("({}) against", f)) != std::string::npos);
  }

  // A negative density: exit 2 at its line and column.
  std::string bad = text;
  const size_t at = bad.find("gyroscope_noise_density: ") + 25;
  bad.insert(at, "-");
  testing::TempFile bad_file(bad, ".yaml");
  r = Characterize("noise-compare " + bad_file.path() + " " + report);
  CHECK(r.exit_code == 2);
  CHECK(r.err.find(bad_file.path() + ":" + testing::LineColumn(bad, at) +
                   ": gyroscope_noise_density: expected a non-negative noise value") !=
        std::string::npos);
}

TEST_CASE("characterize refuses an unresolved term and an unknown format", "[apps][export]") {
  const std::string dir = testing::MakeScratchFolder("metro_noise_export_cli_refuse");
  const std::string report = dir + "s.json", yaml = dir + "s.yaml";
  // 60 s of the bundled static record: K is not resolved. The report is written, the noise
  // file is not.
  testing::ProgramRun r =
      Characterize(std::string(METRO_SOURCE_DIR) + "/datasets/static_imu_100hz.csv --allan -o " +
                   report + " --export kalibr --export-file " + yaml + " --quiet");
  CHECK(r.exit_code == 2);
  CHECK(r.err.find("--export kalibr: not written: ax_g rate_random_walk (K): not resolved by "
                   "the record") != std::string::npos);
  CHECK(std::ifstream(report).good());
  CHECK_FALSE(std::ifstream(yaml).good());
  r = Characterize("noise-export " + report + " --to kalibr");
  CHECK(r.exit_code == 2);
  CHECK(r.err.find("metro does not fill it in") != std::string::npos);
  r = Characterize("noise-export " + report + " --to kalibr2");
  CHECK(r.exit_code == 2);
  CHECK(r.err.find("unknown noise export format 'kalibr2'") != std::string::npos);
}

}  // namespace
}  // namespace metro
