// The golden blob (datasets/golden/): the C++ side regenerates it byte for byte from the
// committed calibration.json, and `calibrate blob` / `calibrate inspect` behave as documented.
#include <sys/wait.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>

#include "metro/blob/from_calibration.hpp"
#include "metro/blob/intel_hex.hpp"
#include "metro/calibration/calibration_io.hpp"
#include "metro/core/file.hpp"
#include "support/run_program.hpp"

namespace metro::blob {
namespace {

const std::string kGolden = std::string(METRO_SOURCE_DIR) + "/datasets/golden/";

// The options of datasets/regenerate.sh.
BlobFromCalibrationOptions GoldenOptions() {
  BlobFromCalibrationOptions o;
  o.sensor = 2;
  o.device_id = 0x9ABCDEF012345678ull;
  o.seq = 3;
  return o;
}

std::vector<uint8_t> Bytes(const std::string& path) {
  Result<std::string> s = ReadFile(path);
  REQUIRE(s.ok());
  return std::vector<uint8_t>(s.value().begin(), s.value().end());
}

}  // namespace

TEST_CASE("The golden blob and HEX regenerate byte for byte from calibration.json", "[blob]") {
  Result<Calibration> cal = LoadCalibration(kGolden + "calibration_sensor2.json");
  REQUIRE(cal.ok());
  Result<BlobContents> contents = BlobContentsFromCalibration(cal.value(), GoldenOptions());
  REQUIRE(contents.ok());
  Result<std::vector<uint8_t>> blob = WriteBlob(contents.value());
  REQUIRE(blob.ok());
  CHECK(blob.value() == Bytes(kGolden + "tag_sensor2.bin"));
  Result<std::string> hex = WriteIntelHex(FactoryImage(blob.value(), kSlotAAddress, kSlotBAddress));
  REQUIRE(hex.ok());
  Result<std::string> golden_hex = ReadFile(kGolden + "tag_sensor2.hex");
  REQUIRE(golden_hex.ok());
  CHECK(hex.value() == golden_hex.value());
  // And it decodes to what went in (binary32 rounding only).
  Result<BlobContents> back = DecodeBlob(blob.value());
  REQUIRE(back.ok());
  CHECK(back.value().seq == 3u);
  CHECK(back.value().accel->b0_lsb[0] ==
        static_cast<double>(static_cast<float>(cal.value().FindTag(2)->accel->model.bias[0])));
}

#ifdef METRO_CALIBRATE_EXE
namespace {

using Run = testing::ProgramRun;

Run Calibrate(const std::string& args) { return testing::RunProgram(METRO_CALIBRATE_EXE, args); }

}  // namespace

TEST_CASE("calibrate blob writes the golden files and prints the nrfjprog command",
          "[blob][apps]") {
  const std::string bin = "metro_blob_cli.bin", hex = "metro_blob_cli.hex";
  Run r = Calibrate("blob " + kGolden +
                    "calibration_sensor2.json --sensor 2 --device-id 9abcdef012345678 --seq 3 -o " +
                    bin + " --hex " + hex);
  REQUIRE(r.exit_code == 0);
  CHECK(Bytes(bin) == Bytes(kGolden + "tag_sensor2.bin"));
  CHECK(Bytes(hex) == Bytes(kGolden + "tag_sensor2.hex"));
  CHECK(r.err.find("program with: nrfjprog -f NRF51 --program " + hex +
                   " --sectorerase --verify --reset") != std::string::npos);

  Run i = Calibrate("inspect " + hex);
  CHECK(i.exit_code == 0);
  CHECK(i.out.find("slot A @0x3B000: METRO_FW_OK - valid [active]") != std::string::npos);
  CHECK(i.out.find("slot B @0x3B400: METRO_FW_E_MAGIC") != std::string::npos);
  Run j = Calibrate("inspect --json " + bin);
  CHECK(j.exit_code == 0);
  CHECK(j.out.find("\"active_slot\": \"file\"") != std::string::npos);
  Run foreign = Calibrate("inspect " + bin + " --device-id 0000000000000001");
  CHECK(foreign.exit_code == 1);
  CHECK(foreign.out.find("METRO_FW_E_FOREIGN - device id belongs to another tag") !=
        std::string::npos);

  // Another slot address moves both pages.
  Run moved = Calibrate("blob " + kGolden +
                        "calibration_sensor2.json --sensor 2 --device-id 9ABCDEF012345678 -o " +
                        bin + " --hex " + hex + " --slot-address 0x3A000");
  REQUIRE(moved.exit_code == 0);
  Result<std::string> text = ReadFile(hex);
  REQUIRE(text.ok());
  Result<std::vector<HexSegment>> segs = ReadIntelHex(text.value(), hex);
  REQUIRE(segs.ok());
  REQUIRE(segs.value().size() == 2);
  CHECK(segs.value()[0].address == 0x3A000u);
  CHECK(segs.value()[1].address == 0x3A400u);
  CHECK(Calibrate("inspect " + hex).exit_code == 1);  // nothing at the default slots
  CHECK(Calibrate("inspect " + hex + " --slot-address 0x3A000").exit_code == 0);
  std::remove(bin.c_str());
  std::remove(hex.c_str());
}

TEST_CASE("calibrate blob and inspect refuse bad input with the reason", "[blob][apps]") {
  const std::string cal = kGolden + "calibration_sensor2.json";
  Run r = Calibrate("blob " + cal + " --sensor 2 --device-id 12345 -o x.bin");
  CHECK(r.exit_code == 2);
  CHECK(r.err ==
        "error: --device-id: device id '12345': expected 16 hex digits, DEVICEID[1] then "
        "DEVICEID[0] (e.g. 9ABCDEF012345678), or the two words `nrfjprog --memrd 0x10000060 "
        "--n 8` prints, DEVICEID[0] then DEVICEID[1] (e.g. 12345678 9ABCDEF0), with or without "
        "0x\n");
  r = Calibrate("blob " + cal + " --sensor 7 --device-id 9ABCDEF012345678 -o x.bin");
  CHECK(r.exit_code == 2);
  // At calibration.json's "tags" (line 11, after `  "tags": `).
  CHECK(r.err == "error: " + cal +
                     ":11:11: calibration has no sensor 7 (it has: 2); expected "
                     "--sensor 2\n");
  r = Calibrate("blob " + cal +
                " --sensor 2 --device-id 9ABCDEF012345678 -o x.bin --hex x.hex "
                "--slot-address 0x3B001");
  CHECK(r.exit_code == 2);
  CHECK(r.err ==
        "error: --slot-address '0x3B001': expected a multiple of 0x400 below 0x3F800 (slot B is "
        "the next page)\n");
  r = Calibrate("blob " + cal + " --sensor 2 --device-id 9ABCDEF012345678 -o " + cal);
  CHECK(r.exit_code == 2);
  CHECK(r.err == "error: -o " + cal + " is the input file: refusing to overwrite it (CALIBRATION " +
                     cal + "); name another output file\n");
  r = Calibrate("blob " + cal + " --sensor 2 --device-id 9ABCDEF012345678 --seq 0 -o x.bin");
  CHECK(r.exit_code == 2);
  CHECK(r.err.find("--seq") != std::string::npos);
  const std::string hex_bad = "metro_blob_cli_bad.hex";
  {
    std::ofstream out(hex_bad);
    out << ":020000040003F7\n:10B000004943414C010000001C02200003000000E6\n:00000001FF\n";
  }
  r = Calibrate("inspect " + hex_bad);
  CHECK(r.exit_code == 2);
  CHECK(r.err.find(hex_bad + ":2:") != std::string::npos);
  CHECK(r.err.find("checksum") != std::string::npos);
  std::remove(hex_bad.c_str());
  CHECK_FALSE(std::ifstream("x.bin").good());
}
#endif  // METRO_CALIBRATE_EXE

}  // namespace metro::blob
