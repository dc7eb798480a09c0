// The library's private parallel helpers: exceptions from worker threads reach the caller.
#include "core/parallel.hpp"

#include <atomic>
#include <catch2/catch.hpp>
#include <chrono>
#include <new>
#include <stdexcept>
#include <thread>
#include <utility>
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
    // Item 10 throws; every later item waits until it has thrown and then takes 100 us, so no
    // later item finishes first however the threads are scheduled. Once the exception has
    // reached ParallelFor no further item is handed out: the other threads run only the items
    // they take while it unwinds (well under a second, a few thousand items at most). Without
    // the stop they would run all 100000 (checked by removing it).
    std::atomic<int> ran{0};
    std::atomic<bool> thrown{false};
    CHECK_THROWS_AS(
        ParallelFor(100000, 4,
                    [&ran, &thrown](size_t i) {
                      if (i > 10) {
                        const auto give_up =
                            std::chrono::steady_clock::now() + std::chrono::seconds(10);
                        while (!thrown.load() && std::chrono::steady_clock::now() < give_up) {
                          std::this_thread::yield();
                        }
                        std::this_thread::sleep_for(std::chrono::microseconds(100));
                      }
                      ran.fetch_add(1);
                      if (i == 10) {
                        thrown.store(true);
                        throw std::runtime_error("item 10");
                      }
                    }),
        std::runtime_error);
    CHECK(ran.load() < 50000);
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

TEST_CASE("ParallelSlices covers 0 to n in contiguous slices and rethrows", "[core][parallel]") {
  for (int threads : {1, 2, 3, 7}) {
    std::vector<int> seen(100, 0);
    std::vector<std::pair<int64_t, int64_t>> ranges(static_cast<size_t>(threads));
    ParallelSlices(threads, 100, [&](int64_t lo, int64_t hi, int slice) {
      ranges[static_cast<size_t>(slice)] = {lo, hi};
      for (int64_t i = lo; i < hi; ++i) ++seen[static_cast<size_t>(i)];
    });
    for (int v : seen) CHECK(v == 1);
    // Slice t is [100 t / threads, 100 (t + 1) / threads).
    for (int t = 0; t < threads; ++t) {
      CHECK(ranges[static_cast<size_t>(t)].first == 100 * t / threads);
      CHECK(ranges[static_cast<size_t>(t)].second == 100 * (t + 1) / threads);
    }
  }
  CHECK_THROWS_WITH(ParallelSlices(4, 100,
                                   [](int64_t lo, int64_t, int) {
                                     if (lo > 0) throw std::runtime_error("slice");
                                   }),
                    "slice");
}

}  // namespace
}  // namespace metro::internal
