// Device ID text (core/device_id.hpp): metro's 16 hex digits and nrfjprog's two words name the
// same FICR DEVICEID.
#include "metro/core/device_id.hpp"

#include <catch2/catch.hpp>
#include <cstdint>
#include <string>

namespace metro {

TEST_CASE("Device ids: the 16 digits and the nrfjprog words of one FICR DEVICEID", "[core]") {
  // FICR at 0x10000060 holds the bytes 78 56 34 12 F0 DE BC 9A (little-endian words):
  // DEVICEID[0] = 0x12345678, DEVICEID[1] = 0x9ABCDEF0. nrfjprog --memrd 0x10000060 --n 8
  // prints the words at increasing addresses: "0x10000060: 12345678 9ABCDEF0 |xV4.....|".
  const uint8_t ficr[8] = {0x78, 0x56, 0x34, 0x12, 0xF0, 0xDE, 0xBC, 0x9A};
  uint32_t word[2] = {0, 0};
  for (int w = 0; w < 2; ++w) {
    for (int b = 3; b >= 0; --b) word[w] = word[w] << 8 | ficr[4 * w + b];
  }
  const uint64_t id = uint64_t{word[1]} << 32 | word[0];
  REQUIRE(id == 0x9ABCDEF012345678ull);
  for (const char* text :
       {"9ABCDEF012345678", "9abcdef012345678", "0x9ABCDEF012345678", "12345678 9ABCDEF0",
        "0x12345678 0x9abcdef0", "12345678,9ABCDEF0", "12345678\t9ABCDEF0",
        "0x10000060: 12345678 9ABCDEF0", "0x10000060: 12345678 9ABCDEF0  |xV4.....|"}) {
    INFO(text);
    Result<uint64_t> r = ParseDeviceIdText(text);
    REQUIRE(r.ok());
    CHECK(r.value() == id);
  }
  CHECK(FormatDeviceIdText(id) == "9ABCDEF012345678");
  CHECK(FormatDeviceIdWords(id) == "12345678 9ABCDEF0");
  // Short words are zero-extended on the left, as nrfjprog's words are numbers.
  CHECK(ParseDeviceIdText("1 2").value() == 0x0000000200000001ull);
}

TEST_CASE("Device ids: bad text is refused naming both orders", "[core]") {
  for (const char* bad : {"", "123", "9abcdef01234567g", "9abcdef0123456789", "123456789 1",
                          "12345678 9ABCDEF0 11", "0x12345678", "zz 11"}) {
    INFO(bad);
    Result<uint64_t> r = ParseDeviceIdText(bad);
    REQUIRE_FALSE(r.ok());
    CHECK(r.error().message == std::string("device id '") + bad +
                                   "': expected 16 hex digits, DEVICEID[1] then DEVICEID[0] (e.g. "
                                   "9ABCDEF012345678), or the two words `nrfjprog --memrd "
                                   "0x10000060 --n 8` prints, DEVICEID[0] then DEVICEID[1] (e.g. "
                                   "12345678 9ABCDEF0), with or without 0x");
  }
  Result<uint64_t> r = ParseDeviceIdText("0x10000080: 12345678 9ABCDEF0");
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().message ==
        "device id '0x10000080: 12345678 9ABCDEF0': the nrfjprog line reads 0x10000080:, not FICR "
        "DEVICEID at 0x10000060");
}

}  // namespace metro
