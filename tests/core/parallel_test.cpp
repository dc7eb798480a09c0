// The library's private parallel helpers: exceptions from worker threads reach the caller.
#include "core/parallel.hpp"

#include <atomic>
#include <catch2/catch.hpp>
#include <new>
#include <stdexcept>
#include <vector>

namespace metro::internal {
namespace {

TEST_CASE("ParallelFor runs every item once", "[core][parallel]") {
  for (int threads : {1, 2, 7}) {
    std::vector<std::atomic<int>> runs(1000);
    ParallelFor(runs.size(), threads, [&runs](size_t i) { runs[i].fetch_add(1); });
    for (const std::atomic<int>& r : runs) CHECK(r.load() == 1);
  }
}

TEST_CASE("An exception in ParallelFor's items reaches the caller and stops the others",
          "[core][parallel]") {
  SECTION("one thread: the items after the failing one are not run") {
    std::vector<int> ran;
    CHECK_THROWS_AS(ParallelFor(100, 1,
                                [&ran](size_t i) {
                                  ran.push_back(static_cast<int>(i));
                                  if (i == 5) throw std::bad_alloc();
                                }),
                    std::bad_alloc);
    CHECK(ran == std::vector<int>{0, 1, 2, 3, 4, 5});
  }
  SECTION("several threads: the first exception, after every thread has finished") {
    std::atomic<int> ran{0};
    CHECK_THROWS_AS(ParallelFor(100000, 4,
                                [&ran](size_t i) {
                                  ran.fetch_add(1);
                                  if (i == 10) throw std::runtime_error("item 10");
                                }),
                    std::runtime_error);
    // Each thread stops at its next item: far fewer than all were run.
    CHECK(ran.load() < 100000);
  }
}

TEST_CASE("RunBeside runs both, then rethrows the caller's exception first", "[core][parallel]") {
  std::atomic<int> beside{0}, here{0};
  auto run = [&](bool beside_throws, bool here_throws) {
    beside = here = 0;
    RunBeside(
        [&] {
          beside = 1;
          if (beside_throws) throw std::runtime_error("beside");
        },
        [&] {
          here = 1;
          if (here_throws) throw std::runtime_error("here");
        });
  };
  CHECK_NOTHROW(run(false, false));
  CHECK((beside == 1 && here == 1));
  CHECK_THROWS_WITH(run(true, false), "beside");
  CHECK((beside == 1 && here == 1));
  CHECK_THROWS_WITH(run(false, true), "here");
  CHECK((beside == 1 && here == 1));
  CHECK_THROWS_WITH(run(true, true), "here");
  CHECK((beside == 1 && here == 1));
}

}  // namespace
}  // namespace metro::internal
