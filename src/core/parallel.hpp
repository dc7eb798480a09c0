// Private helpers for the library's parallel loops and large buffers.
#pragma once

#include <sys/mman.h>

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <thread>
#include <vector>

namespace metro::internal {

// Worker threads for `threads` (0 or less: all cores), at least 1.
inline int ResolveThreads(int threads) {
  if (threads > 0) return threads;
  return std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
}

// Runs fn(i) for every i in [0, n), items handed out one at a time to up to
// ResolveThreads(threads) threads; the calling thread is one of them. fn must not throw.
template <typename Fn>
void ParallelFor(size_t n, int threads, Fn&& fn) {
  std::atomic<size_t> next{0};
  auto worker = [&] {
    for (size_t i = next.fetch_add(1); i < n; i = next.fetch_add(1)) fn(i);
  };
  const size_t workers = std::min(static_cast<size_t>(ResolveThreads(threads)), n);
  std::vector<std::thread> pool;
  for (size_t k = 1; k < workers; ++k) pool.emplace_back(worker);
  worker();
  for (std::thread& t : pool) t.join();
}

// Asks for transparent huge pages on the whole 2 MiB pages inside [p, p + bytes) (Linux
// with THP in "madvise" mode; elsewhere nothing): a buffer of tens of MB written once then
// faults in 2 MiB at a time instead of 4 KiB. Advice only; failures are ignored.
inline void AdviseHugePages(const void* p, size_t bytes) {
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  constexpr uintptr_t kHuge = uintptr_t{2} << 20;
  const uintptr_t begin = reinterpret_cast<uintptr_t>(p);
  const uintptr_t lo = (begin + kHuge - 1) & ~(kHuge - 1);
  const uintptr_t hi = (begin + bytes) & ~(kHuge - 1);
  if (hi > lo) ::madvise(reinterpret_cast<void*>(lo), hi - lo, MADV_HUGEPAGE);
#else
  (void)p;
  (void)bytes;
#endif
}

}  // namespace metro::internal
