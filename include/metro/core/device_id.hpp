// The nRF51 tag's device ID (FICR DEVICEID, two 32-bit words at 0x10000060 and 0x10000064) as
// text: what `calibrate blob|push|inspect --device-id`, tags files and calibration.json accept.
//
//   device_id = (uint64_t(DEVICEID[1]) << 32) | DEVICEID[0]
//
// Accepted spellings of the same ID (docs/calibration-blob.md section 1.1):
//   "9ABCDEF012345678"      16 hex digits, DEVICEID[1] then DEVICEID[0] (as metro prints it);
//   "0x9ABCDEF012345678"    the same with 0x;
//   "12345678 9ABCDEF0"     two words, DEVICEID[0] then DEVICEID[1]: the order
//                           `nrfjprog --memrd 0x10000060 --n 8` prints them (low address first),
//                           each with or without 0x, separated by spaces, a tab or a comma;
//   "0x10000060: 12345678 9ABCDEF0  |xV4.....|"   nrfjprog's whole line (address and ASCII
//                           column ignored; the address must be 0x10000060).
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

#include "metro/core/status.hpp"

namespace metro {

// FICR DEVICEID[0]'s address on the nRF51 (nRF51 Series Reference Manual v3.0, 8.1 FICR).
inline constexpr uint32_t kFicrDeviceIdAddress = 0x10000060u;

// Errors: "device id 'TEXT': expected ..." naming both accepted orders.
Result<uint64_t> ParseDeviceIdText(std::string_view text);
// "9ABCDEF012345678": 16 upper-case hex digits, DEVICEID[1] then DEVICEID[0].
std::string FormatDeviceIdText(uint64_t device_id);
// "12345678 9ABCDEF0": the two words as nrfjprog --memrd prints them (DEVICEID[0] first).
std::string FormatDeviceIdWords(uint64_t device_id);

}  // namespace metro
