// Validation, slot choice and load at boot: the failure cases of the reference design.
#include "metro_fw/blob.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <random>

#include "test_support.hpp"

using fwtest::Blob;
using fwtest::Build;
using fwtest::FakeFlash;
using fwtest::StandardBlob;
using fwtest::Validate;

namespace {

metro_fw_calibration Load(FakeFlash& flash, metro_fw_config cfg = fwtest::Config()) {
  metro_fw_flash f = flash.Interface();
  metro_fw_calibration cal{};
  REQUIRE(metro_fw_load(&f, &cfg, &cal) == METRO_FW_OK);
  return cal;
}

// Builds the standard blob with one sensor replaced.
std::vector<uint8_t> WithAccel(const fwtest::Sensor& accel, uint32_t seq = 1) {
  Blob b = StandardBlob(seq);
  b.sections[1].body = fwtest::SensorBody(accel);
  return Build(b);
}

// The status the decoder gives the blob's ACCEL section (section 3.1). The validator refuses
// the blob (METRO_FW_E_SENSOR: the accelerometer is declared) exactly when that status is not
// OK, and a tag then boots without the slot, checked here too.
uint8_t AccelStatus(const std::vector<uint8_t>& bytes) {
  metro_fw_blob_info info{};
  const int rc = Validate(bytes, &info);
  metro_fw_buffer buf{bytes.data(), static_cast<uint32_t>(bytes.size())};
  const metro_fw_config cfg = fwtest::Config();
  metro_fw_sensor_cal cal{};
  REQUIRE(metro_fw_sensor_decode(metro_fw_buffer_read, &buf, &info, METRO_FW_ACCEL, &cfg, &cal) ==
          METRO_FW_OK);
  CHECK(rc == (cal.status == METRO_FW_SENSOR_OK ? METRO_FW_OK : METRO_FW_E_SENSOR));
  FakeFlash flash;
  flash.Program(METRO_FW_SLOT_A_ADDR, bytes);
  const auto loaded = Load(flash);
  CHECK(loaded.slot_result[0] == rc);
  CHECK(loaded.slot == (rc == METRO_FW_OK ? 0 : METRO_FW_SLOT_NONE));
  return cal.status;
}

}  // namespace

TEST_CASE("The standard v1 blob follows the v1 map and validates", "[fw][blob]") {
  const auto bytes = Build(StandardBlob(42));
  REQUIRE(bytes.size() == METRO_FW_V1_TOTAL_LEN);
  metro_fw_blob_info info{};
  REQUIRE(Validate(bytes, &info) == METRO_FW_OK);
  CHECK(info.total_len == 540);
  CHECK(info.seq == 42u);
  CHECK(info.meta_off == 0x028);
  CHECK(info.accel_off == 0x0B0);
  CHECK(info.gyro_off == 0x168);
  CHECK(info.crc32 == fwtest::Get32(bytes, 0x218));
  CHECK(info.flags == 0x07u);
}

TEST_CASE("Both slots empty give defaults and no active slot", "[fw][blob]") {
  FakeFlash flash;
  const auto cal = Load(flash);
  CHECK(cal.slot == METRO_FW_SLOT_NONE);
  CHECK(cal.slot_result[0] == METRO_FW_E_EMPTY);
  CHECK(cal.slot_result[1] == METRO_FW_E_EMPTY);
  CHECK(cal.accel.status == METRO_FW_SENSOR_ABSENT);
  CHECK(cal.gyro.status == METRO_FW_SENSOR_ABSENT);
  // Defaults: M = diag(9.80665 / 16384) m/s^2/LSB, b = 0 (MPU6050 fs_sel 0).
  CHECK(cal.accel.m[0] == Approx(9.80665 / 16384.0).epsilon(1e-7));
  CHECK(cal.accel.m[1] == 0.0f);
  CHECK(cal.gyro.m[8] == Approx(250.0 / 32768.0 * fwtest::kPi / 180.0).epsilon(1e-7));
}

TEST_CASE("Each slot valid alone is chosen", "[fw][blob]") {
  for (int slot = 0; slot < 2; ++slot) {
    FakeFlash flash;
    flash.Program(slot == 0 ? METRO_FW_SLOT_A_ADDR : METRO_FW_SLOT_B_ADDR, Build(StandardBlob(9)));
    const auto cal = Load(flash);
    CHECK(cal.slot == slot);
    CHECK(cal.seq == 9u);
    CHECK(cal.slot_result[1 - slot] == METRO_FW_E_EMPTY);
    CHECK(cal.accel.status == METRO_FW_SENSOR_OK);
    CHECK(cal.gyro.status == METRO_FW_SENSOR_OK);
    CHECK(cal.accel.m[0] == fwtest::GoodAccel().m[0]);
  }
}

TEST_CASE("Both slots valid: the larger seq wins either way and A wins a tie", "[fw][blob]") {
  struct Case {
    uint32_t seq_a, seq_b;
    int expected;
  };
  for (const Case c : {Case{5, 6, 1}, Case{6, 5, 0}, Case{7, 7, 0}, Case{1, 0xFFFFFFFEu, 1}}) {
    FakeFlash flash;
    flash.Program(METRO_FW_SLOT_A_ADDR, Build(StandardBlob(c.seq_a)));
    flash.Program(METRO_FW_SLOT_B_ADDR, Build(StandardBlob(c.seq_b)));
    const auto cal = Load(flash);
    CHECK(cal.slot == c.expected);
    CHECK(cal.seq == (c.expected == 0 ? c.seq_a : c.seq_b));
  }
}

TEST_CASE("A torn write without the magic word is not valid", "[fw][blob]") {
  auto bytes = Build(StandardBlob(8));
  bytes[0] = bytes[1] = bytes[2] = bytes[3] = 0xFF;
  CHECK(Validate(bytes) == METRO_FW_E_EMPTY);
  FakeFlash flash;
  flash.Program(METRO_FW_SLOT_A_ADDR, Build(StandardBlob(7)));
  flash.Program(METRO_FW_SLOT_B_ADDR, bytes);
  const auto cal = Load(flash);
  CHECK(cal.slot == 0);
  CHECK(cal.seq == 7u);
  // A partly programmed commit word (bits only go 1 -> 0) is not "ICAL" either.
  bytes[0] = 0x49;
  bytes[1] = 0x43;
  CHECK(Validate(bytes) == METRO_FW_E_MAGIC);
}

TEST_CASE("A torn erase leaving the magic over garbage fails the CRC", "[fw][blob]") {
  auto bytes = Build(StandardBlob(8));
  std::fill(bytes.begin() + 512, bytes.end(), 0xFF);  // second half erased, magic kept
  CHECK(Validate(bytes) == METRO_FW_E_CRC);
}

TEST_CASE("The tombstone word reads as a bad magic", "[fw][blob]") {
  std::vector<uint8_t> page(METRO_FW_PAGE_SIZE, 0xFF);
  page[0] = page[1] = page[2] = page[3] = 0x00;
  CHECK(Validate(page) == METRO_FW_E_MAGIC);
}

TEST_CASE("Every single-bit flip of a valid blob is rejected", "[fw][blob]") {
  const auto good = Build(StandardBlob(3));
  REQUIRE(Validate(good) == METRO_FW_OK);
  int accepted = 0;
  for (size_t byte = 0; byte < good.size(); ++byte) {
    for (int bit = 0; bit < 8; ++bit) {
      auto bad = good;
      bad[byte] ^= static_cast<uint8_t>(1u << bit);
      if (Validate(bad) == METRO_FW_OK) ++accepted;
    }
  }
  CHECK(accepted == 0);
}

TEST_CASE("Random corruption is never accepted", "[fw][blob]") {
  const auto good = Build(StandardBlob(3));
  std::mt19937 rng(11);
  int accepted = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    auto bad = good;
    const int n = 1 + static_cast<int>(rng() % 8);
    for (int k = 0; k < n; ++k) bad[rng() % bad.size()] ^= static_cast<uint8_t>(1 + rng() % 255);
    if (Validate(bad) == METRO_FW_OK) ++accepted;
  }
  CHECK(accepted == 0);
}

TEST_CASE("Header bounds of total_len are checked before the body is read", "[fw][blob]") {
  for (uint16_t total : {0, 32, 34, 1028, 0xFFFF}) {
    auto bytes = Build(StandardBlob(3));
    bytes.resize(METRO_FW_PAGE_SIZE + 8, 0xFF);  // more readable bytes than a page
    fwtest::Put16(bytes, 8, total);
    if (total >= 8 && total <= bytes.size()) fwtest::Reseal(bytes, total);
    INFO("total_len " << total);
    CHECK(Validate(bytes) == METRO_FW_E_BOUNDS);
  }
  // total_len larger than the bytes that exist.
  auto bytes = Build(StandardBlob(3));
  bytes.resize(500);
  CHECK(Validate(bytes) == METRO_FW_E_BOUNDS);
}

TEST_CASE("Header bounds of header_len are checked", "[fw][blob]") {
  for (uint16_t header : {0, 28, 30, 540, 600}) {
    auto bytes = Build(StandardBlob(3));
    fwtest::Put16(bytes, 10, header);
    fwtest::Reseal(bytes, bytes.size());
    INFO("header_len " << header);
    CHECK(Validate(bytes) == METRO_FW_E_BOUNDS);
  }
}

TEST_CASE("A longer header of a newer fmt_minor is skipped; fmt_minor 0 has 32 bytes exactly",
          "[fw][blob]") {
  Blob b = StandardBlob(3);
  b.fmt_minor = 1;
  b.header_len = 40;
  metro_fw_blob_info info{};
  REQUIRE(Validate(Build(b), &info) == METRO_FW_OK);
  CHECK(info.accel_off == 0x0B0 + 8);
  b.fmt_minor = 0;  // v1.0 defines the header as 32 bytes: a longer one is inconsistent
  for (uint16_t header : {36, 40, 64}) {
    b.header_len = header;
    INFO("header_len " << header);
    CHECK(Validate(Build(b), &info) == METRO_FW_E_BOUNDS);
  }
}

TEST_CASE("A section body crossing the CRC word is rejected", "[fw][blob][walker]") {
  auto bytes = Build(StandardBlob(3));
  fwtest::Put16(bytes, 0x160 + 4, 180);  // GYRO body_len 176 -> 180 runs into the CRC
  fwtest::Reseal(bytes, bytes.size());
  CHECK(Validate(bytes) == METRO_FW_E_SECTION);
}

TEST_CASE("A section body length that is not a multiple of 4 is rejected", "[fw][blob][walker]") {
  Blob b = StandardBlob(3);
  b.sections.push_back({0x0200, 0x0100, std::vector<uint8_t>(8, 0)});
  auto bytes = Build(b);
  fwtest::Put16(bytes, 0x218 + 4, 6);  // body_len 6, followed by 2 bytes of padding
  fwtest::Reseal(bytes, bytes.size());
  CHECK(Validate(bytes) == METRO_FW_E_SECTION);
}

TEST_CASE("Zero-length sections: skipped if unknown and rejected if known", "[fw][blob][walker]") {
  Blob b = StandardBlob(3);
  b.sections.push_back({0x0200, 0x0100, {}});
  CHECK(Validate(Build(b)) == METRO_FW_OK);
  Blob k = StandardBlob(3);
  k.sections[2].body.clear();  // GYRO v1.0 with no body
  CHECK(Validate(Build(k)) == METRO_FW_E_SECTION);
}

TEST_CASE("Section types 0x0000 and 0xFFFF are rejected", "[fw][blob][walker]") {
  for (uint16_t type : {0x0000, 0xFFFF}) {
    Blob b = StandardBlob(3);
    b.sections.push_back({type, 0x0100, std::vector<uint8_t>(8, 0)});
    CHECK(Validate(Build(b)) == METRO_FW_E_SECTION);
  }
}

TEST_CASE("An unknown section type is skipped", "[fw][blob][walker]") {
  Blob b = StandardBlob(3);
  b.sections.insert(b.sections.begin() + 1, {0x0042, 0x0300, std::vector<uint8_t>(64, 0xAB)});
  FakeFlash flash;
  flash.Program(METRO_FW_SLOT_A_ADDR, Build(b));
  const auto cal = Load(flash);
  CHECK(cal.slot == 0);
  CHECK(cal.accel.status == METRO_FW_SENSOR_OK);
  CHECK(cal.gyro.status == METRO_FW_SENSOR_OK);
}

TEST_CASE("A duplicate known section is rejected", "[fw][blob][walker]") {
  Blob b = StandardBlob(3);
  b.sections.push_back(b.sections[1]);
  CHECK(Validate(Build(b)) == METRO_FW_E_SECTION);
}

TEST_CASE("Bytes after the last section that cannot hold a section are rejected",
          "[fw][blob][walker]") {
  auto bytes = Build(StandardBlob(3));
  // Grow total_len by 4: the gap before the CRC is too short for a section header.
  std::vector<uint8_t> grown(bytes.begin(), bytes.end() - 4);
  grown.resize(grown.size() + 8, 0);
  fwtest::Put16(grown, 8, static_cast<uint16_t>(grown.size()));
  fwtest::Reseal(grown, grown.size());
  CHECK(Validate(grown) == METRO_FW_E_SECTION);
}

TEST_CASE("A declared sensor of a newer section major refuses the blob; the older slot stays",
          "[fw][blob][walker]") {
  // The walker skips it (2.2), but this firmware cannot use a sensor the flags declare: a tag
  // would run that sensor on defaults (issue #20), so the blob is refused.
  Blob b = StandardBlob(4);
  b.sections[1].version = 0x0300;
  metro_fw_blob_info info{};
  CHECK(Validate(Build(b), &info) == METRO_FW_E_SENSOR);
  CHECK(info.accel_version == 0x0300);
  FakeFlash flash;
  flash.Program(METRO_FW_SLOT_A_ADDR, Build(StandardBlob(3)));
  flash.Program(METRO_FW_SLOT_B_ADDR, Build(b));
  const auto cal = Load(flash);
  CHECK(cal.slot_result[1] == METRO_FW_E_SENSOR);
  CHECK(cal.slot == 0);
  CHECK(cal.seq == 3u);
  CHECK(cal.accel.status == METRO_FW_SENSOR_OK);
  CHECK(cal.gyro.status == METRO_FW_SENSOR_OK);
  // The decoder on its own still says why.
  metro_fw_sensor_cal accel{};
  const auto bytes = Build(b);
  metro_fw_buffer buf{bytes.data(), static_cast<uint32_t>(bytes.size())};
  const metro_fw_config cfg = fwtest::Config();
  REQUIRE(metro_fw_sensor_decode(metro_fw_buffer_read, &buf, &info, METRO_FW_ACCEL, &cfg, &accel) ==
          METRO_FW_OK);
  CHECK(accel.status == METRO_FW_SENSOR_UNSUPPORTED);
}

TEST_CASE("A newer section minor with a longer body is read", "[fw][blob][walker]") {
  Blob b = StandardBlob(3);
  b.sections[1].version = 0x0103;
  b.sections[1].body.resize(176 + 24, 0x5A);
  FakeFlash flash;
  flash.Program(METRO_FW_SLOT_A_ADDR, Build(b));
  const auto cal = Load(flash);
  CHECK(cal.accel.status == METRO_FW_SENSOR_OK);
  CHECK(cal.accel.b0[2] == 300.0f);
}

TEST_CASE("A newer fmt_major in the higher-seq slot leaves the v1 slot active", "[fw][blob]") {
  Blob newer = StandardBlob(10);
  newer.fmt_major = 2;
  FakeFlash flash;
  flash.Program(METRO_FW_SLOT_A_ADDR, Build(StandardBlob(9)));
  flash.Program(METRO_FW_SLOT_B_ADDR, Build(newer));
  const auto cal = Load(flash);
  CHECK(cal.slot_result[1] == METRO_FW_E_UNSUPPORTED);
  CHECK(cal.slot == 0);
  CHECK(cal.seq == 9u);
}

TEST_CASE("A newer fmt_minor is accepted", "[fw][blob]") {
  Blob b = StandardBlob(3);
  b.fmt_minor = 7;
  CHECK(Validate(Build(b)) == METRO_FW_OK);
}

TEST_CASE("A foreign device id is rejected", "[fw][blob]") {
  Blob b = StandardBlob(3);
  b.device_id[1] ^= 1u;
  CHECK(Validate(Build(b)) == METRO_FW_E_FOREIGN);
}

TEST_CASE("seq 0 and 0xFFFFFFFF are rejected", "[fw][blob]") {
  for (uint32_t seq : {0u, 0xFFFFFFFFu})
    CHECK(Validate(Build(StandardBlob(seq))) == METRO_FW_E_SEQ);
}

TEST_CASE("NaN or Inf constants of a declared sensor refuse the blob", "[fw][blob][limits]") {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  for (float bad : {nan, inf, -inf}) {
    auto s = fwtest::GoodAccel();
    s.m[4] = bad;
    CHECK(AccelStatus(WithAccel(s)) == METRO_FW_SENSOR_NONFINITE);
    s = fwtest::GoodAccel();
    s.u_b2[1] = bad;  // even a field the firmware does not use
    CHECK(AccelStatus(WithAccel(s)) == METRO_FW_SENSOR_NONFINITE);
    s = fwtest::GoodAccel();
    s.t_valid_max_c = bad;
    CHECK(AccelStatus(WithAccel(s)) == METRO_FW_SENSOR_NONFINITE);
  }
  auto s = fwtest::GoodAccel();
  s.u_m[0] = -1e-7f;  // a negative standard uncertainty
  CHECK(AccelStatus(WithAccel(s)) == METRO_FW_SENSOR_NONFINITE);
}

TEST_CASE("Absurd constants of a declared sensor refuse the blob", "[fw][blob][limits]") {
  auto scaled = [](float k) {
    auto s = fwtest::GoodAccel();
    for (auto& v : s.m) v *= k;
    return s;
  };
  CHECK(AccelStatus(WithAccel(scaled(1.0f / 9.80665f))) == METRO_FW_SENSOR_LIMITS);  // g, not m/s^2
  CHECK(AccelStatus(WithAccel(scaled(2.0f))) == METRO_FW_SENSOR_LIMITS);             // wrong fs_sel
  CHECK(AccelStatus(WithAccel(scaled(1.08f))) == METRO_FW_SENSOR_OK);                // within 10 %
  CHECK(AccelStatus(WithAccel(scaled(1.12f))) == METRO_FW_SENSOR_LIMITS);
  auto flipped = fwtest::GoodAccel();
  for (int j = 0; j < 3; ++j) flipped.m[3 + j] = -flipped.m[3 + j];  // a reflection
  CHECK(AccelStatus(WithAccel(flipped)) == METRO_FW_SENSOR_LIMITS);
  auto bias = fwtest::GoodAccel();
  bias.b0[2] = 4200.0f;  // 0.256 g at fs_sel 0
  CHECK(AccelStatus(WithAccel(bias)) == METRO_FW_SENSOR_LIMITS);
  auto drift = fwtest::GoodAccel();
  drift.b2[0] = 5.0f;  // 5 LSB/degC^2 * 25^2 = 3125 LSB + b0 + b1 term > 4096
  drift.b1[0] = 40.0f;
  CHECK(AccelStatus(WithAccel(drift)) == METRO_FW_SENSOR_LIMITS);
  auto range = fwtest::GoodAccel();
  range.t_valid_min_c = 40.0f;
  range.t_valid_max_c = 30.0f;
  CHECK(AccelStatus(WithAccel(range)) == METRO_FW_SENSOR_LIMITS);
  auto hot = fwtest::GoodAccel();
  hot.t_valid_max_c = 90.0f;
  CHECK(AccelStatus(WithAccel(hot)) == METRO_FW_SENSOR_LIMITS);
}

TEST_CASE("Implausible temperature terms and validity ranges refuse the blob",
          "[fw][blob][limits]") {
  // issue #23: |b1| near 2^15 LSB/degC over a 0.01 degC range passed the bias bound
  // (32767 * 0.01 = 328 LSB) and the fixed apply then erred by up to 8 LSB.
  auto steep = fwtest::GoodAccel();
  steep.t_ref_c = 25.0f;
  steep.t_valid_min_c = 25.0f;
  steep.t_valid_max_c = 25.01f;
  steep.b1 = {32767.0f, -32767.0f, 32767.0f};
  steep.b2 = {0.0f, 0.0f, 0.0f};
  CHECK(AccelStatus(WithAccel(steep)) == METRO_FW_SENSOR_LIMITS);
  // The same range with a plausible b1: refused for the range alone (narrower than 2 degC).
  steep.b1 = {1.0f, 1.0f, 1.0f};
  CHECK(AccelStatus(WithAccel(steep)) == METRO_FW_SENSOR_LIMITS);
  steep.t_valid_max_c = 27.0f;  // 2 degC wide: accepted
  CHECK(AccelStatus(WithAccel(steep)) == METRO_FW_SENSOR_OK);
  // b1 at the temperature-coefficient limit (80 LSB/degC at fs_sel 0, 4.9 mg/degC) passes,
  // above it not; b2 counts with 2 |b2| D (D = 25 degC for 0 ... 50 around 25).
  auto tempco = fwtest::GoodAccel();
  tempco.b1 = {80.0f, 0.0f, 0.0f};
  tempco.b2 = {0.0f, 0.0f, 0.0f};
  CHECK(AccelStatus(WithAccel(tempco)) == METRO_FW_SENSOR_OK);
  tempco.b1[0] = 80.5f;
  CHECK(AccelStatus(WithAccel(tempco)) == METRO_FW_SENSOR_LIMITS);
  tempco.b1[0] = 70.0f;
  tempco.b2[0] = -0.2f;  // 70 + 2 * 0.2 * 25 = 80
  CHECK(AccelStatus(WithAccel(tempco)) == METRO_FW_SENSOR_OK);
  tempco.b2[0] = -0.21f;  // 80.5
  CHECK(AccelStatus(WithAccel(tempco)) == METRO_FW_SENSOR_LIMITS);
  // The gyroscope's limit is 88 LSB/degC (0.67 deg/s/degC) at fs_sel 0, 11 at fs_sel 3.
  auto gyro = fwtest::GoodGyro();
  gyro.b1 = {0.0f, -88.0f, 0.0f};
  gyro.b2 = {0.0f, 0.0f, 0.0f};
  Blob b = StandardBlob(1);
  b.sections[2].body = fwtest::SensorBody(gyro);
  CHECK(Validate(Build(b)) == METRO_FW_OK);
  gyro.b1[1] = -88.5f;
  b.sections[2].body = fwtest::SensorBody(gyro);
  CHECK(Validate(Build(b)) == METRO_FW_E_SENSOR);
  auto bits = fwtest::GoodAccel();
  bits.model_bits = 0x1F;
  CHECK(AccelStatus(WithAccel(bits)) == METRO_FW_SENSOR_BAD_MODEL);
}

TEST_CASE("A 90 degree sensor-to-body rotation in M is accepted", "[fw][blob][limits]") {
  // M = Rz(90 deg) * diag(s): the diagonal is zero, the row norms are s, det > 0.
  auto s = fwtest::GoodAccel();
  const float k = static_cast<float>(fwtest::kStandardGravity_mps2 / 16384.0);
  s.m = {0.0f, -k, 0.0f, k, 0.0f, 0.0f, 0.0f, 0.0f, k};
  CHECK(AccelStatus(WithAccel(s)) == METRO_FW_SENSOR_OK);
}

TEST_CASE("fs_sel or dlpf_cfg mismatch sends only that sensor to defaults", "[fw][blob][limits]") {
  FakeFlash flash;
  flash.Program(METRO_FW_SLOT_A_ADDR, Build(StandardBlob(3)));
  metro_fw_config cfg = fwtest::Config();
  cfg.accel_fs_sel = 1;
  auto cal = Load(flash, cfg);
  CHECK(cal.accel.status == METRO_FW_SENSOR_CONFIG_MISMATCH);
  CHECK(cal.accel.m[0] == Approx(9.80665 / 8192.0).epsilon(1e-7));  // defaults for fs_sel 1
  CHECK(cal.gyro.status == METRO_FW_SENSOR_OK);
  cfg = fwtest::Config();
  cfg.dlpf_cfg = 6;
  cal = Load(flash, cfg);
  CHECK(cal.accel.status == METRO_FW_SENSOR_CONFIG_MISMATCH);
  CHECK(cal.gyro.status == METRO_FW_SENSOR_CONFIG_MISMATCH);
  CHECK(cal.slot == 0);
}

TEST_CASE("Model bits that are clear zero their terms", "[fw][blob]") {
  auto s = fwtest::GoodAccel();
  s.model_bits = METRO_FW_MODEL_BIAS;  // bias only, diagonal M, no temperature terms
  FakeFlash flash;
  flash.Program(METRO_FW_SLOT_A_ADDR, WithAccel(s));
  const auto cal = Load(flash);
  REQUIRE(cal.accel.status == METRO_FW_SENSOR_OK);
  CHECK(cal.accel.m[1] == 0.0f);
  CHECK(cal.accel.m[0] == s.m[0]);
  CHECK(cal.accel.b0[0] == s.b0[0]);
  CHECK(cal.accel.b1[0] == 0.0f);
  CHECK(cal.accel.b2[0] == 0.0f);
}

TEST_CASE("Bad arguments are refused", "[fw][blob]") {
  const auto bytes = Build(StandardBlob(3));
  metro_fw_buffer buf{bytes.data(), static_cast<uint32_t>(bytes.size())};
  CHECK(metro_fw_blob_validate(nullptr, &buf, 540, fwtest::kDeviceId, nullptr) == METRO_FW_E_ARG);
  CHECK(metro_fw_blob_validate(metro_fw_buffer_read, &buf, 540, nullptr, nullptr) ==
        METRO_FW_E_ARG);
  CHECK(metro_fw_blob_validate(metro_fw_buffer_read, &buf, 3, fwtest::kDeviceId, nullptr) ==
        METRO_FW_E_BOUNDS);
  metro_fw_sensor_cal cal;
  CHECK(metro_fw_sensor_defaults(METRO_FW_ACCEL, 4, &cal) == METRO_FW_E_ARG);
  FakeFlash flash;
  metro_fw_flash f = flash.Interface();
  metro_fw_config cfg = fwtest::Config();
  cfg.gyro_fs_sel = 4;
  metro_fw_calibration out{};
  CHECK(metro_fw_load(&f, &cfg, &out) == METRO_FW_E_ARG);
}

TEST_CASE("Buffers shorter than a header give EMPTY or MAGIC before BOUNDS", "[fw][blob]") {
  // Section 4's order: the magic is judged on the bytes that exist, BOUNDS only after it.
  const auto good = Build(StandardBlob(3));
  for (uint32_t n = 4; n < METRO_FW_HEADER_LEN; ++n) {
    INFO("avail_len " << n);
    std::vector<uint8_t> erased(n, 0xFF);
    CHECK(Validate(erased) == METRO_FW_E_EMPTY);
    std::vector<uint8_t> tomb(n, 0x00);
    CHECK(Validate(tomb) == METRO_FW_E_MAGIC);
    std::vector<uint8_t> head(good.begin(), good.begin() + n);
    metro_fw_blob_info info;
    CHECK(Validate(head, &info) == METRO_FW_E_BOUNDS);
  }
  for (uint32_t n = 0; n < 4; ++n) {
    std::vector<uint8_t> erased(n, 0xFF);
    CHECK(Validate(erased) == METRO_FW_E_BOUNDS);
  }
}

TEST_CASE("info.crc32 is the stored CRC word and any other word fails", "[fw][blob]") {
  // The validator checks the CRC-32 residue over the blob including its CRC word; the stored
  // word is still reported, and other values of it are rejected (all 32 single-bit changes and
  // random words).
  auto bytes = Build(StandardBlob(3));
  const uint32_t stored = fwtest::Get32(bytes, 536);
  REQUIRE(stored == fwtest::BitwiseCrc32(bytes.data(), 536));
  metro_fw_blob_info info;
  REQUIRE(Validate(bytes, &info) == METRO_FW_OK);
  CHECK(info.crc32 == stored);
  std::mt19937 rng(5);
  for (int k = 0; k < 2000; ++k) {
    const uint32_t other = k < 32 ? stored ^ (1u << k) : static_cast<uint32_t>(rng());
    if (other == stored) continue;
    fwtest::Put32(bytes, 536, other);
    metro_fw_blob_info bad;
    INFO("stored word " << other);
    CHECK(Validate(bytes, &bad) == METRO_FW_E_CRC);
    CHECK(bad.crc32 == other);
  }
}
