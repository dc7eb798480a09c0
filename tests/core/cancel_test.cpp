// Cooperative cancellation (metro/core/cancel.hpp): the flag reaches ParallelFor's and
// RunBeside's threads, stops the items not yet started, and nothing is cancelled without it.
#include "metro/core/cancel.hpp"

#include <atomic>
#include <catch2/catch.hpp>
#include <vector>

#include "core/parallel.hpp"
#include "metro/noise/allan.hpp"

namespace metro {
namespace {

TEST_CASE("Without a ScopedCancel nothing is cancelled", "[core][cancel]") {
  CHECK(CurrentCancelFlag() == nullptr);
  CHECK_NOTHROW(ThrowIfCancelled());
  CancelFlag flag;
  flag.Cancel();  // Set, but installed nowhere.
  std::atomic<int> ran{0};
  internal::ParallelFor(100, 2, [&ran](size_t) { ran.fetch_add(1); });
  CHECK(ran.load() == 100);
}

TEST_CASE("ScopedCancel installs the flag for its scope and restores the one before",
          "[core][cancel]") {
  CancelFlag outer, inner;
  {
    ScopedCancel a(&outer);
    CHECK(CurrentCancelFlag() == &outer);
    {
      ScopedCancel b(&inner);
      CHECK(CurrentCancelFlag() == &inner);
      inner.Cancel();
      CHECK_THROWS_AS(ThrowIfCancelled(), Cancelled);
    }
    CHECK(CurrentCancelFlag() == &outer);
    CHECK_NOTHROW(ThrowIfCancelled());
  }
  CHECK(CurrentCancelFlag() == nullptr);
}

TEST_CASE("A flag set during ParallelFor stops the items not yet started, on every thread",
          "[core][cancel]") {
  for (int threads : {1, 2, 4}) {
    CancelFlag flag;
    ScopedCancel scope(&flag);
    std::atomic<int> ran{0};
    std::atomic<int> saw_flag_in_worker{0};
    CHECK_THROWS_AS(internal::ParallelFor(10000, threads,
                                          [&](size_t i) {
                                            if (CurrentCancelFlag() == &flag) {
                                              saw_flag_in_worker.fetch_add(1);
                                            }
                                            ran.fetch_add(1);
                                            if (i == 10) flag.Cancel();
                                          }),
                    Cancelled);
    // Each thread finishes the item it holds and starts no other (a few items may start
    // beside item 10 before it sets the flag); without the check all 10000 would run.
    CHECK(ran.load() < 200);
    CHECK(saw_flag_in_worker.load() == ran.load());
  }
}

TEST_CASE("RunBeside's second thread sees the caller's flag", "[core][cancel]") {
  CancelFlag flag;
  ScopedCancel scope(&flag);
  const CancelFlag* seen = nullptr;
  internal::RunBeside([&] { seen = CurrentCancelFlag(); }, [] {});
  CHECK(seen == &flag);
}

TEST_CASE("A cancelled Allan sweep throws Cancelled; an unset flag changes nothing",
          "[core][cancel]") {
  std::vector<double> y(200000);
  for (size_t i = 0; i < y.size(); ++i) y[i] = (i * 7919 % 1000) * 1e-3;  // Deterministic.
  AllanOptions options;
  options.taus = ParseTauSpacing("all").value();
  const Result<AllanCurve> plain = ComputeAllan(y, 0.01, options);
  REQUIRE(plain.ok());
  CancelFlag flag;
  {
    ScopedCancel scope(&flag);
    const Result<AllanCurve> with_flag = ComputeAllan(y, 0.01, options);
    REQUIRE(with_flag.ok());
    CHECK(with_flag.value().dev == plain.value().dev);
    flag.Cancel();
    CHECK_THROWS_AS(ComputeAllan(y, 0.01, options), Cancelled);
  }
}

}  // namespace
}  // namespace metro
