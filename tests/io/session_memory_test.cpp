// Freeing a loaded session's columns at the end of a run (ReleaseSessionSamples).
#include <unistd.h>

#include <catch2/catch.hpp>
#include <cstdint>
#include <cstdio>
#include <vector>

#include "io/session_internal.hpp"
#include "metro/io/session.hpp"
#include "metro/io/session_io.hpp"

namespace metro {
namespace {

// Resident memory of this process [bytes], from /proc/self/statm; -1 where there is none.
int64_t ResidentBytes() {
  std::FILE* f = std::fopen("/proc/self/statm", "r");
  if (f == nullptr) return -1;
  long long size = 0, resident = 0;
  const int read = std::fscanf(f, "%lld %lld", &size, &resident);
  std::fclose(f);
  return read == 2 ? resident * static_cast<int64_t>(sysconf(_SC_PAGESIZE)) : -1;
}

// A tag of `rows` rows, every column written (so its pages are resident).
Tag MakeTag(int sensor, size_t rows) {
  Tag tag;
  tag.sensor = sensor;
  tag.t_s.reserve(rows);  // Capacity = size: every page of each column is written.
  tag.line.reserve(rows);
  for (size_t i = 0; i < rows; ++i) {
    tag.t_s.push_back(0.01 * static_cast<double>(i));
    tag.line.push_back(static_cast<uint32_t>(i + 2));
  }
  for (const char* name : {"ax_g", "gx_dps"}) {
    Quantity q;
    q.name = name;
    q.values.assign(rows, 1.5);
    tag.quantities.push_back(std::move(q));
  }
  return tag;
}

TEST_CASE("A session's large columns go back to the system, small ones are left alone",
          "[io][memory]") {
  constexpr size_t kLarge = size_t{3} << 18;  // 786432 rows: 6 MB per column of doubles.
  Session session;
  session.tags.push_back(MakeTag(1, kLarge));
  session.tags.push_back(MakeTag(2, kLarge));
  session.tags.push_back(MakeTag(3, 1000));  // 8 kB columns: below the 1 MB threshold.
  // The whole pages inside each column of 1 MB or more, counted independently of the code.
  int64_t inside = 0;
  auto count = [&inside](const void* data, size_t bytes) {
    const uintptr_t begin = reinterpret_cast<uintptr_t>(data);
    const uintptr_t first = begin / 4096 + (begin % 4096 != 0 ? 1 : 0);
    const uintptr_t last = (begin + bytes) / 4096;
    if (bytes >= (size_t{1} << 20)) inside += static_cast<int64_t>(last - first) * 4096;
  };
  for (const Tag& tag : session.tags) {
    count(tag.t_s.data(), tag.t_s.capacity() * sizeof(double));
    count(tag.line.data(), tag.line.capacity() * sizeof(uint32_t));
    for (const Quantity& q : tag.quantities) count(q.values.data(), q.values.capacity() * 8);
  }
  REQUIRE(inside > int64_t{30} << 20);  // 2 tags x (3 x 6 MB + 3 MB), minus partial pages.

  const int64_t before = ResidentBytes();
  internal::ReturnColumnPages(&session, 2);
  const int64_t after = ResidentBytes();
  if (before >= 0) {
    // Everything inside went; nothing else this test holds is that large.
    CHECK(before - after >= inside - (int64_t{1} << 20));
  } else {
    WARN("no /proc/self/statm: resident memory not checked");
  }
  // The columns keep their sizes; the returned pages read as zeros (Linux), the small tag
  // and the values before a column's first whole page are untouched.
#ifdef __linux__
  for (size_t k = 0; k < 2; ++k) {
    const Tag& tag = session.tags[k];
    REQUIRE(tag.t_s.size() == kLarge);
    CHECK(tag.quantities[0].values[kLarge / 2] == 0.0);
    CHECK(tag.t_s[kLarge / 2] == 0.0);
    CHECK(tag.line[kLarge / 2] == 0u);
    CHECK(tag.quantities[1].values[0] == 1.5);
  }
#endif
  const Tag& small = session.tags[2];
  CHECK(small.t_s[999] == 0.01 * 999.0);
  CHECK(small.line[500] == 502u);
  CHECK(small.quantities[1].values[700] == 1.5);

  ReleaseSessionSamples(&session, 2);
  CHECK(session.tags.empty());
}

}  // namespace
}  // namespace metro
