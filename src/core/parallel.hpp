// Private helpers for the library's parallel loops and large buffers.
#pragma once

#include <sys/mman.h>

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

#include "metro/core/cancel.hpp"

namespace metro::internal {

// Worker threads for `threads` (0 or less: all cores), at least 1.
inline int ResolveThreads(int threads) {
  if (threads > 0) return threads;
  return std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
}

// Runs fn() on `threads` threads at once (at least 1; the calling thread is one of them) and
// returns once every one has finished. If fn throws (say std::bad_alloc on a session too
// large for the machine), `on_failure()` runs in the throwing thread, to stop the others,
// and the first exception is rethrown in the calling thread once every thread has finished:
// an exception leaving a std::thread would end the process. A thread that cannot be
// started leaves its share of the work to the others. The caller's CancelFlag
// (metro/core/cancel.hpp) is installed in every thread.
template <typename Fn, typename OnFailure>
void RunOnThreads(size_t threads, Fn&& fn, OnFailure&& on_failure) {
  std::mutex failure_mutex;
  std::exception_ptr failure;
  const CancelFlag* cancel = CurrentCancelFlag();
  auto guarded = [&] {
    ScopedCancel scope(cancel);
    try {
      fn();
    } catch (...) {
      on_failure();
      std::lock_guard<std::mutex> lock(failure_mutex);
      if (failure == nullptr) failure = std::current_exception();
    }
  };
  std::vector<std::thread> pool;
  try {
    for (size_t k = 1; k < threads; ++k) pool.emplace_back(guarded);
  } catch (...) {
    // No more threads to be had (std::system_error).
  }
  guarded();
  for (std::thread& t : pool) t.join();
  if (failure != nullptr) std::rethrow_exception(failure);
}

// Runs fn(i) for every i in [0, n), items handed out one at a time to up to
// ResolveThreads(threads) threads (RunOnThreads); once an item throws, no further items
// are handed out, and the exception reaches the caller. Each item first checks the caller's
// CancelFlag (ThrowIfCancelled).
template <typename Fn>
void ParallelFor(size_t n, int threads, Fn&& fn) {
  std::atomic<size_t> next{0};
  RunOnThreads(
      std::min(static_cast<size_t>(ResolveThreads(threads)), n),
      [&] {
        for (size_t i = next.fetch_add(1); i < n; i = next.fetch_add(1)) {
          ThrowIfCancelled();
          fn(i);
        }
      },
      [&] { next.store(n); });
}

// Runs fn(lo, hi, slice) on `threads` contiguous slices [n t / threads, n (t + 1) / threads)
// of [0, n), one slice per thread (ParallelFor, so an exception reaches the caller); on one
// thread, or n < 2, fn(0, n, 0) here.
template <typename Fn>
void ParallelSlices(int threads, int64_t n, Fn&& fn) {
  if (threads <= 1 || n < 2) {
    fn(int64_t{0}, n, 0);
    return;
  }
  ParallelFor(static_cast<size_t>(threads), threads, [&](size_t t) {
    const int64_t ti = static_cast<int64_t>(t);
    fn(n * ti / threads, n * (ti + 1) / threads, static_cast<int>(t));
  });
}

// Runs `beside` on a second thread while the calling thread runs `here`, and returns once
// both are done. An exception from either is rethrown here after both have finished (the
// one from `here` first), never left to end the process from a thread; if no thread can be
// started, `beside` runs after `here` on this thread. The caller's CancelFlag is installed
// in the second thread.
template <typename Beside, typename Here>
void RunBeside(Beside&& beside, Here&& here) {
  std::exception_ptr beside_failure;
  const CancelFlag* cancel = CurrentCancelFlag();
  auto run_beside = [&] {
    ScopedCancel scope(cancel);
    try {
      beside();
    } catch (...) {
      beside_failure = std::current_exception();
    }
  };
  std::thread thread;
  try {
    thread = std::thread(run_beside);
  } catch (...) {
  }
  std::exception_ptr here_failure;
  try {
    here();
  } catch (...) {
    here_failure = std::current_exception();
  }
  if (thread.joinable()) {
    thread.join();
  } else {
    run_beside();
  }
  if (here_failure != nullptr) std::rethrow_exception(here_failure);
  if (beside_failure != nullptr) std::rethrow_exception(beside_failure);
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
