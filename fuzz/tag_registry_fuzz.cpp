// libFuzzer target: the tag registry (`--tag-registry FILE`, a JSON object {"1": "Forehead",
// ...}). Any file must give a registry or an error naming it, never a crash; a registry
// answers any sensor number (an empty name in the file stays empty).
#include <cstddef>
#include <cstdint>

#include "fuzz_input.hpp"
#include "metro/io/tag_registry.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string& path = metro_fuzz::WriteInput(data, size, "registry.json");
  metro::Result<metro::TagRegistry> registry = metro::TagRegistry::Load(path);
  if (!registry.ok()) return 0;
  for (int sensor : {-1, 0, 1, 2, 15, 16, 255, 256}) {
    (void)registry.value().Name(sensor);
  }
  return 0;
}
