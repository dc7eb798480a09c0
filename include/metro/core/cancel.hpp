// Cooperative cancellation of a long library call, for a caller that runs the call on one
// thread and stops it from another (the Python module's Ctrl-C, python/metro_module.cpp).
//
// The caller owns a CancelFlag and installs it for the thread that makes the call with a
// ScopedCancel; the library's thread helpers (src/core/parallel.hpp: RunOnThreads,
// ParallelFor, RunBeside) install the same flag in the threads they start. Long loops call
// ThrowIfCancelled() between items (each ParallelFor item, each Monte Carlo chunk); once the
// flag is set it throws Cancelled, which unwinds the call as std::bad_alloc does (every
// worker joined, every buffer freed) up to the caller, who catches it. Cancelled is the one
// exception the library throws on purpose: it is the caller's request, not a failure, so it
// never becomes an Error. Without a ScopedCancel nothing is cancelled, and the check is one
// thread-local load.
#pragma once

#include <atomic>
#include <exception>

namespace metro {

// Set once (from any thread); never cleared.
class CancelFlag {
 public:
  void Cancel() { cancelled_.store(true, std::memory_order_relaxed); }
  bool cancelled() const { return cancelled_.load(std::memory_order_relaxed); }

 private:
  std::atomic<bool> cancelled_{false};
};

// Thrown by ThrowIfCancelled() once the current thread's flag is set.
class Cancelled : public std::exception {
 public:
  const char* what() const noexcept override { return "cancelled by the caller"; }
};

// The flag installed for this thread (nullptr: none).
const CancelFlag* CurrentCancelFlag();

// Installs `flag` (not owned; may be null) for this thread until destroyed, then restores
// the one before.
class ScopedCancel {
 public:
  explicit ScopedCancel(const CancelFlag* flag);
  ~ScopedCancel();
  ScopedCancel(const ScopedCancel&) = delete;
  ScopedCancel& operator=(const ScopedCancel&) = delete;

 private:
  const CancelFlag* previous_;
};

// Throws Cancelled when this thread's flag is set.
void ThrowIfCancelled();

}  // namespace metro
