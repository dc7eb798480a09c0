// libFuzzer target: the calibration registry (`--registry FILE`, METRO_REGISTRY; a SQLite
// file, docs/registry.md). Any file must give a registry or an error naming it, never a crash,
// an escaped exception or a loop: it is opened for the queries (read-only) and queried, then
// opened for recording (which creates or migrates what it may) and read back.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <string>

#include "fuzz_input.hpp"
#include "metro/registry/registry.hpp"

namespace {

constexpr uint64_t kDevice = 0x9ABCDEF012345678ull;  // The seeds' device.

void Query(metro::Registry& r) {
  (void)r.All();
  (void)r.History(kDevice);
  (void)r.Drift(kDevice);
  (void)r.Due(365.0, "2030-01-01T00:00:00Z", /*all=*/true);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string& path = metro_fuzz::WriteInput(data, size, "registry.sqlite");
  // SQLite's files beside the previous input are not this one's.
  std::remove((path + "-wal").c_str());
  std::remove((path + "-shm").c_str());
  {
    metro::Result<std::unique_ptr<metro::Registry>> q = metro::Registry::OpenForQuery(path);
    if (q.ok()) Query(*q.value());
  }
  {
    metro::Result<std::unique_ptr<metro::Registry>> w = metro::Registry::Open(path);
    if (w.ok()) Query(*w.value());
  }
  std::remove((path + "-wal").c_str());
  std::remove((path + "-shm").c_str());
  return 0;
}
