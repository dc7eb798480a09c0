// End-to-end: the spec library on the command line (issue #40 step 5): --spec-part on a
// record simulated at the MPU-6050's typical densities, noise-compare --spec-part ADIS16448,
// noise-export --from-spec, and the refusals' exit codes.
#include <fmt/format.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "support/noise_generators.hpp"
#include "support/run_program.hpp"
#include "support/temp_file.hpp"

namespace metro {
namespace {

testing::ProgramRun Characterize(const std::string& args) {
  return testing::RunProgram(METRO_CHARACTERIZE_EXE, args);
}

using testing::ReadText;

// 10 min at 100 Hz, one accelerometer and one gyroscope axis whose white noise is the
// MPU-6050's typical one-sided density d (400 ug/sqrt(Hz), 0.005 deg/s/sqrt(Hz)) as
// N = d / sqrt(2), in the units of the report (g, deg/s).
std::string TypicalMpu6050Session() {
  const size_t n = 60000;
  const double dt = 0.01;
  const std::vector<double> a = testing::KalibrImuRate(n, dt, 400e-6 / std::sqrt(2.0), 1e-9, 71);
  const std::vector<double> g = testing::KalibrImuRate(n, dt, 0.005 / std::sqrt(2.0), 1e-9, 72);
  std::string csv = "t_s,sensor,az_g,gx_dps\n";
  for (size_t k = 0; k < n; ++k)
    csv += fmt::format("{:.2f},1,{:.9e},{:.9e}\n", k * dt, 1.0 + a[k], g[k]);
  return csv;
}

TEST_CASE("characterize --spec-part judges N against the MPU-6050 densities (not limits)",
          "[apps][specs]") {
  testing::ScratchFolder dir("metro_spec_cli");
  testing::TempFile session(TypicalMpu6050Session());
  const std::string report = dir.path() + "r.json";
  const std::string page = dir.path() + "r.html";
  testing::ProgramRun r = Characterize(session.path() + " --allan --spec-part mpu-6050 -o " +
                                       report + " --html " + page);
  INFO(r.err);
  REQUIRE(r.exit_code == 0);
  CHECK_THAT(r.err, Catch::Contains("unstated is not a specification limit"));
  const nlohmann::json j = nlohmann::json::parse(ReadText(report));
  REQUIRE(j.contains("spec"));
  CHECK(j["spec"]["part"] == "MPU6050");
  int judged = 0;
  for (const nlohmann::json& row : j["spec"]["rows"]) {
    if (row["term"] != "random_walk" || !row.contains("ratio")) continue;
    ++judged;
    // The simulated density is the typical one: ratio 1 within a few u (10 min record).
    const double ratio = row["ratio"], u = row["u"], figure = row["figure"]["value"];
    CHECK(std::abs(ratio - 1.0) < 4.0 * u / figure);
    CHECK_FALSE(row.contains("decision"));  // unstated (as typ): no pass or fail.
  }
  CHECK(judged == 2);
  // The page shows the same rows: each judged figure with its document and the note.
  const std::string html = ReadText(page);
  CHECK_THAT(html, Catch::Contains("<table id=\"spec-table\">"));
  CHECK_THAT(html, Catch::Contains("Against the datasheet: MPU6050"));
  CHECK_THAT(html, Catch::Contains("PS-MPU-6000A-00"));
  CHECK_THAT(html, Catch::Contains("unstated is not a specification limit"));
}

TEST_CASE("characterize --spec-part refusals", "[apps][specs]") {
  testing::TempFile session(TypicalMpu6050Session());
  testing::ProgramRun r = Characterize(session.path() + " --allan --spec-part BMI999 --quiet");
  CHECK(r.exit_code == 2);
  CHECK_THAT(r.err, Catch::Contains("no part 'BMI999'"));
  r = Characterize(session.path() + " --spec-part MPU6050 --quiet");
  CHECK(r.exit_code == 2);
  CHECK_THAT(r.err, Catch::Contains("--spec-part needs --allan"));
  // A bad library stops before the analysis, at its file:line:column.
  testing::TempFile bad("{\"schema\": \"metro.specs/1\", \"parts\": [{\"prat\": 1}]}\n");
  r = Characterize(session.path() + " --allan --spec-part MPU6050 --spec-library " + bad.path() +
                   " --quiet");
  CHECK(r.exit_code == 2);
  CHECK_THAT(r.err, Catch::Contains(bad.path() + ":1:48: ") && Catch::Contains("no member 'prat'"));
  // Only published configurations: the report is written, the spec decision refused.
  r = Characterize(session.path() + " --allan --spec-part ADIS16448 --quiet");
  CHECK(r.exit_code == 2);
  CHECK_THAT(r.err, Catch::Contains("no datasheet figure of ADIS16448"));
}

TEST_CASE("noise-compare --spec-part ADIS16448 shows EuRoC against Kalibr", "[apps][specs]") {
  testing::ProgramRun r = Characterize("noise-compare --spec-part ADIS16448");
  INFO(r.err);
  REQUIRE(r.exit_code == 0);
  // accelerometer_random_walk: 3.0e-3 (EuRoC) / 4.33e-4 (Kalibr) = 6.928.
  CHECK_THAT(r.out, Catch::Contains("accelerometer_random_walk") && Catch::Contains("ratio 6.928"));
  r = Characterize("noise-compare --spec-part ADIS16448 --reference euroc_sensor_yaml");
  REQUIRE(r.exit_code == 0);
  CHECK_THAT(r.out, Catch::Contains("ratio 0.1443"));  // 4.33e-4 / 3.0e-3
  r = Characterize("noise-compare");
  CHECK(r.exit_code == 2);
  CHECK_THAT(r.err, Catch::Contains("or --spec-part PART"));
}

TEST_CASE("noise-export --from-spec writes Kalibr's imu.yaml or refuses K", "[apps][specs]") {
  testing::ProgramRun r = Characterize(
      "noise-export --from-spec MPU6050 --to kalibr "
      "--update-rate-hz 200");
  CHECK(r.exit_code == 2);
  CHECK_THAT(r.err, Catch::Contains("accelerometer_random_walk, gyroscope_random_walk: refused"));
  r = Characterize("noise-export --from-spec MPU6050 --to kalibr --update-rate-hz 200 --partial");
  INFO(r.err);
  REQUIRE(r.exit_code == 0);
  // 400 ug/sqrt(Hz) one-sided -> N = 400e-6 * 9.80665 / sqrt(2) m/s^2/sqrt(Hz).
  CHECK_THAT(r.out, Catch::Contains(fmt::format("accelerometer_noise_density: {:.17g}",
                                                400e-6 * 9.80665 / std::sqrt(2.0))));
  r = Characterize("noise-export --from-spec MPU6050 --to vins --update-rate-hz 200");
  CHECK(r.exit_code == 2);
  CHECK_THAT(r.err, Catch::Contains("only --to kalibr"));
}

}  // namespace
}  // namespace metro
