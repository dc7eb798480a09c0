// End-to-end: MCAP files and ROS bags through `characterize` (detected by their magic bytes
// or a bag folder) and `characterize topics`, with the counts their writers wrote
// (datasets/external/ros_samples/SOURCE.md); bad input is exit code 2.
#include <catch2/catch.hpp>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "support/run_program.hpp"
#include "support/temp_file.hpp"

namespace metro {
namespace {

const std::string kDir = std::string(METRO_EXTERNAL_DATA_DIR) + "/ros_samples/";

testing::ProgramRun Characterize(const std::string& args) {
  return testing::RunProgram(METRO_CHARACTERIZE_EXE, args);
}

TEST_CASE("characterize BAG --type-a reads the IMU topic of MCAP, ROS 1 and ROS 2 bags",
          "[apps][ros]") {
  struct Case {
    const char* input;
    const char* format;
  };
  for (const Case& c : {Case{"imu_zstd.mcap", "mcap"}, Case{"ros1_bz2.bag", "rosbag1"},
                        Case{"rosbag2_sqlite", "rosbag2"}, Case{"rosbag2_mcap", "rosbag2"}}) {
    SECTION(c.input) {
      auto r = Characterize(kDir + c.input + " --type-a");
      INFO(r.err);
      REQUIRE(r.exit_code == 0);
      const auto report = nlohmann::json::parse(r.out);
      CHECK(report["input"]["format"] == c.format);
      CHECK(report["input"].count("dialect") == 0);  // Binary: no text dialect to report.
      CHECK(report["input"]["time"]["unit"] == "ns");
      REQUIRE(report["sensors"].size() == 1);
      CHECK(report["sensors"][0]["name"] == "/imu/data");  // Named by its topic.
      CHECK(report["sensors"][0]["quantities"]["gx_rads"]["type_a"]["n"] == 60);
      CHECK(report["sensors"][0]["quantities"]["az_mps2"]["type_a"]["n"] == 60);
    }
  }
}

TEST_CASE("A tags file's name for a sensor wins over its topic", "[apps][ros]") {
  testing::TempFile tags(R"({"1": {"name": "left IMU"}})", ".json");
  auto named = Characterize(kDir + "imu_zstd.mcap --type-a --tags " + tags.path());
  INFO(named.err);
  REQUIRE(named.exit_code == 0);
  CHECK(nlohmann::json::parse(named.out)["sensors"][0]["name"] == "left IMU");
}

TEST_CASE("characterize topics lists an MCAP's topics; bad ROS input is exit 2", "[apps][ros]") {
  auto r = Characterize("topics " + kDir + "two_imus_zstd.mcap");
  REQUIRE(r.exit_code == 0);
  CHECK_THAT(r.out, Catch::Contains("/imu0                            sensor_msgs/msg/Imu       "
                                    "                 48     200.00"));
  CHECK_THAT(r.out, Catch::Contains("/imu1                            sensor_msgs/msg/Imu       "
                                    "                 24     100.00"));
  auto several = Characterize(kDir + "two_imus_zstd.mcap --type-a");
  CHECK(several.exit_code == 2);
  CHECK_THAT(several.err, Catch::Contains("2 IMU topics: /imu0"));
  auto two = Characterize(kDir + "two_imus_zstd.mcap --type-a --topic /imu0 --topic /imu1");
  INFO(two.err);
  REQUIRE(two.exit_code == 0);
  CHECK(nlohmann::json::parse(two.out)["sensors"].size() == 2);
  auto missing = Characterize(kDir + "ros1_lz4.bag --type-a --topic /imu/raw");
  CHECK(missing.exit_code == 2);
  CHECK_THAT(missing.err, Catch::Contains("--topic /imu/raw: no such topic"));
  std::ifstream in(kDir + "ros1_none.bag", std::ios::binary);
  std::stringstream bytes;
  bytes << in.rdbuf();
  testing::TempFile cut(bytes.str().substr(0, 9000), ".bag");
  auto strict = Characterize(cut.path() + " --type-a");
  CHECK(strict.exit_code == 2);
  CHECK_THAT(strict.err, Catch::Contains("a record runs past the file's end"));
  auto lenient = Characterize(cut.path() + " --type-a --lenient");
  INFO(lenient.err);
  CHECK(lenient.exit_code == 0);
  auto topics_cut = Characterize("topics " + cut.path());
  CHECK(topics_cut.exit_code == 2);
}

}  // namespace
}  // namespace metro
