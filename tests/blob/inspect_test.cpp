#include "metro/blob/inspect.hpp"

#include <catch2/catch.hpp>
#include <filesystem>

#include "blob/blob_test_support.hpp"
#include "metro/blob/intel_hex.hpp"
#include "metro/core/file.hpp"

using namespace metro::blob;

namespace {

std::string WriteTemp(const std::string& name, const std::string& contents) {
  const auto dir = std::filesystem::temp_directory_path() / "metro_inspect_test";
  std::filesystem::create_directories(dir);
  const auto path = (dir / name).string();
  REQUIRE(metro::WriteFileAtomically(path, contents).ok());
  return path;
}

std::string Bytes(const std::vector<uint8_t>& b) { return std::string(b.begin(), b.end()); }

}  // namespace

TEST_CASE("Inspect of a valid .bin reports the blob and its sensors", "[blob][inspect]") {
  auto blob = WriteBlob(testing::Contents());
  REQUIRE(blob.ok());
  auto r = InspectFile(WriteTemp("tag.bin", Bytes(blob.value())), InspectOptions{});
  REQUIRE(r.ok());
  const auto& report = r.value();
  CHECK(report.format == "bin");
  CHECK(report.ok());
  REQUIRE(report.slots.size() == 1u);
  CHECK(report.slots[0].code_name == "METRO_FW_OK");
  REQUIRE(report.slots[0].sensors.size() == 2u);
  CHECK(report.slots[0].sensors[0].status_name == "OK");
  const auto text = FormatInspect(report);
  CHECK_THAT(text, Catch::Contains("seq 17  device 9ABCDEF012345678"));
  CHECK_THAT(text, Catch::Contains("result: valid"));
  const auto j = InspectToJson(report);
  CHECK(j["ok"] == true);
  CHECK(j["active_slot"] == "file");
  CHECK(j["slots"][0]["seq"] == 17);
  CHECK(j["slots"][0]["accel"]["status"] == "OK");
  CHECK(j["slots"][0]["accel"]["b0_lsb"][0] == 150.25);
  CHECK(j["slots"][0]["meta"]["reference_id"] == "LAB-REF-0042");
}

TEST_CASE("Inspect of a corrupt .bin names the firmware's reason", "[blob][inspect]") {
  auto blob = WriteBlob(testing::Contents());
  REQUIRE(blob.ok());
  auto bytes = blob.value();
  bytes[0x100] ^= 0x10;
  auto r = InspectFile(WriteTemp("bad.bin", Bytes(bytes)), InspectOptions{});
  REQUIRE(r.ok());
  CHECK(!r.value().ok());
  CHECK(r.value().slots[0].code_name == "METRO_FW_E_CRC");
  CHECK_THAT(FormatInspect(r.value()), Catch::Contains("NO VALID CALIBRATION"));
  CHECK(InspectToJson(r.value())["active_slot"].is_null());
}

TEST_CASE("Inspect with the tag's device id detects a foreign blob", "[blob][inspect]") {
  auto blob = WriteBlob(testing::Contents());
  REQUIRE(blob.ok());
  InspectOptions options;
  options.device_id = 0x1122334455667788ull;
  auto r = InspectFile(WriteTemp("foreign.bin", Bytes(blob.value())), options);
  REQUIRE(r.ok());
  CHECK(r.value().slots[0].code_name == "METRO_FW_E_FOREIGN");
}

TEST_CASE("Inspect of the factory .hex finds slot A active and the tombstone in B",
          "[blob][inspect]") {
  auto blob = WriteBlob(testing::Contents());
  REQUIRE(blob.ok());
  auto hex = WriteIntelHex(FactoryImage(blob.value(), kSlotAAddress, kSlotBAddress));
  REQUIRE(hex.ok());
  auto r = InspectFile(WriteTemp("tag.hex", hex.value()), InspectOptions{});
  REQUIRE(r.ok());
  const auto& report = r.value();
  CHECK(report.format == "hex");
  REQUIRE(report.slots.size() == 2u);
  CHECK(report.active == 0);
  CHECK(report.slots[0].code_name == "METRO_FW_OK");
  CHECK(report.slots[1].code_name == "METRO_FW_E_MAGIC");
  CHECK_THAT(FormatInspect(report),
             Catch::Contains("slot A @0x3B000: METRO_FW_OK - valid [active]"));
}

TEST_CASE("Inspect of a .hex picks the larger seq", "[blob][inspect]") {
  auto a = WriteBlob(testing::Contents(4));
  auto b = WriteBlob(testing::Contents(5));
  REQUIRE(a.ok());
  REQUIRE(b.ok());
  auto hex =
      WriteIntelHex({HexSegment{kSlotAAddress, a.value()}, HexSegment{kSlotBAddress, b.value()}});
  REQUIRE(hex.ok());
  auto r = InspectFile(WriteTemp("two.hex", hex.value()), InspectOptions{});
  REQUIRE(r.ok());
  CHECK(r.value().active == 1);
}

TEST_CASE("Inspect reports a sensor the firmware would not use", "[blob][inspect]") {
  auto blob = WriteBlob(testing::Contents());
  REQUIRE(blob.ok());
  auto bytes = blob.value();
  // Gyro t_valid_max_c (body offset 160) := +Inf, CRC recomputed.
  const size_t off = 0x168 + 160;
  bytes[off] = 0x00;
  bytes[off + 1] = 0x00;
  bytes[off + 2] = 0x80;
  bytes[off + 3] = 0x7F;
  const uint32_t crc = Crc32(bytes.data(), 0x218);
  for (int i = 0; i < 4; ++i) bytes[0x218 + i] = static_cast<uint8_t>(crc >> (8 * i));
  auto r = InspectFile(WriteTemp("inf.bin", Bytes(bytes)), InspectOptions{});
  REQUIRE(r.ok());
  CHECK(r.value().ok());
  CHECK(r.value().slots[0].sensors[0].status_name == "OK");
  CHECK(r.value().slots[0].sensors[1].status_name == "NONFINITE");
}

TEST_CASE("Inspect refuses unreadable files and bad HEX and bad options", "[blob][inspect]") {
  auto missing = InspectFile("/nonexistent/tag.bin", InspectOptions{});
  REQUIRE(!missing.ok());
  CHECK_THAT(missing.error().ToString(), Catch::Contains("/nonexistent/tag.bin"));
  auto bad = InspectFile(WriteTemp("bad.hex", ":00000001FE\n"), InspectOptions{});
  REQUIRE(!bad.ok());
  CHECK(bad.error().line == 1);
  CHECK_THAT(bad.error().message, Catch::Contains("checksum"));
  InspectOptions options;
  options.slot_b_address = 0x3B100;
  auto opt = InspectFile(WriteTemp("x.bin", "x"), options);
  REQUIRE(!opt.ok());
  CHECK_THAT(opt.error().message, Catch::Contains("multiples of the 1024-byte page"));
  options.slot_b_address = options.slot_a_address;
  std::string why;
  CHECK(!options.IsValid(&why));
  CHECK(why == "slot A and slot B must be different pages");
}
