// End-to-end: a PX4 ULog through `characterize` (detected by its magic bytes) and
// `characterize topics`, with the counts pyulog's ulog_info gives for the same file
// (datasets/external/px4_pyulog_samples/sample_info.txt: sensor_combined (0, 72) 17070).
#include <catch2/catch.hpp>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "support/run_program.hpp"
#include "support/temp_file.hpp"

namespace metro {
namespace {

const std::string kDir = std::string(METRO_EXTERNAL_DATA_DIR) + "/px4_pyulog_samples/";

testing::ProgramRun Characterize(const std::string& args) {
  return testing::RunProgram(METRO_CHARACTERIZE_EXE, args);
}

TEST_CASE("characterize FILE.ulg --type-a reads sensor_combined", "[apps][ulog]") {
  auto r = Characterize(kDir + "sample.ulg --type-a");
  INFO(r.err);
  REQUIRE(r.exit_code == 0);
  const auto report = nlohmann::json::parse(r.out);
  CHECK(report["input"]["format"] == "ulog");
  CHECK(report["input"].count("dialect") == 0);  // Binary: no text dialect to report.
  CHECK(report["input"]["time"]["unit"] == "us");
  CHECK(report["input"]["time"]["integer"] == true);
  REQUIRE(report["sensors"].size() == 1);
  const auto& q = report["sensors"][0]["quantities"];
  CHECK(q["gx_rads"]["type_a"]["n"] == 17070);
  CHECK(q["az_mps2"]["type_a"]["n"] == 17070);
  // The same through a pipe: a ULog is binary by design, not refused as binary data.
  std::ifstream in(kDir + "sample.ulg", std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  auto piped = testing::RunProgramWithStdin(METRO_CHARACTERIZE_EXE, "- --type-a", bytes);
  INFO(piped.err);
  REQUIRE(piped.exit_code == 0);
  CHECK(nlohmann::json::parse(piped.out)["sensors"][0]["quantities"]["gz_rads"]["type_a"]["n"] ==
        17070);
  // --topic chooses; --format ulog forces; a topic that is not an IMU's is exit 2.
  auto bad = Characterize(kDir + "sample.ulg --type-a --format ulog --topic vehicle_attitude");
  CHECK(bad.exit_code == 2);
  CHECK_THAT(bad.err, Catch::Contains("--topic vehicle_attitude: not an IMU topic"));
}

TEST_CASE("characterize topics lists a ULog's topics", "[apps][ulog]") {
  auto r = Characterize("topics " + kDir + "sample.ulg");
  INFO(r.err);
  REQUIRE(r.exit_code == 0);
  std::istringstream lines(r.out);
  std::string line;
  bool found = false;
  while (std::getline(lines, line)) {
    std::istringstream f(line);
    std::string topic;
    int multi = -1;
    long count = 0, size = 0;
    double rate = 0;
    if (f >> topic >> multi >> count >> size >> rate && topic == "sensor_combined") {
      found = true;
      CHECK(multi == 0);
      CHECK(count == 17070);
      CHECK(size == 72);
      CHECK(rate == Approx(247.81).margin(0.01));
    }
  }
  CHECK(found);
  CHECK_THAT(r.out, Catch::Contains("dropouts: 4 ("));
  // A truncated copy: exit 2 with the file and byte offset; --lenient lists what is complete.
  std::ifstream in(kDir + "sample_log_small.ulg", std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  testing::TempFile cut(bytes.substr(0, 500000), ".ulg");
  auto bad = Characterize("topics " + cut.path());
  CHECK(bad.exit_code == 2);
  CHECK_THAT(bad.err, Catch::Contains(cut.path() + ": byte offset "));
  CHECK_THAT(bad.err, Catch::Contains("truncated file"));
  auto lenient = Characterize("topics --lenient " + cut.path());
  CHECK(lenient.exit_code == 0);
  CHECK_THAT(lenient.out, Catch::Contains("truncated: the last"));
  auto analyze = Characterize(cut.path() + " --type-a");
  CHECK(analyze.exit_code == 2);
  CHECK_THAT(analyze.err, Catch::Contains("truncated file"));
}

TEST_CASE("characterize convert FILE.ulg writes a session.csv that reads back the same",
          "[apps][ulog]") {
  const std::string csv = "metro_ulog_convert_test.csv";
  auto conv = Characterize("convert " + kDir + "sample.ulg -o " + csv);
  INFO(conv.err);
  REQUIRE(conv.exit_code == 0);
  auto direct = Characterize(kDir + "sample.ulg --type-a");
  auto back = Characterize(csv + " --type-a");
  std::remove(csv.c_str());
  REQUIRE(direct.exit_code == 0);
  REQUIRE(back.exit_code == 0);
  const auto a = nlohmann::json::parse(direct.out)["sensors"][0]["quantities"];
  const auto b = nlohmann::json::parse(back.out)["sensors"][0]["quantities"];
  for (const char* q : {"gx_rads", "gy_rads", "gz_rads", "ax_mps2", "ay_mps2", "az_mps2"}) {
    INFO(q);
    CHECK(a[q]["type_a"]["n"] == b[q]["type_a"]["n"]);
    CHECK(a[q]["type_a"]["mean"].get<double>() == b[q]["type_a"]["mean"].get<double>());
    CHECK(a[q]["type_a"]["u_mean"].get<double>() == b[q]["type_a"]["u_mean"].get<double>());
  }
}

}  // namespace
}  // namespace metro
