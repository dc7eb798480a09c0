// End-to-end: the load flags every command shares (apps/load_cli.hpp), convert's among them,
// convert's join of the per-sensor files of one recording, each asserting the numbers that
// come out, and the names third-party files' sensors are given.
#include <catch2/catch.hpp>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "support/run_program.hpp"
#include "support/temp_file.hpp"

namespace metro {
namespace {

using testing::TempFile;

const std::string kDatasets = std::string(METRO_SOURCE_DIR) + "/datasets/";
const std::string kExternal = std::string(METRO_EXTERNAL_DATA_DIR) + "/";
const std::string kEuroc = kExternal + "euroc_v1_01_easy_imu0_kimera/data.csv";

testing::ProgramRun Characterize(const std::string& args) {
  return testing::RunProgram(METRO_CHARACTERIZE_EXE, args);
}

std::string Slurp(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST_CASE("characterize reads a mapped header with --column and --rate-hz", "[apps][formats]") {
  // No time column, a non-canonical header, decimal commas: 2.5, 3.5, 2.5, 3.5 deg/s.
  TempFile file("Gyro Z (deg/s)\n2,5\n3,5\n2,5\n3,5\n");
  auto r = Characterize(file.path() + " --type-a --rate-hz 50 --column 'Gyro Z (deg/s)=gz_dps'");
  REQUIRE(r.exit_code == 0);
  const auto report = nlohmann::json::parse(r.out);
  CHECK(report["input"]["time"]["unit"] == "rate");
  CHECK(report["input"]["time"]["rate_hz"] == 50);
  const auto& q = report["sensors"][0]["quantities"]["gz_dps"]["type_a"];
  CHECK(q["mean"].get<double>() == 3.0);
  CHECK(q["n"] == 4);
  // Without the mapping: exit 2 and the mapping proposed.
  auto bad = Characterize(file.path() + " --type-a --rate-hz 50");
  CHECK(bad.exit_code == 2);
  CHECK_THAT(bad.err, Catch::Contains("--column 'Gyro Z (deg/s)=gz_dps'"));
  auto bad_map = Characterize(file.path() + " --type-a --column nonsense");
  CHECK(bad_map.exit_code == 2);
  CHECK_THAT(bad_map.err, Catch::Contains("expected SRC=DST"));
}

TEST_CASE("raw prints with full-scale flags", "[apps][formats]") {
  TempFile file("Fs,100\nax,ay,az\n0,0,16384\n0,0,16384\n0,0,8192\n0,0,8192\n");
  auto r = Characterize(file.path() + " --type-a --accel-fs-g 2");
  REQUIRE(r.exit_code == 0);
  const auto report = nlohmann::json::parse(r.out);
  CHECK(report["input"]["format"] == "raw");
  // 16384 and 8192 counts at 16384 LSB/g: 1 g and 0.5 g, mean 0.75 g.
  CHECK(report["sensors"][0]["quantities"]["az_g"]["type_a"]["mean"].get<double>() == 0.75);
  CHECK(report["sensors"][0]["quantities"]["az_lsb"]["type_a"]["mean"].get<double>() == 12288);
}

TEST_CASE("convert joins Sensor Logger's per-sensor files on time", "[apps][formats]") {
  const int64_t t0 = 1700000000000000000;
  std::string gyro = "time,seconds_elapsed,z,y,x\n";
  std::string accel = "time,seconds_elapsed,z,y,x\n";
  for (int i = 0; i < 20; ++i) {
    gyro += std::to_string(t0 + 10000000LL * i) + ",0," + "0.5,0.25," + std::to_string(i) + "\n";
    // The accelerometer 3 ms later; its first two samples have no gyroscope partner.
    accel += std::to_string(t0 + 3000000 + 10000000LL * (i - 2)) + ",0,9.75,0,-1\n";
  }
  TempFile g(gyro, "_Gyroscope.csv");
  TempFile a(accel, "_Accelerometer.csv");
  const std::string out = "metro_cli_joined.csv";
  std::remove(out.c_str());
  auto r = Characterize("convert " + g.path() + " " + a.path() + " -o " + out);
  REQUIRE(r.exit_code == 0);
  // Gyroscope samples 18, 19 and accelerometer samples 0, 1 have no partner.
  CHECK_THAT(r.err, Catch::Contains("20 samples, 2 in no joined row"));
  auto report = Characterize(out + " --type-a");
  REQUIRE(report.exit_code == 0);
  const auto j = nlohmann::json::parse(report.out);
  // Gyro samples 0..17 have accelerometer partners (3 ms away, within half of 10 ms).
  CHECK(j["sensors"][0]["quantities"]["gx_rads"]["type_a"]["n"] == 18);
  CHECK(j["sensors"][0]["quantities"]["gx_rads"]["type_a"]["mean"].get<double>() == 8.5);
  CHECK(j["sensors"][0]["quantities"]["az_mps2"]["type_a"]["mean"].get<double>() == 9.75);
  CHECK(j["input"]["time"]["unit"] == "ns");
  CHECK(Slurp(out).find("t_ns,sensor,gz_rads") != std::string::npos);
  std::remove(out.c_str());
}

// The first line of `text` (a refused command's error).
std::string FirstLine(const std::string& text) { return text.substr(0, text.find('\n')); }

TEST_CASE("convert --format accepts and refuses what characterize SESSION --format does",
          "[apps][formats][issue39]") {
  // The values docs/formats.md lists for --format, and values it does not: imu_tk's pair is a
  // flag of its own (--imutk), names are case-sensitive, an empty value is no format.
  const std::vector<std::string> accepted = {"auto", "csv",     "receiver",    "euroc",
                                             "raw",  "phyphox", "sensorlogger"};
  const std::vector<std::string> refused = {"imutk", "bogus", "CSV", "''"};
  // A thesis session.csv and a EuRoC file: each value reads one, the other or neither.
  for (const std::string& file : {kDatasets + "static_chest.csv", kEuroc}) {
    for (const std::string& value : accepted) {
      INFO(file << " --format " << value);
      auto main = Characterize(file + " --type-a --format " + value + " -o -");
      auto convert = Characterize("convert " + file + " --format " + value + " -o -");
      CHECK(main.exit_code == convert.exit_code);
      // A value that does not fit the file: the same error from the same loader.
      if (main.exit_code != 0) {
        CHECK(main.exit_code == 2);
        CHECK(FirstLine(main.err) == FirstLine(convert.err));
      }
    }
    for (const std::string& value : refused) {
      INFO(file << " --format " << value);
      auto main = Characterize(file + " --type-a --format " + value + " -o -");
      auto convert = Characterize("convert " + file + " --format " + value + " -o -");
      CHECK(main.exit_code == 2);
      CHECK(convert.exit_code == 2);
      CHECK_THAT(main.err, Catch::Contains("--format"));
      CHECK(FirstLine(main.err) == FirstLine(convert.err));
    }
  }
  // Where the format fits: session.csv as csv or detected, EuRoC as euroc or detected.
  CHECK(Characterize("convert " + kDatasets + "static_chest.csv --format csv -o -").exit_code == 0);
  CHECK(Characterize("convert " + kEuroc + " --format euroc -o -").exit_code == 0);
  CHECK(Characterize(kEuroc + " --type-a --format euroc -o -").exit_code == 0);
  // convert's older --from FORMAT still works and writes what --format writes.
  auto from = Characterize("convert " + kEuroc + " --from euroc -o -");
  auto format = Characterize("convert " + kEuroc + " --format euroc -o -");
  REQUIRE(from.exit_code == 0);
  CHECK(from.out == format.out);
  CHECK(Characterize("convert " + kEuroc + " --from bogus -o -").exit_code == 2);
  CHECK(Characterize("convert " + kEuroc + " --from euroc --format euroc -o -").exit_code == 2);
}

TEST_CASE("convert --imutk and the older --from imutk read imu_tk's pair alike",
          "[apps][formats][issue39]") {
  // Two samples of imu_tk's whitespace-separated `timestamp_s x y z` raw counts.
  TempFile acc("0.00 10 20 16384\n0.01 12 22 16380\n", "_acc.txt");
  TempFile gyro("0.00 1 2 3\n0.01 4 5 6\n", "_gyro.txt");
  auto flag = Characterize("convert --imutk " + acc.path() + " " + gyro.path() + " -o -");
  auto from = Characterize("convert --from imutk " + acc.path() + " " + gyro.path() + " -o -");
  REQUIRE(flag.exit_code == 0);
  CHECK(flag.out == from.out);
  CHECK(flag.out.find("\n0.01,1,12,22,16380,4,5,6") != std::string::npos);
  // imutk is not a --format value (it takes two files), and the flag excludes --format.
  CHECK(Characterize("convert --format imutk " + acc.path() + " " + gyro.path() + " -o -")
            .exit_code == 2);
  auto both =
      Characterize("convert --imutk --format csv " + acc.path() + " " + gyro.path() + " -o -");
  CHECK(both.exit_code == 2);
  CHECK_THAT(both.err, Catch::Contains("--format"));
  auto one = Characterize("convert --imutk " + acc.path() + " -o -");
  CHECK(one.exit_code == 2);
  CHECK_THAT(one.err, Catch::Contains("--imutk takes two inputs: ACC GYRO"));
}

TEST_CASE("A third-party file's sensor is 'sensor N', not a thesis tag's body part",
          "[apps][formats][issue39]") {
  // Thesis Table 5.2 names the thesis tags (sensor 1 Forehead, 2 Chest): a EuRoC flight, a
  // phyphox and a Sensor Logger phone, and raw MPU6050 prints are sensor 1 of another IMU
  // (the flags each file needs as in real_records_cli_test.cpp).
  struct File {
    std::string args;
    std::string format;
  };
  const std::vector<File> files = {
      {kEuroc, "euroc"},
      {kExternal + "phyphox_deadreckoning_walk/Gyroscope.csv --format phyphox --column "
                   "'X (rad/s)=gx_rads' --column 'Y (rad/s)=gy_rads' --column 'Z (rad/s)=gz_rads'",
       "phyphox"},
      {kExternal + "sensorlogger_kalmannet_static/noise_Gyr.csv --column x=gx_rads --column "
                   "y=gy_rads --column z=gz_rads",
       "sensorlogger"},
      {kExternal + "mpu6050_imucalibration_static_7min/example_data_tinit_calc.csv", "raw"}};
  for (const auto& [args, format] : files) {
    INFO(args);
    auto r = Characterize(args + " --type-a -o -");
    REQUIRE(r.exit_code == 0);
    const auto report = nlohmann::json::parse(r.out);
    CHECK(report["input"]["format"] == format);
    REQUIRE(report["sensors"].size() == 1);
    CHECK(report["sensors"][0]["sensor"] == 1);
    CHECK(report["sensors"][0]["name"] == "sensor 1");
  }
  // The thesis tags' own file keeps its tag's name.
  auto chest = Characterize(kDatasets + "static_chest.csv --type-a -o -");
  REQUIRE(chest.exit_code == 0);
  CHECK(nlohmann::json::parse(chest.out)["sensors"][0]["name"] == "Chest");
  // A tags file that names the sensor names it whatever the file.
  TempFile tags(R"({"1": "ADIS16448 on the MAV"})", ".json");
  auto named = Characterize(kEuroc + " --type-a --tags " + tags.path() + " -o -");
  REQUIRE(named.exit_code == 0);
  CHECK(nlohmann::json::parse(named.out)["sensors"][0]["name"] == "ADIS16448 on the MAV");
  // The page of a EuRoC report named after the fact by a file that names another tag.
  const std::string report = "metro_formats_cli_euroc_report.json";
  const std::string page = "metro_formats_cli_euroc_report.html";
  REQUIRE(Characterize(kEuroc + " --type-a -q -o " + report).exit_code == 0);
  TempFile other(R"({"2": "Bench Tag"})", ".json");
  auto html = Characterize("report " + report + " --html " + page + " --tags " + other.path());
  REQUIRE(html.exit_code == 0);
  CHECK(Slurp(page).find("Forehead") == std::string::npos);
  CHECK(Slurp(page).find("sensor 1") != std::string::npos);
  std::remove(report.c_str());
  std::remove(page.c_str());
}

}  // namespace
}  // namespace metro
