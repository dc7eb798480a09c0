#include "metro_fw/crc.h"

#include <catch2/catch.hpp>
#include <cstring>
#include <random>
#include <vector>

#include "test_support.hpp"

namespace {
const uint8_t kCheck[] = {'1', '2', '3', '4', '5', '6', '7', '8', '9'};
}

TEST_CASE("CRC-32/ISO-HDLC check value of 123456789 is 0xCBF43926", "[fw][crc]") {
  REQUIRE(metro_fw_crc32(0, kCheck, 9) == 0xCBF43926u);
  REQUIRE(metro_fw_crc32(0, nullptr, 0) == 0u);
}

TEST_CASE("CRC-32 in chunks equals the CRC of the whole and the bitwise reference", "[fw][crc]") {
  std::mt19937 rng(7);
  std::vector<uint8_t> data(1000);
  for (auto& b : data) b = static_cast<uint8_t>(rng());
  const uint32_t whole = metro_fw_crc32(0, data.data(), 1000);
  REQUIRE(whole == fwtest::BitwiseCrc32(data.data(), data.size()));
  for (uint32_t split : {0u, 1u, 31u, 500u, 999u, 1000u}) {
    const uint32_t part = metro_fw_crc32(0, data.data(), split);
    REQUIRE(metro_fw_crc32(part, data.data() + split, 1000 - split) == whole);
  }
}

TEST_CASE("CRC-16/CCITT-FALSE check value of 123456789 is 0x29B1", "[fw][crc]") {
  REQUIRE(metro_fw_crc16(METRO_FW_CRC16_INIT, kCheck, 9) == 0x29B1u);
  const uint16_t part = metro_fw_crc16(METRO_FW_CRC16_INIT, kCheck, 4);
  REQUIRE(metro_fw_crc16(part, kCheck + 4, 5) == 0x29B1u);
}
