// The golden blob written by the C++ side (datasets/golden/tag_sensor2.bin, made by
// `calibrate blob` from calibration_sensor2.json) parsed by the tag's C code: it validates,
// loads into slot A, and every constant equals calibration.json converted to SI as
// docs/calibration-blob.md section 10 says, rounded to binary32.
#include <catch2/catch.hpp>
#include <cmath>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>

#include "metro_fw/blob.h"
#include "test_support.hpp"

namespace {

const std::string kGolden = std::string(METRO_SOURCE_DIR) + "/datasets/golden/";

std::vector<uint8_t> ReadBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  REQUIRE(in.good());
  return std::vector<uint8_t>(std::istreambuf_iterator<char>(in), {});
}

void CheckSensor(const metro_fw_sensor_cal& c, const nlohmann::json& j, double si) {
  CHECK(c.status == METRO_FW_SENSOR_OK);
  CHECK(c.model_bits == 0x07);  // bias, full M, linear T
  for (int i = 0; i < 3; ++i) {
    for (int k = 0; k < 3; ++k) {
      CHECK(c.m[3 * i + k] == static_cast<float>(si * j["matrix"][i][k].get<double>()));
    }
    CHECK(c.b0[i] == static_cast<float>(j["bias"][i].get<double>()));
    CHECK(c.b1[i] == static_cast<float>(j["temperature"]["bias_per_c"][i].get<double>()));
    CHECK(c.b2[i] == 0.0f);
  }
  CHECK(c.t_ref_c == static_cast<float>(j["temperature"]["t_ref_c"].get<double>()));
  CHECK(c.t_valid_min_c == -40.0f);
  CHECK(c.t_valid_max_c == 85.0f);
}

}  // namespace

TEST_CASE("Golden blob from the C++ writer is valid for the C reader", "[golden]") {
  const std::vector<uint8_t> blob = ReadBytes(kGolden + "tag_sensor2.bin");
  REQUIRE(blob.size() == METRO_FW_V1_TOTAL_LEN);
  metro_fw_blob_info info{};
  REQUIRE(fwtest::Validate(blob, &info) == METRO_FW_OK);
  CHECK(info.seq == 3u);
  CHECK(info.device_id[0] == fwtest::kDeviceId[0]);
  CHECK(info.device_id[1] == fwtest::kDeviceId[1]);
  CHECK(info.flags == 0x07u);  // accel, gyro, temperature model
  CHECK(info.crc32 == fwtest::BitwiseCrc32(blob.data(), blob.size() - 4));
  CHECK(info.accel_off == 0xB0);
  CHECK(info.gyro_off == 0x168);

  fwtest::FakeFlash flash;
  flash.Program(METRO_FW_SLOT_A_ADDR, blob);
  const metro_fw_flash f = flash.Interface();
  const metro_fw_config cfg = fwtest::Config();
  metro_fw_calibration cal{};
  REQUIRE(metro_fw_load(&f, &cfg, &cal) == METRO_FW_OK);
  CHECK(cal.slot == 0);
  CHECK(cal.slot_result[1] == METRO_FW_E_EMPTY);

  std::ifstream in(kGolden + "calibration_sensor2.json");
  REQUIRE(in.good());
  const nlohmann::json j = nlohmann::json::parse(in);
  const nlohmann::json& tag = j["tags"][0];
  REQUIRE(tag["sensor"] == 2);
  CheckSensor(cal.accel, tag["accel"], fwtest::kStandardGravity_mps2);
  CheckSensor(cal.gyro, tag["gyro"], fwtest::kPi / 180.0);

  // A tag configured for another range or filter refuses the sections but keeps the slot.
  metro_fw_config other = cfg;
  other.gyro_fs_sel = 1;
  other.dlpf_cfg = 0;
  REQUIRE(metro_fw_load(&f, &other, &cal) == METRO_FW_OK);
  CHECK(cal.slot == 0);
  CHECK(cal.accel.status == METRO_FW_SENSOR_CONFIG_MISMATCH);
  CHECK(cal.gyro.status == METRO_FW_SENSOR_CONFIG_MISMATCH);
}
