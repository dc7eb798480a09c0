// The tags file (io/tag_registry.hpp): names as before, and per tag the device ID and the IMU
// profile; each class of bad input refused with the file and the tag.
#include "metro/io/tag_registry.hpp"

#include <catch2/catch.hpp>
#include <string>

#include "support/temp_file.hpp"
#include "support/text_position.hpp"

namespace metro {

TEST_CASE("Tags file: names, device IDs in both orders and profiles", "[io]") {
  testing::TempFile file(
      R"({"2": {"name": "Chest", "device_id": "12345678 9ABCDEF0", "profile": "generic"},
          "3": "Left Arm",
          "16": {"name": "Spare", "device_id": "0x0011223344556677"}})",
      ".json");
  Result<TagRegistry> r = TagRegistry::Load(file.path());
  REQUIRE(r.ok());
  const TagRegistry& t = r.value();
  CHECK(t.Name(1) == "Forehead");  // thesis Table 5.2, kept
  CHECK(t.Name(2) == "Chest");
  CHECK(t.Name(3) == "Left Arm");
  CHECK(t.Name(16) == "Spare");
  CHECK(t.Name(40) == "tag 40");
  REQUIRE(t.Find(2) != nullptr);
  // nrfjprog's words: DEVICEID[0] = 0x12345678, DEVICEID[1] = 0x9ABCDEF0.
  CHECK(t.Find(2)->device_id == 0x9ABCDEF012345678ull);
  CHECK(t.Find(2)->profile == "generic");
  CHECK_FALSE(t.Find(3)->device_id.has_value());
  CHECK(t.Find(3)->profile.empty());
  CHECK(t.Find(16)->device_id == 0x0011223344556677ull);
  CHECK(t.SensorOfDevice(0x9ABCDEF012345678ull) == 2);
  CHECK_FALSE(t.SensorOfDevice(1).has_value());
  CHECK(t.Entries().size() == 16);
  // Where each device_id is written (for errors that name it beside calibration.json's): tag 2's
  // value after `{"2": {"name": "Chest", "device_id": ` (37 characters), tag 16's on line 3 after
  // 10 spaces and `"16": {"name": "Spare", "device_id": ` (37).
  CHECK(t.Find(2)->DeviceIdPosition() == file.path() + ":1:38");
  CHECK(t.Find(16)->DeviceIdPosition() == file.path() + ":3:48");
  CHECK(t.Find(3)->DeviceIdPosition().empty());
}

TEST_CASE("Tags file: the default body-part names name only the thesis tags' own files",
          "[io][issue39]") {
  testing::TempFile file(R"({"1": "ADIS16448"})", ".json");
  Result<TagRegistry> r = TagRegistry::Load(file.path());
  REQUIRE(r.ok());
  const TagRegistry& t = r.value();
  // A receiver capture and session.csv: thesis Table 5.2 (2 Chest), as Name(sensor).
  CHECK(t.Name(2, SessionFormat::kReceiver) == "Chest");
  CHECK(t.Name(2, SessionFormat::kCsv) == "Chest");
  CHECK(t.Name(40, SessionFormat::kCsv) == "tag 40");
  // Another tool's file: the file's name where it gives one, "sensor N" otherwise.
  for (SessionFormat f :
       {SessionFormat::kEuroc, SessionFormat::kPhyphox, SessionFormat::kSensorLogger,
        SessionFormat::kRaw, SessionFormat::kImuTk}) {
    INFO(SessionFormatName(f));
    CHECK_FALSE(IsThesisTagFormat(f));
    CHECK(t.Name(1, f) == "ADIS16448");
    CHECK(t.Name(2, f) == "sensor 2");
    CHECK(t.Name(40, f) == "sensor 40");
    CHECK(TagRegistry::Default().Name(1, f) == "sensor 1");
  }
}

TEST_CASE("Tags file: bad input names the file, line and column, the tag and the shape",
          "[io][issue37]") {
  // issue #37: each error was "tags.json: ..." without line and column. `at` is the text the
  // error points at (its first occurrence), located here independently of the reader.
  struct Case {
    const char* json;
    const char* at;
    const char* message;
  };
  const Case cases[] = {
      {R"([1])", "[1]",
       R"(expected a JSON object {"1": "Forehead", "2": {"name": "Chest", "device_id": "12345678 9ABCDEF0", "profile": "mpu6050"}, ...})"},
      {R"({"0": "x"})", R"("x")",
       R"(key '0': expected a tag number 1..255 as the key, e.g. "2": "Chest")"},
      {R"({"2": 5})", "5",
       R"(tag 2: expected a name string or an object with name, device_id, profile: "2": "Chest" or "2": {"name": "Chest", "device_id": "12345678 9ABCDEF0"})"},
      {R"({"2": {"device_id": "9ABCDEF012345678"}})", R"({"device_id")",
       R"(tag 2: expected a name: "2": {"name": "Chest", ...})"},
      {R"({"2": {"name": "C", "serial": "x"}})", R"("x")",
       R"(tag 2: unknown key 'serial'; expected name, device_id, profile: "2": {"name": "Chest", "device_id": "12345678 9ABCDEF0", "profile": "mpu6050"})"},
      {R"({"2": {"name": "C", "device_id": 5}})", "5",
       R"(tag 2: device_id: expected a string, e.g. "device_id": "12345678 9ABCDEF0")"},
      {R"({"2": {"name": "C", "device_id": "123"}})", R"("123")",
       "tag 2: device_id: device id '123': expected 16 hex digits, DEVICEID[1] then DEVICEID[0] "
       "(e.g. 9ABCDEF012345678), or the two words `nrfjprog --memrd 0x10000060 --n 8` prints, "
       "DEVICEID[0] then DEVICEID[1] (e.g. 12345678 9ABCDEF0), with or without 0x"},
      {R"({"2": {"name": "C", "profile": "bmi160"}})", R"("bmi160")",
       "tag 2: profile 'bmi160': expected mpu6050 or generic"},
      {R"({"2": {"name": "C", "device_id": "9ABCDEF012345678"},
           "3": {"name": "D", "device_id": "12345678 9abcdef0"}})",
       R"("12345678 9abcdef0")",
       "tag 3: device_id 9ABCDEF012345678 is tag 2's already; expected one device per tag"},
  };
  for (const Case& c : cases) {
    testing::TempFile file(c.json, ".json");
    Result<TagRegistry> r = TagRegistry::Load(file.path());
    INFO(c.json);
    REQUIRE_FALSE(r.ok());
    const std::string text = c.json;
    const size_t at = text.find(c.at);
    REQUIRE(at != std::string::npos);
    CHECK(r.error().ToString() ==
          file.path() + ":" + testing::LineColumn(text, at) + ": " + c.message);
  }
}

}  // namespace metro
