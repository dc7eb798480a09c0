// libFuzzer target: the Intel HEX reader (docs/calibration-blob.md section 8). Any text gives
// segments or an error with line and column; segments that were read must write back as
// Intel HEX that reads to the same segments (sorted, non-overlapping, 32-bit addresses).
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "metro/blob/intel_hex.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  auto segments = metro::blob::ReadIntelHex(text, "fuzz.hex");
  if (!segments.ok()) return 0;
  auto written = metro::blob::WriteIntelHex(segments.value());
  if (!written.ok()) __builtin_trap();
  auto again = metro::blob::ReadIntelHex(written.value(), "fuzz-rewritten.hex");
  if (!again.ok() || again.value().size() != segments.value().size()) __builtin_trap();
  for (size_t i = 0; i < segments.value().size(); ++i) {
    if (again.value()[i].address != segments.value()[i].address ||
        again.value()[i].bytes != segments.value()[i].bytes) {
      __builtin_trap();
    }
  }
  return 0;
}
