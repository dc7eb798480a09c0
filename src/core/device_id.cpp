#include "metro/core/device_id.hpp"

#include <fmt/format.h>

#include <cctype>
#include <vector>

namespace metro {
namespace {

bool IsHex(std::string_view s) {
  if (s.empty()) return false;
  for (char ch : s) {
    if (std::isxdigit(static_cast<unsigned char>(ch)) == 0) return false;
  }
  return true;
}

std::string_view StripHexPrefix(std::string_view s) {
  if (s.size() > 2 && s[0] == '0' && (s[1] == 'x' || s[1] == 'X')) s.remove_prefix(2);
  return s;
}

uint64_t HexValue(std::string_view s) {
  uint64_t v = 0;
  for (char ch : s) {
    const int c = std::tolower(static_cast<unsigned char>(ch));
    v = v << 4 | static_cast<uint64_t>(c <= '9' ? c - '0' : c - 'a' + 10);
  }
  return v;
}

}  // namespace

Result<uint64_t> ParseDeviceIdText(std::string_view text) {
  auto fail = [&]() -> Result<uint64_t> {
    return MakeError(fmt::format(
        "device id '{}': expected 16 hex digits, DEVICEID[1] then DEVICEID[0] (e.g. "
        "9ABCDEF012345678), or the two words `nrfjprog --memrd 0x10000060 --n 8` prints, "
        "DEVICEID[0] then DEVICEID[1] (e.g. 12345678 9ABCDEF0), with or without 0x",
        text));
  };
  std::string_view s = text;
  // nrfjprog's ASCII column, "|xV4.....|", at the end of its line.
  if (const size_t bar = s.find('|'); bar != std::string_view::npos) s = s.substr(0, bar);
  std::vector<std::string_view> words;
  size_t i = 0;
  while (i < s.size()) {
    while (i < s.size() && (s[i] == ' ' || s[i] == '\t' || s[i] == ',')) ++i;
    size_t j = i;
    while (j < s.size() && s[j] != ' ' && s[j] != '\t' && s[j] != ',') ++j;
    if (j > i) words.push_back(s.substr(i, j - i));
    i = j;
  }
  // nrfjprog's address, "0x10000060:".
  if (!words.empty() && words.front().back() == ':') {
    const std::string_view address =
        StripHexPrefix(words.front().substr(0, words.front().size() - 1));
    if (!IsHex(address) || address.size() > 8 || HexValue(address) != kFicrDeviceIdAddress) {
      return MakeError(
          fmt::format("device id '{}': the nrfjprog line reads {}, not FICR DEVICEID at 0x{:08X}",
                      text, words.front(), kFicrDeviceIdAddress));
    }
    words.erase(words.begin());
  }
  if (words.size() == 1) {
    const std::string_view hex = StripHexPrefix(words[0]);
    if (hex.size() != 16 || !IsHex(hex)) return fail();
    return HexValue(hex);
  }
  if (words.size() == 2) {
    const std::string_view lo = StripHexPrefix(words[0]), hi = StripHexPrefix(words[1]);
    if (lo.size() > 8 || hi.size() > 8 || !IsHex(lo) || !IsHex(hi)) return fail();
    return HexValue(hi) << 32 | HexValue(lo);
  }
  return fail();
}

std::string FormatDeviceIdText(uint64_t device_id) { return fmt::format("{:016X}", device_id); }

std::string FormatDeviceIdWords(uint64_t device_id) {
  return fmt::format("{:08X} {:08X}", device_id & 0xFFFFFFFFu, device_id >> 32);
}

}  // namespace metro
