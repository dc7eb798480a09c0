// Issue #37 point 6, "errors at file:line:column": the checks `calibrate blob`, `push` and
// `apply` make after calibration.json (and the tags file, and the session) were read point at
// the value they are about, with what was expected, exit 2 and nothing written. Each input is
// the golden calibration.json with one value edited by hand (or a hand-written tags file or
// session); the expected line:column is counted by hand from the edited text and checked again
// with testing::LineColumn, which shares no code with the library's JSON walker.
#include <catch2/catch.hpp>
#include <filesystem>
#include <string>

#include "metro/core/file.hpp"
#include "support/run_program.hpp"
#include "support/temp_file.hpp"
#include "support/text_position.hpp"

namespace metro {
namespace {

using Run = testing::ProgramRun;
using Dir = testing::WorkDir;
using testing::Put;

const std::string kGoldenCal =
    std::string(METRO_SOURCE_DIR) + "/datasets/golden/calibration_sensor2.json";

Run Calibrate(const std::string& args) { return testing::RunProgram(METRO_CALIBRATE_EXE, args); }

// The golden calibration.json (tag 2: LSB input, a temperature term, no device ID) with the first
// `old` replaced by `replacement`.
std::string GoldenWith(const std::string& old, const std::string& replacement) {
  Result<std::string> text = ReadFile(kGoldenCal);
  REQUIRE(text.ok());
  std::string s = text.value();
  const size_t at = s.find(old);
  REQUIRE(at != std::string::npos);
  return s.replace(at, old.size(), replacement);
}

// line:column of the first byte after the first `marker` in `text`.
std::string After(const std::string& text, const std::string& marker) {
  const size_t at = text.find(marker);
  REQUIRE(at != std::string::npos);
  return testing::LineColumn(text, at + marker.size());
}

bool Exists(const std::string& path) { return std::filesystem::exists(path); }

}  // namespace

TEST_CASE("calibrate blob and push point at the calibration.json value a check refuses",
          "[apps][blob][calibration][issue37]") {
  Dir d;
  const std::string cal = d / "c.json";
  const std::string out = d / "tag.bin";
  const std::string port = d / "no-such-tty";
  const std::string id = " --device-id 9ABCDEF012345678";

  SECTION("constants marked model_rejected: at their model_check's model_rejected") {
    // The accelerometer's object (line 13) gets a model_check on line 366, the line of its
    // input_unit: 8 spaces, then 53 characters up to the value, which is at column 62.
    const std::string text = GoldenWith(
        "        \"input_unit\": \"LSB\",",
        "        \"model_check\": {\"comparisons\": [], \"model_rejected\": true, \"reason\": "
        "\"hand-written\", \"selection\": \"given\", \"status\": \"rejected\"},\n"
        "        \"input_unit\": \"LSB\",");
    Put(cal, text);
    REQUIRE(After(text, "\"model_rejected\": ") == "366:62");
    Run r = Calibrate("blob " + cal + " --sensor 2" + id + " -o " + out);
    CHECK(r.exit_code == 2);
    CHECK(r.err == "error: " + cal +
                       ":366:62: sensor 2 accel: the constants are marked model_rejected: "
                       "hand-written; expected \"model_rejected\": false (constants of a model the "
                       "data accept: refit, e.g. calibrate fit --model auto), or "
                       "--accept-rejected-model to use these anyway\n");
    CHECK_FALSE(Exists(out));
    r = Calibrate("push --port " + port + " " + cal + " --sensor 2" + id);
    CHECK(r.exit_code == 2);
    CHECK_THAT(r.err, Catch::StartsWith("error: " + cal +
                                        ":366:62: sensor 2 accel: the "
                                        "constants are marked model_rejected: hand-written; "
                                        "expected \"model_rejected\": false"));
    CHECK_THAT(r.err, Catch::EndsWith("(nothing sent; " + port + " not opened)\n"));
    CHECK_FALSE(Exists(port));
  }

  SECTION("a date_utc the blob cannot carry: at the value (line 2, after 14 characters)") {
    const std::string text = GoldenWith("\"date_utc\": \"2026-11-21T09:35:57Z\"",
                                        "\"date_utc\": \"2107-01-01T00:00:00Z\"");
    Put(cal, text);
    REQUIRE(After(text, "\"date_utc\": ") == "2:15");
    const Run r =
        Calibrate("blob " + cal + " --sensor 2" + id + " -o " + out + " --hex " + d / "tag.hex");
    CHECK(r.exit_code == 2);
    CHECK(r.err == "error: " + cal +
                       ":2:15: 'date_utc' '2107-01-01T00:00:00Z' is outside 1970..2106 (u32 "
                       "seconds); expected a time from 1970-01-01T00:00:00Z to "
                       "2106-02-07T06:28:15Z, e.g. 2024-05-01T12:00:00Z\n");
    CHECK_FALSE(Exists(out));
    CHECK_FALSE(Exists(d / "tag.hex"));
  }

  SECTION("a constant out of range for the blob: at the element (bias_per_c[1], line 703)") {
    // The accelerometer's temperature.bias_per_c opens on line 701; element [1] is on line 703
    // after 12 spaces.
    const std::string text = GoldenWith("            1.6176133738518415,", "            120.5,");
    Put(cal, text);
    REQUIRE(After(text, "\"bias_per_c\": [\n            3.5561378779786703,\n            ") ==
            "703:13");
    Run r = Calibrate("blob " + cal + " --sensor 2" + id + " -o " + out);
    CHECK(r.exit_code == 2);
    CHECK_THAT(r.err, Catch::StartsWith("error: " + cal +
                                        ":703:13: sensor 2 accel: the temperature coefficient "
                                        "b1_y = 120.5 LSB/degC"));
    CHECK_THAT(r.err, Catch::Contains("expected |b1| <= 80 LSB/degC"));
    CHECK_FALSE(Exists(out));
    r = Calibrate("push --port " + port + " " + cal + " --sensor 2" + id);
    CHECK(r.exit_code == 2);
    CHECK_THAT(r.err, Catch::StartsWith("error: " + cal +
                                        ":703:13: sensor 2 accel: the "
                                        "temperature coefficient b1_y = 120.5 LSB/degC"));
  }

  SECTION("a sensor calibration.json lacks: at its tags array, with the sensors it has") {
    const std::string text = GoldenWith("", "");
    Put(cal, text);
    REQUIRE(After(text, "  \"tags\": ") == "11:11");
    Run r = Calibrate("blob " + cal + " --sensor 7" + id + " -o " + out);
    CHECK(r.exit_code == 2);
    CHECK(r.err == "error: " + cal +
                       ":11:11: calibration has no sensor 7 (it has: 2); expected --sensor 2\n");
    CHECK_FALSE(Exists(out));
    r = Calibrate("push --port " + port + " " + cal + " --sensor 7" + id);
    CHECK(r.exit_code == 2);
    CHECK(r.err == "error: " + cal +
                       ":11:11: calibration has no sensor 7 (it has: 2); expected --sensor 2 "
                       "(nothing sent; " +
                       port + " not opened)\n");
  }
}

TEST_CASE("A device ID calibration.json and the tags file disagree on: both positions",
          "[apps][tags][calibration][issue37]") {
  Dir d;
  // Tag 2's object gets a device_id on line 2286 (the line of its "sensor"): 6 spaces and
  // `"device_id": ` before the value, at column 20.
  const std::string cal = d / "c.json";
  const std::string text = GoldenWith("      \"sensor\": 2,",
                                      "      \"device_id\": \"0011223344556677\",\n"
                                      "      \"sensor\": 2,");
  Put(cal, text);
  REQUIRE(After(text, "\"device_id\": ") == "2286:20");

  SECTION("calibrate blob: the tags file gives that device to another tag") {
    // `{"5": {"name": "Left Leg", "device_id": ` is 40 characters: the value at 1:41.
    const std::string tags = d / "t.json";
    const std::string tags_text =
        R"({"5": {"name": "Left Leg", "device_id": "0x0011223344556677"}})";
    Put(tags, tags_text);
    REQUIRE(After(tags_text, "\"device_id\": ") == "1:41");
    const std::string out = d / "tag.bin";
    const Run r = Calibrate("blob " + cal + " --sensor 2 --tags " + tags + " -o " + out);
    CHECK(r.exit_code == 2);
    CHECK(r.err == "error: " + cal +
                       ":2286:20: device 0011223344556677 is sensor 5's in the tags file (" + tags +
                       ":1:41), not sensor 2's; expected one device per tag: sensor 2's own "
                       "device, or the calibration of sensor 5\n");
    CHECK_FALSE(Exists(out));
  }

  SECTION("calibrate blob and push: --device-id or the tags file names another device") {
    // One tag's constants are never written or pushed for another chip (as apply refuses).
    const std::string out = d / "tag.bin";
    const std::string port = d / "no-such-tty";
    const std::string expected_tail =
        " gives device 1111111111111111: this calibration was made for another tag; expected "
        "--device-id 0011223344556677 (the calibrated tag), or a calibration of device "
        "1111111111111111\n";
    const Run flag =
        Calibrate("blob " + cal + " --sensor 2 --device-id 1111111111111111 -o " + out);
    CHECK(flag.exit_code == 2);
    CHECK(flag.err == "error: " + cal +
                          ":2286:20: sensor 2 was calibrated on device 0011223344556677, but "
                          "--device-id" +
                          expected_tail);
    CHECK_FALSE(Exists(out));
    const std::string tags = d / "t.json";
    const std::string tags_text =
        "{\n  \"2\": {\"name\": \"Chest\",\n        \"device_id\": \"0x1111111111111111\"}\n}\n";
    Put(tags, tags_text);
    const Run file = Calibrate("push " + cal + " --sensor 2 --tags " + tags + " --port " + port);
    CHECK(file.exit_code == 2);
    CHECK(file.err == "error: " + cal +
                          ":2286:20: sensor 2 was calibrated on device 0011223344556677, but " +
                          tags + ":3:22" + expected_tail);
    // The calibrated device itself is accepted.
    const Run same =
        Calibrate("blob " + cal + " --sensor 2 --device-id 0011223344556677 -o " + out);
    CHECK(same.exit_code == 0);
    CHECK(Exists(out));
  }

  SECTION("calibrate apply: the tags file gives the sensor another device") {
    // The device_id on line 3 after 8 spaces and `"device_id": `: column 22.
    const std::string tags = d / "t.json";
    const std::string tags_text =
        "{\n  \"2\": {\"name\": \"Chest\",\n        \"device_id\": \"0x1111111111111111\"}\n}\n";
    Put(tags, tags_text);
    REQUIRE(After(tags_text, "\"device_id\": ") == "3:22");
    const std::string session = d / "s.csv";
    Put(session,
        "t_s,sensor,ax_lsb,ay_lsb,az_lsb,gx_lsb,gy_lsb,gz_lsb,temp_c\n"
        "0.00,2,0,0,16384,0,0,0,25\n0.01,2,0,0,16384,0,0,0,25\n");
    const std::string out = d / "applied.csv";
    const Run r = Calibrate("apply " + cal + " " + session + " -o " + out + " --tags " + tags);
    CHECK(r.exit_code == 2);
    CHECK(r.err == "error: " + cal +
                       ":2286:20: sensor 2 is device 0011223344556677 in calibration.json but "
                       "device 1111111111111111 in " +
                       tags +
                       ":3:22: this calibration was made for another tag; expected the "
                       "calibration of device 1111111111111111 (or a tags file that gives sensor "
                       "2 device 0011223344556677)\n");
    CHECK_FALSE(Exists(out));
  }
}

TEST_CASE("calibrate apply points at the session's header cell a calibration cannot use",
          "[apps][calibration][issue37]") {
  // The golden calibration takes raw counts (_lsb) and has a temperature term (temp_c).
  Dir d;
  const std::string out = d / "applied.csv";
  const std::string session = d / "s.csv";

  SECTION("the accelerometer in g where the calibration takes LSB: at ax_g, field 3") {
    Put(session,
        "t_s,sensor,ax_g,ay_g,az_g,gx_lsb,gy_lsb,gz_lsb,temp_c\n"
        "0.00,2,0,0,1,0,0,0,25\n0.01,2,0,0,1,0,0,0,25\n");
    const Run r = Calibrate("apply " + kGoldenCal + " " + session + " -o " + out);
    CHECK(r.exit_code == 2);
    CHECK(r.err == "error: " + session +
                       ":1:3: sensor 2: the accel calibration takes LSB input (_lsb columns) but "
                       "the session has no ax_lsb column; it has ax_g (unit g) instead: expected "
                       "the columns the calibration takes, ax_lsb, ay_lsb, az_lsb (a session in "
                       "the unit of the calibration's records)\n");
    CHECK_FALSE(Exists(out));
  }

  SECTION("no temp_c for a temperature term: at the header line (line 2 after a comment)") {
    Put(session,
        "# bench log, written by hand\n"
        "t_s,sensor,ax_lsb,ay_lsb,az_lsb,gx_lsb,gy_lsb,gz_lsb\n"
        "0.00,2,0,0,16384,0,0,0\n0.01,2,0,0,16384,0,0,0\n");
    const Run r = Calibrate("apply " + kGoldenCal + " " + session + " -o " + out);
    CHECK(r.exit_code == 2);
    CHECK(r.err == "error: " + session +
                       ":2:1: sensor 2: the accel calibration has a temperature term but the "
                       "session has no temp_c column; expected temp_c (degC) in the header, as "
                       "in the calibration's records\n");
    CHECK_FALSE(Exists(out));
  }
}

}  // namespace metro
