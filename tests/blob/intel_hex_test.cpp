#include "metro/blob/intel_hex.hpp"

#include <catch2/catch.hpp>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "blob/blob_test_support.hpp"
#include "metro/blob/blob.hpp"
#include "metro/core/file.hpp"

using namespace metro::blob;

namespace {

std::vector<std::string> Lines(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) out.push_back(line);
  return out;
}

bool HaveSrecCat() { return std::system("srec_cat -version > /dev/null 2>&1") == 0; }

std::filesystem::path TempDir(const std::string& name) {
  auto dir = std::filesystem::temp_directory_path() / ("metro_blob_" + name);
  std::filesystem::create_directories(dir);
  return dir;
}

}  // namespace

TEST_CASE("HEX records: 04 first and 16-byte 00 records with checksums and 01 last",
          "[blob][hex]") {
  // The published example record ":10010000214601360121470136007EFE09D2190140" (checksum 0x40).
  std::vector<uint8_t> example = {0x21, 0x46, 0x01, 0x36, 0x01, 0x21, 0x47, 0x01,
                                  0x36, 0x00, 0x7E, 0xFE, 0x09, 0xD2, 0x19, 0x01};
  auto hex = WriteIntelHex({HexSegment{0x0100, example}});
  REQUIRE(hex.ok());
  CHECK(Lines(hex.value()) ==
        std::vector<std::string>{":020000040000FA", ":10010000214601360121470136007EFE09D2190140",
                                 ":00000001FF"});
}

TEST_CASE("The factory image holds the blob at slot A and a tombstone at slot B", "[blob][hex]") {
  auto blob = WriteBlob(testing::Contents());
  REQUIRE(blob.ok());
  auto hex = WriteIntelHex(FactoryImage(blob.value(), kSlotAAddress, kSlotBAddress));
  REQUIRE(hex.ok());
  const auto lines = Lines(hex.value());
  // 540 bytes = 33 full records + one of 12; one 04 record (0x0003); tombstone; EOF.
  REQUIRE(lines.size() == 1u + 34u + 1u + 1u);
  CHECK(lines[0] == ":020000040003F7");
  CHECK(lines[1].substr(0, 9) == ":10B00000");
  CHECK(lines[34].substr(0, 9) == ":0CB21000");
  CHECK(lines[35] == ":04B4000000000000" + std::string("48"));
  CHECK(lines.back() == ":00000001FF");
  for (const auto& l : lines) {
    const auto type = l.substr(7, 2);
    CHECK((type == "00" || type == "01" || type == "04"));
  }
  auto back = ReadIntelHex(hex.value(), "tag.hex");
  REQUIRE(back.ok());
  REQUIRE(back.value().size() == 2u);
  CHECK(back.value()[0].address == kSlotAAddress);
  CHECK(back.value()[0].bytes == blob.value());
  CHECK(back.value()[1].address == kSlotBAddress);
  CHECK(back.value()[1].bytes == std::vector<uint8_t>{0, 0, 0, 0});
}

TEST_CASE("A 64 KiB crossing emits a new 04 record", "[blob][hex]") {
  std::vector<uint8_t> bytes(40);
  for (size_t i = 0; i < bytes.size(); ++i) bytes[i] = static_cast<uint8_t>(i);
  auto hex = WriteIntelHex({HexSegment{0x1FFF8, bytes}});
  REQUIRE(hex.ok());
  const auto lines = Lines(hex.value());
  CHECK(lines[0] == ":020000040001F9");
  CHECK(lines[1].substr(0, 9) == ":08FFF800");
  CHECK(lines[2] == ":020000040002F8");
  CHECK(lines[3].substr(0, 9) == ":10000000");
  auto back = ReadIntelHex(hex.value(), "x.hex");
  REQUIRE(back.ok());
  CHECK(back.value()[0].address == 0x1FFF8u);
  CHECK(back.value()[0].bytes == bytes);
}

TEST_CASE("Overlapping segments are refused by the writer", "[blob][hex]") {
  auto r = WriteIntelHex({HexSegment{0x100, {1, 2, 3, 4}}, HexSegment{0x102, {5}}});
  REQUIRE(!r.ok());
  CHECK_THAT(r.error().message, Catch::Contains("overlaps or precedes"));
}

TEST_CASE("Every class of bad HEX input is refused with its line and column", "[blob][hex]") {
  struct Case {
    std::string text;
    int64_t line;
    std::string message;
  };
  const std::vector<Case> cases = {
      {"10010000214601360121470136007EFE09D2190140\n:00000001FF\n", 1, "expected ':'"},
      {":10010000214601360121470136007EFE09D2190141\n:00000001FF\n", 1,
       "checksum 0x41 is wrong, expected 0x40"},
      {":0201000021G6FF\n:00000001FF\n", 1, "expected a hex digit"},
      {":0401000021460136\n:00000001FF\n", 1, "length field says 4 data bytes"},
      {":0101\n", 1, "even number"},
      {":020000021000EC\n:00000001FF\n", 1, "record type 02 is not supported"},
      {":0400000500000000F7\n:00000001FF\n", 1, "record type 05 is not supported"},
      {":02010000214696\n", 1, "missing EOF record"},
      {":00000001FF\n:02010000214696\n", 2, "record after the EOF record"},
      {":02010000214696\n:02010000214696\n:00000001FF\n", 2, "written twice"},
  };
  for (const auto& c : cases) {
    auto r = ReadIntelHex(c.text, "bad.hex");
    INFO(c.text);
    REQUIRE(!r.ok());
    CHECK(r.error().file == "bad.hex");
    CHECK(r.error().line == c.line);
    CHECK_THAT(r.error().message, Catch::Contains(c.message));
  }
}

TEST_CASE("The factory HEX round-trips through srec_cat and its CRC-32 matches", "[blob][hex]") {
  if (!HaveSrecCat()) {
    WARN("srec_cat (Debian package srecord) is not installed: HEX round trip skipped");
    return;
  }
  auto blob = WriteBlob(testing::Contents());
  REQUIRE(blob.ok());
  auto hex = WriteIntelHex(FactoryImage(blob.value(), kSlotAAddress, kSlotBAddress));
  REQUIRE(hex.ok());
  const auto dir = TempDir("srec");
  const auto hex_path = (dir / "tag.hex").string();
  REQUIRE(metro::WriteFileAtomically(hex_path, hex.value()).ok());

  // srec_cat extracts slot A as binary: the same 540 bytes.
  const auto bin_path = (dir / "slot_a.bin").string();
  const std::string extract = "srec_cat " + hex_path + " -intel -crop 0x3B000 0x3B21C -offset " +
                              "-0x3B000 -o " + bin_path + " -binary";
  REQUIRE(std::system(extract.c_str()) == 0);
  auto bin = metro::ReadFile(bin_path);
  REQUIRE(bin.ok());
  CHECK(std::vector<uint8_t>(bin.value().begin(), bin.value().end()) == blob.value());

  // srec_cat's own CRC-32 over [0, 0x218), little-endian at 0x218, equals the blob's CRC word.
  const auto crc_path = (dir / "crc.bin").string();
  const std::string crc = "srec_cat " + hex_path + " -intel -crop 0x3B000 0x3B218 -offset " +
                          "-0x3B000 -crc32-l-e 0x218 -o " + crc_path + " -binary";
  REQUIRE(std::system(crc.c_str()) == 0);
  auto crc_bin = metro::ReadFile(crc_path);
  REQUIRE(crc_bin.ok());
  REQUIRE(crc_bin.value().size() == 540u);
  CHECK(crc_bin.value().substr(0x218) ==
        std::string(blob.value().begin() + 0x218, blob.value().end()));

  // srec_cat rewrites the HEX its own way; our reader gets the same bytes back.
  const auto hex2_path = (dir / "again.hex").string();
  const std::string rewrite = "srec_cat " + hex_path + " -intel -o " + hex2_path +
                              " -intel -output_block_size=32 -disable=exec_start_address";
  REQUIRE(std::system(rewrite.c_str()) == 0);
  auto text2 = metro::ReadFile(hex2_path);
  REQUIRE(text2.ok());
  auto back = ReadIntelHex(text2.value(), hex2_path);
  REQUIRE(back.ok());
  REQUIRE(back.value().size() == 2u);
  CHECK(back.value()[0].bytes == blob.value());
  CHECK(back.value()[1].address == kSlotBAddress);
  std::filesystem::remove_all(dir);
}

TEST_CASE("The nrfjprog command keeps the other pages", "[blob][hex]") {
  CHECK(NrfjprogCommand("tag.hex") ==
        "nrfjprog -f NRF51 --program tag.hex --sectorerase --verify --reset");
}
