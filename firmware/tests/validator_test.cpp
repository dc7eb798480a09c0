// Issue #20, part 8: the validator checks the flags against the sections present and refuses a
// blob whose declared sensors are missing, NaN or outside their limits, and lengths the format
// defines exactly (docs/security.md section 8). Each case here was accepted before.
#include <catch2/catch.hpp>
#include <limits>

#include "metro_fw/blob.h"
#include "metro_fw/push.h"
#include "metro_fw/update.h"
#include "test_support.hpp"

using fwtest::Blob;
using fwtest::Build;
using fwtest::FakeFlash;
using fwtest::StandardBlob;
using fwtest::Validate;

namespace {

metro_fw_calibration Load(FakeFlash& flash) {
  metro_fw_flash f = flash.Interface();
  metro_fw_config cfg = fwtest::Config();
  metro_fw_calibration cal{};
  REQUIRE(metro_fw_load(&f, &cfg, &cal) == METRO_FW_OK);
  return cal;
}

// The standard blob cut down to its header: total_len 36, the CRC recomputed.
std::vector<uint8_t> HeaderOnly(uint32_t seq, uint32_t flags) {
  std::vector<uint8_t> b(Build(StandardBlob(seq)));
  b.resize(36);
  fwtest::Put16(b, 8, 36);
  fwtest::Put32(b, 24, flags);
  fwtest::Reseal(b, b.size());
  return b;
}

Blob WithFlags(Blob b, uint32_t flags) {
  b.flags = flags;
  return b;
}

// Removes the section of `type`.
Blob Without(Blob b, uint16_t type) {
  for (size_t i = 0; i < b.sections.size(); ++i) {
    if (b.sections[i].type == type) b.sections.erase(b.sections.begin() + static_cast<long>(i));
  }
  return b;
}

}  // namespace

TEST_CASE("A blob cut down to its header, length and CRC fixed, is refused", "[fw][validator]") {
  for (uint32_t flags : {0x07u, 0x03u, 0x01u, 0x02u, 0x00u, 0x08u}) {
    INFO("flags " << flags);
    const auto cut = HeaderOnly(9, flags);
    metro_fw_blob_info info{};
    CHECK(Validate(cut, &info) == METRO_FW_E_SENSOR);
    CHECK(info.total_len == 36);
    // A tag holding it beside an older calibration boots on the older one, not on defaults.
    FakeFlash flash;
    flash.Program(METRO_FW_SLOT_A_ADDR, Build(StandardBlob(8)));
    flash.Program(METRO_FW_SLOT_B_ADDR, cut);
    const auto cal = Load(flash);
    CHECK(cal.slot_result[1] == METRO_FW_E_SENSOR);
    CHECK(cal.slot == 0);
    CHECK(cal.seq == 8u);
    CHECK(cal.accel.status == METRO_FW_SENSOR_OK);
    CHECK(cal.gyro.status == METRO_FW_SENSOR_OK);
    // Alone it is no calibration at all (UNCALIBRATED), never "calibrated" with defaults.
    FakeFlash alone;
    alone.Program(METRO_FW_SLOT_A_ADDR, cut);
    CHECK(Load(alone).slot == METRO_FW_SLOT_NONE);
    // And the update refuses it before touching flash.
    metro_fw_flash f = flash.Interface();
    int slot = 7;
    CHECK(metro_fw_update(&f, fwtest::kDeviceId, cut.data(), 36, &slot) == METRO_FW_E_SENSOR);
    CHECK(slot == METRO_FW_SLOT_NONE);
    CHECK(flash.ops == 0);
  }
  // META alone (no sensor section) is no calibration either, whatever the flags say.
  for (uint32_t flags : {0x07u, 0x00u}) {
    Blob b = WithFlags(StandardBlob(9), flags);
    b.sections.resize(1);
    CHECK(Validate(Build(b)) == METRO_FW_E_SENSOR);
  }
}

TEST_CASE("Flags b0 and b1 name exactly the sensor sections present", "[fw][validator]") {
  const Blob full = StandardBlob(3);
  const Blob accel_only = Without(full, METRO_FW_SEC_GYRO);
  const Blob gyro_only = Without(full, METRO_FW_SEC_ACCEL);
  // consistent: both, accel alone, gyro alone (b2: both test sensors have temperature terms)
  CHECK(Validate(Build(WithFlags(full, 0x07))) == METRO_FW_OK);
  CHECK(Validate(Build(WithFlags(accel_only, 0x05))) == METRO_FW_OK);
  CHECK(Validate(Build(WithFlags(gyro_only, 0x06))) == METRO_FW_OK);
  CHECK(Validate(Build(WithFlags(full, 0x0F))) == METRO_FW_OK);  // provisional is free
  // a declared sensor missing
  CHECK(Validate(Build(WithFlags(accel_only, 0x07))) == METRO_FW_E_SENSOR);
  CHECK(Validate(Build(WithFlags(gyro_only, 0x07))) == METRO_FW_E_SENSOR);
  CHECK(Validate(Build(WithFlags(gyro_only, 0x05))) == METRO_FW_E_SENSOR);
  // a section present but not declared
  CHECK(Validate(Build(WithFlags(full, 0x05))) == METRO_FW_E_SENSOR);
  CHECK(Validate(Build(WithFlags(full, 0x06))) == METRO_FW_E_SENSOR);
  CHECK(Validate(Build(WithFlags(accel_only, 0x06))) == METRO_FW_E_SENSOR);
  CHECK(Validate(Build(WithFlags(full, 0x04))) == METRO_FW_E_SENSOR);
}

TEST_CASE("Flag b2 is set exactly when a sensor has a temperature term", "[fw][validator]") {
  CHECK(Validate(Build(WithFlags(StandardBlob(3), 0x03))) == METRO_FW_E_SENSOR);
  Blob plain = StandardBlob(3);
  for (int k : {1, 2}) {
    auto s = k == 1 ? fwtest::GoodAccel() : fwtest::GoodGyro();
    s.model_bits = METRO_FW_MODEL_BIAS | METRO_FW_MODEL_FULL_M;
    plain.sections[static_cast<size_t>(k)].body = fwtest::SensorBody(s);
  }
  CHECK(Validate(Build(WithFlags(plain, 0x03))) == METRO_FW_OK);
  CHECK(Validate(Build(WithFlags(plain, 0x07))) == METRO_FW_E_SENSOR);
  // one sensor with a quadratic term only is enough
  auto quad = fwtest::GoodGyro();
  quad.model_bits = METRO_FW_MODEL_BIAS | METRO_FW_MODEL_QUADRATIC_T;
  plain.sections[2].body = fwtest::SensorBody(quad);
  CHECK(Validate(Build(WithFlags(plain, 0x07))) == METRO_FW_OK);
  CHECK(Validate(Build(WithFlags(plain, 0x03))) == METRO_FW_E_SENSOR);
}

TEST_CASE("Both sensor sections NaN, or either one, refuse the blob", "[fw][validator]") {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  auto accel = fwtest::GoodAccel();
  auto gyro = fwtest::GoodGyro();
  accel.b0[0] = nan;
  gyro.m[8] = nan;
  for (int which = 1; which <= 3; ++which) {
    Blob b = StandardBlob(3);
    if (which & 1) b.sections[1].body = fwtest::SensorBody(accel);
    if (which & 2) b.sections[2].body = fwtest::SensorBody(gyro);
    INFO("NaN in " << which);
    CHECK(Validate(Build(b)) == METRO_FW_E_SENSOR);
  }
  // Every float of the body is checked, the gyroscope's as the accelerometer's.
  for (int off = 4; off < 164; off += 4) {
    Blob b = StandardBlob(3);
    fwtest::PutF32(b.sections[2].body, static_cast<size_t>(off), nan);
    INFO("gyro body offset " << off);
    CHECK(Validate(Build(b)) == METRO_FW_E_SENSOR);
  }
}

TEST_CASE("A gyroscope outside its limits refuses the blob", "[fw][validator]") {
  auto gyro = fwtest::GoodGyro();
  for (auto& v : gyro.m) v *= static_cast<float>(180.0 / fwtest::kPi);  // deg/s, not rad/s
  Blob b = StandardBlob(3);
  b.sections[2].body = fwtest::SensorBody(gyro);
  CHECK(Validate(Build(b)) == METRO_FW_E_SENSOR);
  gyro = fwtest::GoodGyro();
  gyro.b0[1] = 8000.0f;  // 61 deg/s of bias at fs_sel 0
  b.sections[2].body = fwtest::SensorBody(gyro);
  CHECK(Validate(Build(b)) == METRO_FW_E_SENSOR);
  gyro.b0[1] = 7800.0f;  // 59.5 deg/s: inside
  gyro.b1 = {0.0f, 0.0f, 0.0f};
  gyro.b2 = {0.0f, 0.0f, 0.0f};
  b.sections[2].body = fwtest::SensorBody(gyro);
  CHECK(Validate(Build(b)) == METRO_FW_OK);
}

TEST_CASE("The validator judges a section on its own fs_sel and dlpf_cfg, in range",
          "[fw][validator]") {
  // An accelerometer calibrated at fs_sel 1 (+-4 g): twice the sensitivity, half the counts.
  auto accel = fwtest::GoodAccel();
  accel.fs_sel = 1;
  for (auto& v : accel.m) v *= 2.0f;
  for (auto& v : accel.b0) v /= 2.0f;
  Blob b = StandardBlob(3);
  b.sections[1].body = fwtest::SensorBody(accel);
  const auto fs1 = Build(b);
  CHECK(Validate(fs1) == METRO_FW_OK);
  // A tag configured for fs_sel 0 keeps the slot and runs that sensor on defaults (the
  // validator does not know the tag's configuration: section 3.1, CONFIG_MISMATCH).
  FakeFlash flash;
  flash.Program(METRO_FW_SLOT_A_ADDR, fs1);
  const auto cal = Load(flash);
  CHECK(cal.slot == 0);
  CHECK(cal.accel.status == METRO_FW_SENSOR_CONFIG_MISMATCH);
  // fs_sel above 3 and dlpf_cfg above 6 exist in no configuration.
  for (int field : {0, 1}) {
    for (uint8_t v : {4, 7, 255}) {
      if (field == 1 && v == 4) continue;  // dlpf_cfg 4 is a real setting
      Blob bad = StandardBlob(3);
      bad.sections[2].body[static_cast<size_t>(field)] = v;
      INFO("field " << field << " value " << int{v});
      CHECK(Validate(Build(bad)) == METRO_FW_E_SENSOR);
    }
  }
}

TEST_CASE("A v1.0 section body longer than v1.0 is refused; a newer minor may be longer",
          "[fw][validator]") {
  for (size_t k : {0u, 1u, 2u}) {
    Blob b = StandardBlob(3);
    b.sections[k].body.resize(b.sections[k].body.size() + 4, 0);
    INFO("section " << k);
    CHECK(Validate(Build(b)) == METRO_FW_E_SECTION);
    b.sections[k].version = 0x0101;
    CHECK(Validate(Build(b)) == METRO_FW_OK);
  }
}

TEST_CASE("An update with bytes after total_len is refused before flash is touched",
          "[fw][validator][update]") {
  for (uint8_t fill : {0x00, 0xFF, 0x5A}) {
    auto bytes = Build(StandardBlob(6));
    bytes.resize(bytes.size() + 4, fill);
    FakeFlash flash;
    flash.Program(METRO_FW_SLOT_A_ADDR, Build(StandardBlob(5)));
    metro_fw_flash f = flash.Interface();
    int slot = 3;
    CHECK(metro_fw_update(&f, fwtest::kDeviceId, bytes.data(), static_cast<uint32_t>(bytes.size()),
                          &slot) == METRO_FW_E_BOUNDS);
    CHECK(slot == METRO_FW_SLOT_NONE);
    CHECK(flash.ops == 0);
    CHECK(Load(flash).seq == 5u);
  }
}
