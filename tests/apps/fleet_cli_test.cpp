// Fleets (issue #25 point 3): one tags file gives each tag's device ID and profile to
// `calibrate fit` (calibration.json's device_id), `calibrate blob` (one tag, or --all into a
// directory); the blobs carry the device IDs the file names, in either word order.
#include <sys/stat.h>

#include <catch2/catch.hpp>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "metro/blob/blob.hpp"
#include "metro/blob/from_calibration.hpp"
#include "metro/calibration/calibration_io.hpp"
#include "metro/core/file.hpp"
#include "support/run_program.hpp"
#include "support/text_position.hpp"

namespace metro {
namespace {

const std::string kDatasets = std::string(METRO_SOURCE_DIR) + "/datasets/";

std::vector<uint8_t> Bytes(const std::string& path) {
  Result<std::string> s = ReadFile(path);
  REQUIRE(s.ok());
  return std::vector<uint8_t>(s.value().begin(), s.value().end());
}

}  // namespace

#ifdef METRO_CALIBRATE_EXE
TEST_CASE("Fleet: a tags file gives calibrate fit and blob each tag's device ID", "[apps][blob]") {
  auto run = [](const std::string& args) { return testing::RunProgram(METRO_CALIBRATE_EXE, args); };
  const std::string tags = "metro_fleet_tags.json";
  // Sensor 2 in nrfjprog's word order, sensor 3 in metro's; sensor 4 without a device ID.
  std::ofstream(tags) << R"({"2": {"name": "Chest", "device_id": "12345678 9ABCDEF0"},
                             "3": {"name": "Left Arm", "device_id": "0x0011223344556677",
                                   "profile": "mpu6050"},
                             "4": "Right Arm"})";
  // fit --tags: calibration.json carries the device ID.
  const std::string cal = "metro_fleet_cal.json";
  testing::ProgramRun r =
      run("fit " + kDatasets + "calibration_session.csv -o " + cal + " -q --tags " + tags);
  REQUIRE(r.exit_code == 0);
  Result<Calibration> fitted = LoadCalibration(cal);
  REQUIRE(fitted.ok());
  CHECK(fitted.value().tags.at(0).device_id == 0x9ABCDEF012345678ull);
  CHECK(ReadFile(cal).value().find("\"device_id\": \"9ABCDEF012345678\"") != std::string::npos);

  // blob without --device-id: the tags file's (or calibration.json's) ID; the same bytes as
  // with the ID given.
  REQUIRE(run("blob " + cal + " --sensor 2 --tags " + tags + " --seq 3 -o metro_fleet_a.bin -q")
              .exit_code == 0);
  REQUIRE(run("blob " + cal + " --sensor 2 --seq 3 -o metro_fleet_b.bin -q").exit_code == 0);
  REQUIRE(run("blob " + cal +
              " --sensor 2 --device-id 9abcdef012345678 --seq 3 -o "
              "metro_fleet_c.bin -q")
              .exit_code == 0);
  CHECK(Bytes("metro_fleet_a.bin") == Bytes("metro_fleet_c.bin"));
  CHECK(Bytes("metro_fleet_b.bin") == Bytes("metro_fleet_c.bin"));
  // calibration.json's device is sensor 3's in another tags file: refused, not bound to it.
  const std::string moved = "metro_fleet_moved.json";
  std::ofstream(moved) << R"({"3": {"name": "Left Arm", "device_id": "9ABCDEF012345678"}})";
  r = run("blob " + cal + " --sensor 2 --tags " + moved + " -o metro_fleet_d.bin");
  CHECK(r.exit_code == 2);
  // At calibration.json's device_id, naming the tags file's (`{"3": {"name": "Left Arm",
  // "device_id": ` is 40 characters).
  const std::string cal_text = ReadFile(cal).value();
  const std::string cal_at = testing::LineColumn(cal_text, cal_text.find("\"device_id\": ") + 13);
  CHECK(r.err == "error: " + cal + ":" + cal_at +
                     ": device 9ABCDEF012345678 is sensor 3's in the tags file (" + moved +
                     ":1:41), not sensor 2's; expected one device per tag: sensor 2's own "
                     "device, or the calibration of sensor 3\n");
  CHECK_FALSE(std::ifstream("metro_fleet_d.bin").good());
  std::remove(moved.c_str());

  // --all: a calibration of sensors 2, 3 and 4 (the golden tag under three numbers).
  Result<Calibration> golden = LoadCalibration(kDatasets + "golden/calibration_sensor2.json");
  REQUIRE(golden.ok());
  Calibration fleet = golden.value();
  for (int sensor : {3, 4}) {
    TagCalibration t = golden.value().tags.at(0);
    t.sensor = sensor;
    fleet.tags.push_back(t);
  }
  const std::string fleet_cal = "metro_fleet_three.json";
  REQUIRE(WriteFileAtomically(fleet_cal, FormatCalibrationJson(fleet)).ok());
  const std::string dir = "metro_fleet_dir";
  ::mkdir(dir.c_str(), 0755);
  // Sensor 4 has no device ID: refused, nothing written.
  r = run("blob " + fleet_cal + " --all --tags " + tags + " -o " + dir);
  CHECK(r.exit_code == 2);
  CHECK(r.err ==
        "error: sensor 4: no device ID in the tags file or calibration.json (nothing "
        "written)\n");
  CHECK_FALSE(std::ifstream(dir + "/tag2.bin").good());
  fleet.tags.pop_back();
  REQUIRE(WriteFileAtomically(fleet_cal, FormatCalibrationJson(fleet)).ok());
  r = run("blob " + fleet_cal + " --all --tags " + tags + " --seq 7 -o " + dir);
  INFO(r.err);
  REQUIRE(r.exit_code == 0);
  CHECK(r.err.find("     2  Chest             9ABCDEF012345678  " + dir + "/tag2.bin") !=
        std::string::npos);
  CHECK(r.err.find("     3  Left Arm          0011223344556677  " + dir + "/tag3.bin") !=
        std::string::npos);
  for (const auto& [sensor, id] :
       {std::pair{2, 0x9ABCDEF012345678ull}, std::pair{3, 0x0011223344556677ull}}) {
    const std::string bin = dir + "/tag" + std::to_string(sensor) + ".bin";
    // The firmware's validator accepts it only for its own chip.
    Result<blob::BlobContents> decoded = blob::DecodeBlob(Bytes(bin), id);
    REQUIRE(decoded.ok());
    CHECK(decoded.value().device_id == id);
    CHECK(decoded.value().seq == 7);
    CHECK_FALSE(blob::DecodeBlob(Bytes(bin), id ^ 1).ok());
    CHECK(std::ifstream(dir + "/tag" + std::to_string(sensor) + ".hex").good());
    std::remove(bin.c_str());
    std::remove((dir + "/tag" + std::to_string(sensor) + ".hex").c_str());
  }
  // inspect --tags: which tag a blob is for, and a check against a tag's device.
  const std::string golden_bin = kDatasets + "golden/tag_sensor2.bin";  // device 9ABC...5678
  r = run("inspect " + golden_bin + " --tags " + tags);
  CHECK(r.exit_code == 0);
  CHECK(r.err == "slot file: device 9ABCDEF012345678 is sensor 2 (Chest) in " + tags + "\n");
  r = run("inspect " + golden_bin + " --tags " + tags + " --sensor 3");
  CHECK(r.exit_code == 1);
  CHECK(r.out.find("METRO_FW_E_FOREIGN") != std::string::npos);
  r = run("inspect " + golden_bin + " --tags " + tags + " --sensor 4");
  CHECK(r.exit_code == 2);
  CHECK(r.err == "error: sensor 4 has no device_id in " + tags + " (or give --device-id)\n");
  // Usage errors.
  r = run("blob " + fleet_cal + " --all --sensor 2 -o " + dir);
  CHECK(r.exit_code == 2);
  r = run("blob " + fleet_cal + " --all --tags " + tags + " -o metro_fleet_missing_dir");
  CHECK(r.exit_code == 2);
  CHECK(r.err.find("expected an existing directory") != std::string::npos);
  r = run("blob " + kDatasets + "golden/calibration_sensor2.json --sensor 2 -o x.bin");
  CHECK(r.exit_code == 2);
  CHECK(r.err.find("no device ID for sensor 2") != std::string::npos);
  ::rmdir(dir.c_str());
  for (const char* f : {"metro_fleet_a.bin", "metro_fleet_b.bin", "metro_fleet_c.bin"}) {
    std::remove(f);
  }
  std::remove(cal.c_str());
  std::remove(fleet_cal.c_str());
  std::remove(tags.c_str());
}
#endif

#ifdef METRO_CHARACTERIZE_EXE
TEST_CASE("Fleet: characterize names the tags from a tags file with device IDs", "[apps]") {
  const std::string tags = "metro_fleet_characterize_tags.json";
  std::ofstream(tags) << R"({"2": {"name": "Sternum", "device_id": "12345678 9ABCDEF0",
                                   "profile": "mpu6050"}})";
  for (const char* flag : {"--tags", "--tag-registry"}) {
    testing::ProgramRun r =
        testing::RunProgram(METRO_CHARACTERIZE_EXE,
                            kDatasets + "static_chest.csv --type-a -q -o - " + flag + " " + tags);
    INFO(flag << ": " << r.err);
    REQUIRE(r.exit_code == 0);
    CHECK(r.out.find("\"name\": \"Sternum\"") != std::string::npos);
  }
  std::ofstream(tags) << R"({"2": {"name": "Sternum", "device_id": "12345678"}})";
  testing::ProgramRun r = testing::RunProgram(
      METRO_CHARACTERIZE_EXE, kDatasets + "static_chest.csv --type-a -q -o - --tags " + tags);
  CHECK(r.exit_code == 2);
  // At the device_id's value, line 1 column 40 (issue #37).
  CHECK(r.err.find("error: " + tags + ":1:40: tag 2: device_id: device id '12345678': expected") ==
        0);
  std::remove(tags.c_str());
}
#endif

}  // namespace metro
