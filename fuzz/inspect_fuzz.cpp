// libFuzzer target: `calibrate inspect FILE` of a .bin blob or a .hex programmer image
// (InspectFile chooses by the first non-blank character), with the firmware's own validator
// compiled in. Every outcome is rendered as text and JSON, as the command does. The .bin
// path is also taken directly (InspectBin), so a text that starts with ':' is still tried
// as a blob.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "fuzz_input.hpp"
#include "metro/blob/inspect.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  metro::blob::InspectOptions options;
  const std::string& path = metro_fuzz::WriteInput(data, size, "tag.img");
  auto report = metro::blob::InspectFile(path, options);
  if (report.ok()) {
    (void)metro::blob::FormatInspect(report.value());
    (void)metro::blob::ToJson(report.value());
  }
  const std::vector<uint8_t> bytes(data, data + size);
  metro::blob::InspectReport bin = metro::blob::InspectBin(bytes, options);
  (void)metro::blob::FormatInspect(bin);
  (void)metro::blob::ToJson(bin);
  return 0;
}
