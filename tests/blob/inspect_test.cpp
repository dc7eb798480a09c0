#include "metro/blob/inspect.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "blob/blob_test_support.hpp"
#include "metro/blob/intel_hex.hpp"
#include "metro/core/file.hpp"
#include "support/run_program.hpp"

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
  const nlohmann::json j = nlohmann::json::parse(ToJson(report));
  CHECK(j["ok"] == true);
  CHECK(j["active_slot"] == "file");
  CHECK(j["slots"][0]["seq"] == 17);
  CHECK(j["slots"][0]["accel"]["status"] == "OK");
  CHECK(j["slots"][0]["accel"]["b0_lsb"][0] == 150.25);
  CHECK(j["slots"][0]["meta"]["reference_id"] == "LAB-REF-0042");
}

TEST_CASE("Inspect text shows the whole blob with dates in UTC", "[blob][inspect]") {
  // issue #23: M, the temperature terms, t_ref, the validity range and the times as dates.
  auto blob = WriteBlob(testing::Contents());
  REQUIRE(blob.ok());
  auto r = InspectFile(WriteTemp("whole.bin", Bytes(blob.value())), InspectOptions{});
  REQUIRE(r.ok());
  const std::string text = FormatInspect(r.value());
  // 1780000000 s and 1811536000 s after 1970-01-01T00:00:00Z (Python's datetime.utcfromtimestamp).
  CHECK_THAT(text, Catch::Contains("    calibrated 2026-05-28T20:26:40Z, due 2027-05-28T20:26:40Z; "
                                   "tool 0.1.0 commit a0a1a2a3a4a5a6a7a8a9aaabacadaeafb0b1b2b3; "
                                   "procedure 3, k = 2.0\n"));
  CHECK_THAT(text, Catch::Contains("    temperature of the calibration: mean 24, min 6, max 44 "
                                   "degC\n"));
  // Row 0 of the accelerometer's M, 1.012 k, 0.003 k, -0.002 k with k = 9.80665 / 16384, as the
  // shortest decimals of their binary32 values (each checked to round-trip in Python).
  CHECK_THAT(text, Catch::Contains("    M [m/s^2 per LSB], row-major, and u(M) (k = 1):\n"
                                   "      [    0.000605733   1.7956512e-06  -1.1971008e-06]  u "
                                   "[2e-07 1e-08 1e-08]\n"));
  CHECK_THAT(text, Catch::Contains("    b1 [1.25 -0.75 2.5] LSB/degC, u [0.05 0.05 0.08]\n"));
  CHECK_THAT(text, Catch::Contains("    b2 [0.0125 0 -0.025] LSB/degC^2, u [0.001 0.001 0.002]\n"));
  CHECK_THAT(text, Catch::Contains("    t_ref 24.5 degC; validity range 5 .. 45 degC (the tag "
                                   "clamps the temperature to it)\n"));
  CHECK_THAT(text, Catch::Contains("    resid_rms 0.0081 m/s^2; hw_offs [-1234 567 8901] (bit 0x80 "
                                   "clear: not written)\n"));
  // The gyroscope has no quadratic term: its b2 is not applied.
  CHECK_THAT(text, Catch::Contains("    M [rad/s per LSB]"));
  CHECK_THAT(text, Catch::Contains("LSB/degC^2, u [0 0 0] (bit clear: not applied)\n"));
  // JSON: the dates beside the seconds, every key kept.
  const nlohmann::json j = nlohmann::json::parse(ToJson(r.value()));
  CHECK(j["slots"][0]["meta"]["cal_time_utc"] == "2026-05-28T20:26:40Z");
  CHECK(j["slots"][0]["meta"]["cal_time_utc_s"] == 1780000000u);
  CHECK(j["slots"][0]["meta"]["due_time_utc"] == "2027-05-28T20:26:40Z");
}

TEST_CASE("Inspect shows a section v2.0's declared s_nom and input", "[blob][inspect]") {
  // issue #25: the gyroscope of imu_tk's Xsens (83.2 LSB/(deg/s), unsigned counts).
  BlobContents c = testing::Contents();
  const double s_nom = 3.14159265358979323846 / 180.0 / 83.2;
  const double old_nom = 250.0 / 32768.0 * 3.14159265358979323846 / 180.0;
  for (double& m : c.gyro->m) m *= s_nom / old_nom;
  c.gyro->s_nom_si_per_lsb = s_nom;
  c.gyro->input = kInputOffsetBinary;
  c.gyro->fs_sel = 1;
  auto blob = WriteBlob(c);
  REQUIRE(blob.ok());
  auto r = InspectFile(WriteTemp("v2.bin", Bytes(blob.value())), InspectOptions{});
  REQUIRE(r.ok());
  CHECK(r.value().ok());
  const std::string text = FormatInspect(r.value());
  INFO(text);
  // s_nom as the binary32 the tag holds, and 83.2 LSB/(deg/s) back from it
  CHECK_THAT(text, Catch::Contains(fmt::format(
                       "    section v2.0: s_nom {} rad/s per LSB (83.2 LSB/(deg/s)); input offset "
                       "binary (unsigned 16-bit counts; b0 relative to the mid-scale 32768)\n",
                       static_cast<float>(s_nom))));
  CHECK(text.find("section v2.0") == text.rfind("section v2.0"));  // the accel stays v1.0
  const nlohmann::json j = nlohmann::json::parse(ToJson(r.value()));
  CHECK(j["slots"][0]["gyro"]["section_version"] == "2.0");
  CHECK(j["slots"][0]["gyro"]["input"] == "offset_binary");
  CHECK(j["slots"][0]["gyro"]["s_nom_si_per_lsb"] ==
        static_cast<double>(static_cast<float>(s_nom)));
  CHECK(j["slots"][0]["accel"]["section_version"] == "1.0");
  CHECK_FALSE(j["slots"][0]["accel"].contains("s_nom_si_per_lsb"));
  // An input code the firmware does not know is refused by the gate, naming it.
  std::vector<uint8_t> bad = blob.value();
  bad[0x168 + 3] = 2;
  const uint32_t crc = Crc32(bad.data(), bad.size() - 4);
  for (int i = 0; i < 4; ++i) bad[bad.size() - 4 + i] = static_cast<uint8_t>(crc >> (8 * i));
  auto rb = InspectFile(WriteTemp("v2_bad_input.bin", Bytes(bad)), InspectOptions{});
  REQUIRE(rb.ok());
  CHECK_FALSE(rb.value().ok());
  CHECK_THAT(FormatInspect(rb.value()), Catch::Contains("an input encoding other than 0 (int16) "
                                                        "and 1 (offset binary)"));
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
  CHECK(nlohmann::json::parse(ToJson(r.value()))["active_slot"].is_null());
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

TEST_CASE("Inspect refuses a blob with a sensor the firmware would not use", "[blob][inspect]") {
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
  // issue #20: this passed (the tag would have run the gyro on defaults).
  CHECK_FALSE(r.value().ok());
  CHECK(r.value().slots[0].sensors[0].status_name == "OK");
  CHECK(r.value().slots[0].sensors[1].status_name == "NONFINITE");
  CHECK(r.value().refusals ==
        std::vector<std::string>{
            "blob: the gyro section at bytes 0x168-0x217 is NONFINITE: a NaN or Inf constant, or "
            "a negative uncertainty; expected finite constants; the tag would run the gyro on "
            "default constants"});
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

namespace {

// Sets the f32 at blob offset `off` and fixes the CRC.
void SetF32(std::vector<uint8_t>& b, size_t off, uint32_t bits) {
  for (int i = 0; i < 4; ++i) b[off + i] = static_cast<uint8_t>(bits >> (8 * i));
  const uint32_t crc = Crc32(b.data(), b.size() - 4);
  for (int i = 0; i < 4; ++i) b[b.size() - 4 + i] = static_cast<uint8_t>(crc >> (8 * i));
}

std::vector<uint8_t> Golden() {
  auto blob = WriteBlob(testing::Contents());
  REQUIRE(blob.ok());
  return blob.value();
}

std::string Factory(std::vector<HexSegment> extra = {}) {
  std::vector<HexSegment> segs = FactoryImage(Golden(), kSlotAAddress, kSlotBAddress);
  segs.insert(segs.end(), extra.begin(), extra.end());
  std::sort(segs.begin(), segs.end(),
            [](const HexSegment& a, const HexSegment& b) { return a.address < b.address; });
  auto hex = WriteIntelHex(segs);
  REQUIRE(hex.ok());
  return hex.value();
}

const std::string kSlots =
    ": a calibration image writes only slot A 0x3B000-0x3B3FF and slot B 0x3B400-0x3B7FF";

}  // namespace

TEST_CASE("Inspect refuses a HEX that writes the MBR, the bootloader or 0x3B800",
          "[blob][inspect][security]") {
  // issue #20: each of these said "result: valid"; programming them bricks the tag.
  const std::vector<uint8_t> sixteen(16, 0xAB);
  auto r = InspectFile(
      WriteTemp("brick.hex", Factory({HexSegment{0x00000000, sixteen},
                                      HexSegment{0x3B7F0, std::vector<uint8_t>(32, 0xAB)},
                                      HexSegment{0x3C000, sixteen},
                                      HexSegment{0x10001014, {0x00, 0xC0, 0x03, 0x00}}})),
      InspectOptions{});
  REQUIRE(r.ok());
  const InspectReport& report = r.value();
  CHECK(report.active == 0);  // the firmware would load slot A ...
  CHECK_FALSE(report.ok());   // ... but the file must not reach a programmer
  CHECK(report.refusals ==
        std::vector<std::string>{
            "0x00000000-0x0000000F (16 bytes) is written in the MBR and SoftDevice S110 "
            "(0x00000-0x17FFF)" +
                kSlots,
            "0x0003B800-0x0003B80F (16 bytes) is written in the pages between slot B and the "
            "bootloader (0x3B800-0x3BFFF)" +
                kSlots,
            "0x0003C000-0x0003C00F (16 bytes) is written in the DFU bootloader (0x3C000-0x3FFFF)" +
                kSlots,
            "0x10001014-0x10001017 (4 bytes) is written in the UICR (bootloader address, "
            "readback protection)" +
                kSlots,
            "slot B: bytes written after the tombstone word (0x3B7F0-0x3B7FF); expected them left "
            "erased (docs/calibration-blob.md section 1)"});
  const std::string text = FormatInspect(report);
  CHECK_THAT(text, Catch::Contains("refused: 0x00000000-0x0000000F (16 bytes) is written in the "
                                   "MBR and SoftDevice S110"));
  CHECK_THAT(text, Catch::EndsWith("result: REFUSED (5 problems): do not program this file\n"));
  const nlohmann::json j = nlohmann::json::parse(ToJson(report));
  CHECK(j["ok"] == false);
  CHECK(j["refusals"].size() == 5u);
  // The factory image alone still passes.
  auto clean = InspectFile(WriteTemp("clean.hex", Factory()), InspectOptions{});
  REQUIRE(clean.ok());
  CHECK(clean.value().ok());
  CHECK(clean.value().refusals.empty());
}

TEST_CASE("Inspect refuses a HEX without the slot-B tombstone or with garbage in a slot",
          "[blob][inspect][security]") {
  SECTION("no tombstone") {
    auto hex = WriteIntelHex({HexSegment{kSlotAAddress, Golden()}});
    REQUIRE(hex.ok());
    auto r = InspectFile(WriteTemp("notomb.hex", hex.value()), InspectOptions{});
    REQUIRE(r.ok());
    CHECK_FALSE(r.value().ok());
    CHECK(r.value().refusals ==
          std::vector<std::string>{
              "slot B (0x3B400-0x3B7FF) is not written: nrfjprog --sectorerase leaves the tag's "
              "old slot B, whose blob may carry a higher seq and win; expected a blob or the "
              "tombstone word 0x00000000 at 0x3B400 (docs/calibration-blob.md section 8)"});
  }
  SECTION("a broken blob instead of the tombstone, bytes after total_len in slot A") {
    std::vector<uint8_t> broken = Golden();
    broken[0x100] ^= 1;
    auto hex = WriteIntelHex({HexSegment{kSlotAAddress, Golden()},
                              HexSegment{kSlotAAddress + 0x300, {1, 2, 3, 4}},
                              HexSegment{kSlotBAddress, broken}});
    REQUIRE(hex.ok());
    auto r = InspectFile(WriteTemp("garbage.hex", hex.value()), InspectOptions{});
    REQUIRE(r.ok());
    CHECK_FALSE(r.value().ok());
    CHECK(r.value().refusals ==
          std::vector<std::string>{
              "slot A: bytes written after the blob's total_len 540 (0x3B300-0x3B303); expected "
              "them left erased (docs/calibration-blob.md section 1)",
              "slot B (0x3B400-0x3B7FF) holds no valid blob (METRO_FW_E_CRC) and no tombstone: "
              "expected a valid blob or the word 0x00000000 at 0x3B400"});
  }
}

TEST_CASE("Inspect refuses a blob whose sensors are both NaN or absent or disagree with flags",
          "[blob][inspect][security]") {
  SECTION("both NaN") {
    std::vector<uint8_t> b = Golden();
    SetF32(b, 0x0B0 + 8, 0x7FC00000u);  // accel M[0] = NaN
    SetF32(b, 0x168 + 8, 0x7FC00000u);  // gyro M[0] = NaN
    auto r = InspectFile(WriteTemp("nan.bin", Bytes(b)), InspectOptions{});
    REQUIRE(r.ok());
    CHECK_FALSE(r.value().ok());
    CHECK(r.value().refusals ==
          std::vector<std::string>{
              "blob: the accel section at bytes 0x0B0-0x15F is NONFINITE: a NaN or Inf constant, "
              "or a negative uncertainty; expected finite constants; the tag would run the accel "
              "on default constants",
              "blob: the gyro section at bytes 0x168-0x217 is NONFINITE: a NaN or Inf constant, or "
              "a negative uncertainty; expected finite constants; the tag would run the gyro on "
              "default constants"});
  }
  SECTION("both absent, header flags cleared") {
    // Header, META and CRC only (172 bytes), by hand: WriteBlob refuses it.
    std::vector<uint8_t> b = Golden();
    b.resize(0x0A8 + 4);
    b[8] = 0xAC;  // total_len
    b[9] = 0x00;
    SetF32(b, 24, 0);  // flags 0, CRC fixed
    auto r = InspectFile(WriteTemp("none.bin", Bytes(b)), InspectOptions{});
    REQUIRE(r.ok());
    CHECK_FALSE(r.value().ok());
    CHECK_THAT(FormatInspect(r.value()),
               Catch::Contains("refused: blob: no accel and no gyro section: the tag would run "
                               "both sensors on default constants; expected at least one sensor "
                               "section"));
  }
  SECTION("flags declare a gyro the blob does not hold") {
    BlobContents c = testing::Contents();
    c.gyro.reset();
    std::vector<uint8_t> b = WriteBlob(c).value();
    b[24] |= 0x02;  // flags b1
    SetF32(b, 24, b[24] | uint32_t{b[25]} << 8);
    auto r = InspectFile(WriteTemp("flags.bin", Bytes(b)), InspectOptions{});
    REQUIRE(r.ok());
    CHECK_FALSE(r.value().ok());
    CHECK(r.value().refusals ==
          std::vector<std::string>{
              "blob: flags 0x00000007 declare a gyro section (bit b1) that the blob does not "
              "hold; the tag would run the gyro on default constants; expected flags naming "
              "exactly the sensor sections present"});
  }
}

TEST_CASE("Inspect refuses a .bin with data after total_len", "[blob][inspect][security]") {
  std::vector<uint8_t> b = Golden();
  b.resize(b.size() + 4096, 0x00);
  auto r = InspectFile(WriteTemp("trailing.bin", Bytes(b)), InspectOptions{});
  REQUIRE(r.ok());
  CHECK(r.value().active == 0);
  CHECK_FALSE(r.value().ok());
  CHECK(r.value().refusals ==
        std::vector<std::string>{"4096 bytes after total_len 540 (bytes 0x21C-0x121B): a .bin "
                                 "holds exactly one blob; expected a file of 540 bytes"});
}

TEST_CASE("Inspect refuses a file past 64 KiB from its size, before reading it",
          "[blob][inspect][security]") {
  const auto dir = std::filesystem::temp_directory_path() / "metro_inspect_test";
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "huge.hex").string();
  {
    // A sparse 180 MB file: reading it all (the old code) would take 180 MB and more.
    std::ofstream f(path, std::ios::binary);
    f << ':';
  }
  std::filesystem::resize_file(path, 180u * 1024 * 1024);
  auto r = InspectFile(path, InspectOptions{});
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().ToString() ==
        path +
            ": 188743680 bytes; calibrate inspect reads at most 65536 bytes (both slot pages as "
            "Intel HEX take about 6 KiB, a .bin at most 1024 bytes)");
  // One byte past the limit is refused too; the limit itself is read.
  std::filesystem::resize_file(path, kMaxInspectFileBytes + 1);
  CHECK_FALSE(InspectFile(path, InspectOptions{}).ok());
  std::filesystem::resize_file(path, kMaxInspectFileBytes);
  auto at_limit = InspectFile(path, InspectOptions{});
  REQUIRE_FALSE(at_limit.ok());  // read, then refused as HEX syntax (NUL bytes)
  CHECK(at_limit.error().line == 1);
  std::filesystem::remove(path);
}

#ifdef METRO_CALIBRATE_EXE
TEST_CASE("calibrate inspect exits 1 with ok false for a HEX that writes the bootloader",
          "[blob][inspect][security][apps]") {
  const std::string path =
      WriteTemp("boot.hex", Factory({HexSegment{0x3C000, std::vector<uint8_t>(16, 0xAB)}}));
  metro::testing::ProgramRun r =
      metro::testing::RunProgram(METRO_CALIBRATE_EXE, "inspect --json " + path);
  CHECK(r.exit_code == 1);
  const auto j = nlohmann::json::parse(r.out);
  CHECK(j["ok"] == false);
  CHECK(j["active_slot"] == "A");
  CHECK(j["refusals"][0] ==
        "0x0003C000-0x0003C00F (16 bytes) is written in the DFU bootloader (0x3C000-0x3FFFF)" +
            kSlots);
  metro::testing::ProgramRun text =
      metro::testing::RunProgram(METRO_CALIBRATE_EXE, "inspect " + path);
  CHECK(text.exit_code == 1);
  CHECK_THAT(text.out, Catch::Contains("result: REFUSED (1 problem): do not program this file"));
}
#endif
