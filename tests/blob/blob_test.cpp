#include "metro/blob/blob.hpp"

#include <catch2/catch.hpp>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <random>
#include <regex>
#include <string>

#include "blob/blob_test_support.hpp"
#include "metro_fw/blob.h"
#include "metro_fw/crc.h"
#include "tests/test_support.hpp"

using namespace metro::blob;
using metro::blob::testing::Contents;
using metro::blob::testing::kDeviceId;

namespace {

uint32_t Le32(const std::vector<uint8_t>& b, size_t off) {
  return uint32_t{b[off]} | uint32_t{b[off + 1]} << 8 | uint32_t{b[off + 2]} << 16 |
         uint32_t{b[off + 3]} << 24;
}
float LeF32(const std::vector<uint8_t>& b, size_t off) {
  const uint32_t u = Le32(b, off);
  float f;
  std::memcpy(&f, &u, 4);
  return f;
}

}  // namespace

TEST_CASE("CRC-32 check value 0xCBF43926 on the C++ and the C side", "[blob]") {
  const uint8_t check[] = {'1', '2', '3', '4', '5', '6', '7', '8', '9'};
  CHECK(Crc32(check, 9) == 0xCBF43926u);
  CHECK(metro_fw_crc32(0, check, 9) == 0xCBF43926u);
}

TEST_CASE("The C++ writer lays the blob out on the v1 map", "[blob]") {
  auto written = WriteBlob(Contents());
  REQUIRE(written.ok());
  const auto& b = written.value();
  REQUIRE(b.size() == kV1TotalLen);
  CHECK(std::string(b.begin(), b.begin() + 4) == "ICAL");
  CHECK(Le32(b, 4) == 0x00000001u);         // fmt 1.0
  CHECK(Le32(b, 8) == (540u | 32u << 16));  // total_len 540, header_len 32
  CHECK(Le32(b, 12) == 17u);
  CHECK(Le32(b, 16) == 0x12345678u);                  // DEVICEID[0]
  CHECK(Le32(b, 20) == 0x9ABCDEF0u);                  // DEVICEID[1]
  CHECK(Le32(b, 24) == 0x07u);                        // accel, gyro, temperature model
  CHECK(Le32(b, 0x20) == (0x0001u | 0x0100u << 16));  // META v1.0
  CHECK(Le32(b, 0x24) == 128u);
  CHECK(Le32(b, 0xA8) == (0x0010u | 0x0100u << 16));  // ACCEL v1.0
  CHECK(Le32(b, 0xAC) == 176u);
  CHECK(Le32(b, 0x160) == (0x0011u | 0x0100u << 16));  // GYRO v1.0
  CHECK(b[0xB0] == 0);                                 // accel fs_sel
  CHECK(b[0xB1] == 3);                                 // dlpf_cfg
  CHECK(b[0xB2] == 0x0F);
  CHECK(LeF32(b, 0xB0 + 4) == 24.5f);
  CHECK(LeF32(b, 0xB0 + 44) == 150.25f);  // b0[0]
  CHECK(LeF32(b, 0x168 + 44) == -42.0f);  // gyro b0[0]
  CHECK(LeF32(b, 0x28 + 96) == static_cast<float>(9.8101));
  CHECK(std::string(reinterpret_cast<const char*>(&b[0x28 + 80])) == "LAB-REF-0042");
  CHECK(static_cast<int16_t>(b[0xB0 + 164] | b[0xB0 + 165] << 8) == -1234);
  CHECK(Le32(b, 0x218) == metro_fw_crc32(0, b.data(), 0x218));
}

TEST_CASE("The golden blob written by C++ is loaded by the firmware with the same constants",
          "[blob]") {
  const auto contents = Contents();
  auto written = WriteBlob(contents);
  REQUIRE(written.ok());
  fwtest::FakeFlash flash;
  flash.Program(METRO_FW_SLOT_A_ADDR, written.value());
  metro_fw_flash f = flash.Interface();
  metro_fw_config cfg{};
  cfg.device_id[0] = 0x12345678u;
  cfg.device_id[1] = 0x9ABCDEF0u;
  cfg.dlpf_cfg = 3;
  metro_fw_calibration cal{};
  REQUIRE(metro_fw_load(&f, &cfg, &cal) == METRO_FW_OK);
  REQUIRE(cal.slot == 0);
  CHECK(cal.seq == 17u);
  CHECK(cal.crc32 == Crc32(written.value().data(), 0x218));
  REQUIRE(cal.accel.status == METRO_FW_SENSOR_OK);
  REQUIRE(cal.gyro.status == METRO_FW_SENSOR_OK);
  for (size_t i = 0; i < 9; ++i) CHECK(cal.accel.m[i] == static_cast<float>(contents.accel->m[i]));
  for (size_t i = 0; i < 3; ++i) {
    CHECK(cal.accel.b0[i] == static_cast<float>(contents.accel->b0_lsb[i]));
    CHECK(cal.accel.b1[i] == static_cast<float>(contents.accel->b1_lsb_per_c[i]));
    CHECK(cal.accel.b2[i] == static_cast<float>(contents.accel->b2_lsb_per_c2[i]));
    CHECK(cal.gyro.b2[i] == 0.0f);  // gyro has no quadratic bit
    CHECK(cal.accel.hw_offs[i] == contents.accel->hw_offs[i]);
  }
  CHECK(cal.accel.t_valid_max_c == 45.0f);
}

TEST_CASE("Decode returns what was written and rounded to binary32", "[blob]") {
  const auto c = Contents();
  auto written = WriteBlob(c);
  REQUIRE(written.ok());
  auto decoded = DecodeBlob(written.value());
  REQUIRE(decoded.ok());
  const auto& d = decoded.value();
  CHECK(d.seq == 17u);
  CHECK(d.device_id == kDeviceId);
  CHECK(d.meta.reference_id == "LAB-REF-0042");
  CHECK(d.meta.tag_label == "TAG-07");
  CHECK(d.meta.tool_commit == c.meta.tool_commit);
  CHECK(d.meta.raw_data_sha256 == c.meta.raw_data_sha256);
  CHECK(d.meta.g_local_mps2 == static_cast<float>(9.8101));
  REQUIRE(d.accel);
  REQUIRE(d.gyro);
  for (size_t i = 0; i < 9; ++i) {
    CHECK(d.accel->u_m[i] == static_cast<float>(c.accel->u_m[i]));
    CHECK(d.gyro->m[i] == static_cast<float>(c.gyro->m[i]));
  }
  CHECK(d.accel->resid_rms_si == static_cast<float>(0.0081));
  CHECK(d.accel->hw_offs == c.accel->hw_offs);
  // A second write of the decoded contents gives the same bytes.
  auto again = WriteBlob(d);
  REQUIRE(again.ok());
  CHECK(again.value() == written.value());
}

TEST_CASE("A blob without gyro leaves the section out", "[blob]") {
  auto c = Contents();
  c.gyro.reset();
  c.provisional = true;
  auto written = WriteBlob(c);
  REQUIRE(written.ok());
  CHECK(written.value().size() == 540u - 184u);
  auto d = DecodeBlob(written.value());
  REQUIRE(d.ok());
  CHECK(!d.value().gyro);
  CHECK(d.value().flags == (0x01u | 0x04u | 0x08u));
}

TEST_CASE("The writer refuses invalid contents with a message", "[blob]") {
  auto check = [](BlobContents c, const std::string& expected) {
    auto r = WriteBlob(c);
    REQUIRE(!r.ok());
    CHECK_THAT(r.error().message, Catch::Contains(expected));
  };
  auto c = Contents();
  c.seq = 0;
  check(c, "seq 0 is outside 1..4294967294");
  c = Contents();
  c.seq = 0xFFFFFFFFu;
  check(c, "seq 4294967295 is outside");
  c = Contents();
  c.accel->fs_sel = 4;
  check(c, "accel: fs_sel 4 is not 0..3");
  c = Contents();
  c.gyro->dlpf_cfg = 7;
  check(c, "gyro: dlpf_cfg 7 is not 0..6");
  c = Contents();
  c.accel->model_bits = 0x10;
  check(c, "model_bits 0x10 has bits outside 0x8F");
  c = Contents();
  c.accel->m[4] = std::numeric_limits<double>::quiet_NaN();
  check(c, "accel: a constant is NaN, infinite or too large for binary32");
  c = Contents();
  c.accel->b0_lsb[0] = 1e39;
  check(c, "too large for binary32");
  c = Contents();
  c.gyro->u_b0_lsb[1] = -0.1;
  check(c, "gyro: an uncertainty or resid_rms is negative");
  c = Contents();
  c.accel->t_valid_min_c = 50.0;
  check(c, "t_valid_min_c 50 is not below t_valid_max_c 45");
  c = Contents();
  c.meta.reference_id = "an identifier far too long";
  check(c, "reference_id 'an identifier far too long' is longer than 16 characters");
  c = Contents();
  c.meta.tag_label = "T\x01";
  check(c, "tag_label");
  c = Contents();
  for (auto& v : c.accel->m) v /= 9.80665;  // in g instead of m/s^2
  check(c, "the tag firmware would not use the accel constants (LIMITS)");
  c = Contents();
  c.gyro->b0_lsb[2] = 8000.0;  // 61 deg/s
  check(c, "would not use the gyro constants (LIMITS)");
  c = Contents();
  c.accel.reset();
  c.gyro.reset();  // the firmware's validator refuses it (METRO_FW_E_SENSOR)
  check(c, "no sensor constants; a blob carries the accel constants, the gyro constants or both");
}

TEST_CASE("Device ids parse from 16 hex digits", "[blob]") {
  auto id = ParseDeviceId("9abcdef012345678");
  REQUIRE(id.ok());
  CHECK(id.value() == kDeviceId);
  CHECK(FormatDeviceId(kDeviceId) == "9ABCDEF012345678");
  for (const char* bad : {"", "123", "9abcdef01234567g", "9abcdef0123456789"}) {
    auto r = ParseDeviceId(bad);
    REQUIRE(!r.ok());
    CHECK_THAT(r.error().message, Catch::Contains("expected 16 hex digits"));
  }
}

TEST_CASE("Decode reports the firmware's reason", "[blob]") {
  auto written = WriteBlob(Contents());
  REQUIRE(written.ok());
  auto bytes = written.value();
  bytes[300] ^= 0x04;
  auto r = DecodeBlob(bytes);
  REQUIRE(!r.ok());
  CHECK(r.error().message == "METRO_FW_E_CRC: CRC-32 mismatch");
  auto foreign = DecodeBlob(written.value(), 1ull);
  REQUIRE(!foreign.ok());
  CHECK(foreign.error().message == "METRO_FW_E_FOREIGN: device id belongs to another tag");
  auto empty = DecodeBlob(std::vector<uint8_t>(1024, 0xFF));
  REQUIRE(!empty.ok());
  CHECK(empty.error().message == "METRO_FW_E_EMPTY: empty slot (magic 0xFFFFFFFF)");
  auto shortblob = DecodeBlob(std::vector<uint8_t>(2, 0));
  REQUIRE(!shortblob.ok());
  CHECK_THAT(shortblob.error().message, Catch::StartsWith("METRO_FW_E_BOUNDS"));
}

TEST_CASE("Every firmware return code of error.h has its own name", "[blob]") {
  // The enumerators as the firmware's header spells them, read from its text: a code added
  // there without a name here fails this test.
  std::ifstream in(std::string(METRO_SOURCE_DIR) + "/firmware/include/metro_fw/error.h");
  REQUIRE(in);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::regex enumerator(R"((METRO_FW_[A-Z_]+) = (-?[0-9]+))");
  int count = 0;
  for (auto it = std::sregex_iterator(text.begin(), text.end(), enumerator);
       it != std::sregex_iterator(); ++it, ++count) {
    const int code = std::stoi((*it)[2].str());
    CAPTURE(code);
    CHECK(FirmwareErrorName(code) == (*it)[1].str());
  }
  CHECK(count >= 15);  // METRO_FW_OK .. METRO_FW_E_SENSOR and METRO_FW_LIVE_UNVERIFIED.
  CHECK(FirmwareErrorName(-99) == "METRO_FW_E_UNKNOWN(-99)");
}

TEST_CASE("Apply on the firmware equals ApplyConstants on the PC within float32", "[blob]") {
  auto written = WriteBlob(Contents());
  REQUIRE(written.ok());
  auto decoded = DecodeBlob(written.value());
  REQUIRE(decoded.ok());
  fwtest::FakeFlash flash;
  flash.Program(METRO_FW_SLOT_A_ADDR, written.value());
  metro_fw_flash f = flash.Interface();
  metro_fw_config cfg{};
  cfg.device_id[0] = 0x12345678u;
  cfg.device_id[1] = 0x9ABCDEF0u;
  cfg.dlpf_cfg = 3;
  metro_fw_calibration cal{};
  REQUIRE(metro_fw_load(&f, &cfg, &cal) == METRO_FW_OK);
  std::mt19937 rng(5);
  std::uniform_int_distribution<int> raw(-32768, 32767);
  std::uniform_real_distribution<double> temp(-10.0, 60.0);  // also outside 5..45: clamped
  for (int n = 0; n < 5000; ++n) {
    const std::array<int16_t, 3> r = {static_cast<int16_t>(raw(rng)),
                                      static_cast<int16_t>(raw(rng)),
                                      static_cast<int16_t>(raw(rng))};
    const float t = static_cast<float>(temp(rng));
    for (int sensor = 0; sensor < 2; ++sensor) {
      const auto& constants = sensor == 0 ? *decoded.value().accel : *decoded.value().gyro;
      const auto& fw = sensor == 0 ? cal.accel : cal.gyro;
      float y[3];
      REQUIRE(metro_fw_apply(&fw, r.data(), t, y) == METRO_FW_OK);
      const auto pc = ApplyConstants(constants, r, t);
      const double full_scale = 32768.0 * 1.1 * constants.m[0];
      for (size_t i = 0; i < 3; ++i) CHECK(std::fabs(y[i] - pc[i]) <= 1e-6 * full_scale);
    }
  }
}

TEST_CASE("ApplyConstants follows the model and its bits", "[blob]") {
  SensorConstants s;
  s.model_bits = kModelBias | kModelLinearT;  // no full matrix, no quadratic term
  s.m = {2.0, 5.0, 0.0, 0.0, 3.0, 0.0, 0.0, 0.0, 4.0};
  s.b0_lsb = {10.0, 20.0, 30.0};
  s.b1_lsb_per_c = {1.0, 0.0, 0.0};
  s.b2_lsb_per_c2 = {100.0, 100.0, 100.0};
  s.t_ref_c = 20.0;
  s.t_valid_min_c = 0.0;
  s.t_valid_max_c = 40.0;
  // T = 50 clamps to 40: dT = 20; x: 2 * (110 - 10 - 20) = 160; m[1] is ignored.
  const auto y = ApplyConstants(s, {110, 23, 34}, 50.0);
  CHECK(y[0] == 160.0);
  CHECK(y[1] == 9.0);
  CHECK(y[2] == 16.0);
  const auto nan_t = ApplyConstants(s, {110, 23, 34}, std::numeric_limits<double>::quiet_NaN());
  CHECK(nan_t[0] == 200.0);  // dT = 0
}
