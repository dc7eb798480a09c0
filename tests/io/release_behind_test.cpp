#include "io/release_behind.hpp"

#include <algorithm>
#include <atomic>
#include <catch2/catch.hpp>
#include <chrono>
#include <mutex>
#include <numeric>
#include <random>
#include <thread>
#include <utility>
#include <vector>

namespace metro::internal {
namespace {

using Ranges = std::vector<std::pair<size_t, size_t>>;

// Records every release; ranges must be consecutive from 0 within a pass.
struct Recorder {
  std::mutex mutex;
  Ranges ranges;
  std::function<void(size_t, size_t)> Callback() {
    return [this](size_t b, size_t e) {
      std::lock_guard<std::mutex> lock(mutex);
      ranges.emplace_back(b, e);
    };
  }
  size_t ReleasedTo() const { return ranges.empty() ? 0 : ranges.back().second; }
};

// A ReleaseBehind recording its releases, with a pass started.
struct Tracked {
  Tracked(bool hashing, size_t max_gap_bytes, const std::vector<size_t>& begins,
          const std::vector<size_t>& ends)
      : release(r.Callback(), hashing, max_gap_bytes) {
    release.StartPass(begins, ends);
  }
  Recorder r;
  ReleaseBehind release;
};

// Blocks [10, 20), [20, 35), [35, 50) after a 10-byte header; the file is 50 bytes.
const std::vector<size_t> kBegins = {10, 20, 35};
const std::vector<size_t> kEnds = {20, 35, 50};

TEST_CASE("Pages go once the parser and the hasher are both past them", "[io][release]") {
  SECTION("hasher ahead: the parser's contiguous prefix decides") {
    Tracked t(true, 1000, kBegins, kEnds);
    CHECK(t.r.ranges.empty());  // The hasher has not passed the header yet.
    t.release.Hashed(50);
    CHECK(t.r.ranges == Ranges{{0, 10}});  // The header is behind both.
    t.release.BlockDone(1);                // Out of order: block 0 still in flight.
    CHECK(t.r.ReleasedTo() == 10);
    t.release.BlockDone(0);
    CHECK(t.r.ranges == Ranges{{0, 10}, {10, 35}});
    t.release.BlockDone(2);
    CHECK(t.r.ranges == Ranges{{0, 10}, {10, 35}, {35, 50}});
  }
  SECTION("parser ahead: the hasher's progress decides") {
    Tracked t(true, 1000, kBegins, kEnds);
    for (size_t i = 0; i < 3; ++i) t.release.BlockDone(i);
    CHECK(t.r.ranges.empty());  // Nothing hashed: the slow hasher still needs every page.
    t.release.Hashed(4);
    t.release.Hashed(4);  // No progress, no t.release.
    t.release.Hashed(27);
    CHECK(t.r.ranges == Ranges{{0, 4}, {4, 27}});
    t.release.Hashed(50);
    CHECK(t.r.ReleasedTo() == 50);
  }
  SECTION("without a hasher the parser alone decides") {
    Tracked t(false, 1000, kBegins, kEnds);
    CHECK(t.r.ranges == Ranges{{0, 10}});
    t.release.BlockDone(2);
    t.release.BlockDone(0);
    CHECK(t.r.ReleasedTo() == 20);
  }
  SECTION("a second pass reads the pages again and releases them again") {
    Tracked t(false, 1000, kBegins, kEnds);
    t.release.BlockDone(0);
    CHECK(t.r.ReleasedTo() == 20);
    t.release.StartPass(kBegins, kEnds);  // The general loader after the clean path gave up.
    t.release.BlockDone(1);
    t.release.BlockDone(0);
    CHECK(t.r.ranges == Ranges{{0, 10}, {10, 20}, {0, 10}, {10, 35}});
  }
}

TEST_CASE("Pages far ahead of the trailing reader go behind the leader", "[io][release]") {
  // Ten 100-byte blocks, no header; at most 250 bytes kept ahead of the trailing reader.
  std::vector<size_t> begins, ends;
  for (size_t b = 0; b < 1000; b += 100) {
    begins.push_back(b);
    ends.push_back(b + 100);
  }
  SECTION("a slow hasher") {
    Tracked t(true, 250, begins, ends);
    for (size_t i = 0; i < 6; ++i) t.release.BlockDone(i);
    CHECK(t.r.ranges == Ranges{{250, 300}, {300, 400}, {400, 500}, {500, 600}});
    t.release.Hashed(100);  // Behind both now: [0, 100); [350, 600) is already gone.
    t.release.BlockDone(6);
    t.release.Hashed(700);  // The hasher mapped [250, 700) again; it goes again.
    CHECK(t.r.ranges ==
          Ranges{{250, 300}, {300, 400}, {400, 500}, {500, 600}, {0, 100}, {600, 700}, {100, 700}});
  }
  SECTION("a fast hasher releases nothing ahead of the parser") {
    Tracked t(true, 250, begins, ends);
    t.release.Hashed(1000);
    CHECK(t.r.ranges.empty());
    t.release.BlockDone(0);
    CHECK(t.r.ranges == Ranges{{0, 100}});
  }
  SECTION("no hasher: the parser alone, nothing released ahead of it") {
    Tracked t(false, 250, begins, ends);
    t.release.BlockDone(0);
    t.release.BlockDone(1);
    CHECK(t.r.ranges == Ranges{{0, 100}, {100, 200}});
  }
}

TEST_CASE("Concurrent parser blocks and hasher release every byte", "[io][release]") {
  constexpr size_t kBlocks = 200;
  std::vector<size_t> begins(kBlocks), ends(kBlocks);
  for (size_t i = 0; i < kBlocks; ++i) {
    begins[i] = 100 + i * 1000;
    ends[i] = begins[i] + 1000;
  }
  const size_t size = ends.back();
  for (int trial = 0; trial < 20; ++trial) {
    Tracked t(true, trial % 2 == 0 ? size : 5000, begins, ends);
    std::vector<size_t> order(kBlocks);
    std::iota(order.begin(), order.end(), size_t{0});
    std::mt19937 rng(static_cast<unsigned>(trial));
    std::shuffle(order.begin(), order.end(), rng);
    std::thread parser_a([&] {
      for (size_t k = 0; k < kBlocks; k += 2) t.release.BlockDone(order[k]);
    });
    std::thread parser_b([&] {
      for (size_t k = 1; k < kBlocks; k += 2) t.release.BlockDone(order[k]);
    });
    std::thread hasher([&] {
      for (size_t n = 333; n < size; n += 333) t.release.Hashed(n);
      t.release.Hashed(size);
    });
    parser_a.join();
    parser_b.join();
    hasher.join();
    Ranges sorted = t.r.ranges;
    std::sort(sorted.begin(), sorted.end());
    size_t covered = 0;
    for (const auto& [b, e] : sorted) {
      CHECK(b <= covered);  // No gap.
      CHECK(e > b);
      covered = std::max(covered, e);
    }
    CHECK(covered == size);
    if (trial % 2 == 0) {  // No gap limit: every byte goes exactly once, behind both.
      for (size_t k = 1; k < sorted.size(); ++k) CHECK(sorted[k].first == sorted[k - 1].second);
    }
  }
}

}  // namespace
}  // namespace metro::internal
