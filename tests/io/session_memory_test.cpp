// Sessions and memory: freeing a loaded session's columns at the end of a run
// (Session::~Session), and loading a session that does not fit in the memory allowed.
#include <fmt/format.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <catch2/catch.hpp>
#include <cstdint>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "io/session_internal.hpp"
#include "metro/io/session.hpp"
#include "metro/io/session_io.hpp"
#include "support/allocation_limit.hpp"
#include "support/sanitizer.hpp"
#include "support/temp_file.hpp"

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
    // Everything inside went (give or take what the process did meanwhile: a sanitizer's
    // bookkeeping, the list of pages); nothing else this test holds is that large.
    CHECK(before - after >= inside / 10 * 9);
  } else {
    WARN("no /proc/self/statm: resident memory not checked");
  }
  // The columns keep their sizes; the returned pages read as zeros (Linux), the small tag
  // and the values outside a column's whole pages are untouched.
#ifdef __linux__
  for (size_t k = 0; k < 2; ++k) {
    const Tag& tag = session.tags[k];
    REQUIRE(tag.t_s.size() == kLarge);
    CHECK(tag.quantities[0].values[kLarge / 2] == 0.0);
    CHECK(tag.t_s[kLarge / 2] == 0.0);
    CHECK(tag.line[kLarge / 2] == 0u);
    const std::vector<double>& v = tag.quantities[1].values;
    const uintptr_t begin = reinterpret_cast<uintptr_t>(v.data());
    const size_t head = ((4096 - begin % 4096) % 4096) / sizeof(double);  // Before page 1.
    const size_t tail = (begin + v.size() * sizeof(double)) % 4096 / sizeof(double);
    if (head > 0) CHECK(v[head - 1] == 1.5);
    if (head < v.size()) CHECK(v[head] == 0.0);
    if (tail > 0) CHECK(v[v.size() - tail] == 1.5);
  }
#endif
  const Tag& small = session.tags[2];
  CHECK(small.t_s[999] == 0.01 * 999.0);
  CHECK(small.line[500] == 502u);
  CHECK(small.quantities[1].values[700] == 1.5);
}

// The outcome of loading `path` in a child process whose address space is limited to its
// size at the fork plus `extra_bytes`: 'L' loaded, 'M' the out-of-memory error naming the
// file, 'E' another error naming the file (the file could not be mapped), 'X' any other
// error, 'T' an exception out of LoadSession, 'C' a crash (a signal, std::terminate).
[[maybe_unused]] char LoadUnderLimit(const std::string& path, const LoadOptions& options,
                                     int64_t extra_bytes) {
  const pid_t pid = fork();
  if (pid == 0) {
    long long size_pages = 0;
    std::FILE* f = std::fopen("/proc/self/statm", "r");
    if (f == nullptr || std::fscanf(f, "%lld", &size_pages) != 1) _exit(3);
    std::fclose(f);
    const rlim_t limit = static_cast<rlim_t>(size_pages * sysconf(_SC_PAGESIZE) + extra_bytes);
    const rlimit as{limit, limit};
    if (setrlimit(RLIMIT_AS, &as) != 0) _exit(3);
    try {
      const Result<Session> session = LoadSession(path, options);
      if (session.ok()) _exit(0);
      const Error& e = session.error();
      if (e.file != path) _exit(4);
      _exit(e.message.find("out of memory") != std::string::npos ? 1 : 2);
    } catch (...) {
      _exit(5);  // Never back into the test framework in the child.
    }
  }
  int status = 0;
  if (pid < 0 || waitpid(pid, &status, 0) != pid) return '?';
  if (!WIFEXITED(status)) return 'C';
  switch (WEXITSTATUS(status)) {
    case 0:
      return 'L';
    case 1:
      return 'M';
    case 2:
      return 'E';
    case 4:
      return 'X';
    case 5:
      return 'T';
    default:
      return '?';
  }
}

TEST_CASE("Loads under address-space limits end in a session or an error, never a crash",
          "[io][memory]") {
#if METRO_UNDER_SANITIZER || !defined(__linux__)
  WARN("not run here: the sanitizers reserve terabytes of address space (RLIMIT_AS)");
#else
  // 12 MB of short rows (3.4 x as many bytes of columns as of text, so that the columns
  // dominate whatever free heap the test process has), 15 tags; and the same with one
  // malformed row, which only the general loader (--lenient) takes.
  std::string text = "t_s,sensor,ax_lsb,ay_lsb,az_lsb,gx_lsb,gy_lsb,gz_lsb,temp_c\n";
  std::mt19937 rng(5);
  std::uniform_int_distribution<int> lsb(-9, 9);
  for (int i = 0; i < 600000; ++i) {
    text += fmt::format("{},{},{},{},{},{},{},{},{}\n", i / 15, 1 + i % 15, lsb(rng), lsb(rng),
                        lsb(rng), lsb(rng), lsb(rng), lsb(rng), 25 + i % 3);
  }
  testing::TempFile clean(text);
  testing::TempFile bad(text + "not,a,row\n");
  // From less than the file's own size to plenty: every load either succeeds or returns an
  // error naming the file (out of memory, or the file could not be mapped); the loosest
  // loads. The limits are only roughly the memory left (the process at the fork may hold
  // much free heap, and a second thread allocates in its own arena), so which limits fail
  // is not asserted here; the test below fails allocations deterministically.
  struct Case {
    const char* name;
    const std::string* path;
    bool lenient;
    int threads;
  };
  const std::string clean_path = clean.path(), bad_path = bad.path();
  for (const Case& c : {Case{"clean path, 1 thread", &clean_path, false, 1},
                        Case{"clean path, 2 threads", &clean_path, false, 2},
                        Case{"general loader, 2 threads", &bad_path, true, 2}}) {
    LoadOptions options;
    options.lenient = c.lenient;
    options.threads = c.threads;
    std::string outcomes;
    for (int64_t mb : {0, 8, 16, 20, 24, 28, 32, 40, 48, 64, 96, 160, 256}) {
      outcomes += LoadUnderLimit(*c.path, options, mb << 20);
    }
    INFO(c.name << ": outcomes by limit, +0 to +256 MB: " << outcomes);
    CHECK(outcomes.find_first_not_of("LME") == std::string::npos);
    CHECK(outcomes.back() == 'L');
  }
#endif
}

// 'L' loaded, 'M' the out-of-memory error naming the file, 'E' another error, 'T' an
// exception out of LoadSession, with operator new refusing requests over `max_bytes`.
char LoadWithAllocationLimit(const std::string& path, const LoadOptions& options, size_t max_bytes,
                             Session* loaded = nullptr) {
  try {
    Result<Session> session = [&] {
      testing::AllocationLimit limit(max_bytes);
      return LoadSession(path, options);
    }();
    if (session.ok()) {
      if (loaded != nullptr) *loaded = std::move(session).value();
      return 'L';
    }
    const Error& e = session.error();
    return e.file == path && e.message.find("out of memory") != std::string::npos ? 'M' : 'E';
  } catch (...) {
    return 'T';
  }
}

TEST_CASE("A session whose columns cannot be allocated fails with a clear error", "[io][memory]") {
  if (!testing::AllocationLimit::Available()) {
    WARN("not run here: the sanitizers keep their own operator new");
    return;
  }
  // 600 k short rows of 15 tags (columns of 40 k values, 320 kB), and the same with one
  // malformed row, which only the general loader (--lenient) takes.
  std::string text = "t_s,sensor,ax_lsb,ay_lsb,az_lsb,gx_lsb,gy_lsb,gz_lsb,temp_c\n";
  for (int i = 0; i < 600000; ++i) {
    text += fmt::format("{},{},{},{},{},{},{},{},{}\n", i / 15, 1 + i % 15, i % 7, i % 5, i % 3,
                        -(i % 11), i % 13, i % 2, 25 + i % 3);
  }
  testing::TempFile clean(text);
  testing::TempFile bad(text + "not,a,row\n");
  for (int threads : {1, 2}) {
    LoadOptions options;
    options.threads = threads;
    std::string outcomes;
    for (size_t max : {size_t{64} << 10, size_t{256} << 10, size_t{64} << 20}) {
      outcomes += LoadWithAllocationLimit(clean.path(), options, max);
      options.lenient = true;
      outcomes += LoadWithAllocationLimit(bad.path(), options, max);
      options.lenient = false;
    }
    INFO(threads << " threads: clean, general at 64 kB, 256 kB, 64 MB: " << outcomes);
    CHECK(outcomes == "MMMMLL");
  }
}

TEST_CASE("A column reservation the system refuses falls back to growing as it fills",
          "[io][memory]") {
  if (!testing::AllocationLimit::Available()) {
    WARN("not run here: the sanitizers keep their own operator new");
    return;
  }
  // Tag 1 alone for the first 30 k rows, then 15 tags in turn: the clean path reserves tag 1
  // for as many rows as the whole file would hold at its first block's rate (about 5 MB a
  // column), though it ends with 68 k rows (544 kB a column).
  std::string text = "t_s,sensor,ax_lsb,ay_lsb,az_lsb\n";
  std::array<int, 16> count{};
  for (int i = 0; i < 600000; ++i) {
    const int sensor = i < 30000 ? 1 : 1 + i % 15;
    text += fmt::format("{},{},{},{},{}\n", count[static_cast<size_t>(sensor)]++, sensor, i % 7,
                        -(i % 5), i % 3);
  }
  testing::TempFile file(text);
  const int64_t clean_before = internal::CleanPathLoads();
  Session limited;
  CHECK(LoadWithAllocationLimit(file.path(), LoadOptions{}, size_t{2} << 20, &limited) == 'L');
  CHECK(internal::CleanPathLoads() == clean_before + 1);  // Through the clean path.
  const Result<Session> unlimited = LoadSession(file.path());
  REQUIRE(unlimited.ok());
  REQUIRE(limited.tags.size() == 15);
  CHECK(limited.tags[0].size() == 68000);
  for (size_t k = 0; k < 15; ++k) {
    const Tag& a = limited.tags[k];
    const Tag& b = unlimited.value().tags[k];
    CHECK(a.t_s == b.t_s);
    CHECK(a.line == b.line);
    for (size_t q = 0; q < 3; ++q) CHECK(a.quantities[q].values == b.quantities[q].values);
  }
}

}  // namespace
}  // namespace metro
