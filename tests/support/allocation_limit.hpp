// Test helper: makes every `operator new` request larger than a limit throw std::bad_alloc,
// on any thread, while an AllocationLimit is alive: a machine out of memory, on demand and
// deterministic (the library's large buffers, tag columns among them, come from operator
// new). The test program replaces the global operator new for this (allocation_limit.cpp);
// the sanitizer builds keep their own, and there Available() is false.
#pragma once

#include <cstddef>

namespace metro::testing {

class AllocationLimit {
 public:
  explicit AllocationLimit(size_t max_bytes);
  ~AllocationLimit();
  AllocationLimit(const AllocationLimit&) = delete;
  AllocationLimit& operator=(const AllocationLimit&) = delete;

  // False where operator new is not replaced (under AddressSanitizer or ThreadSanitizer).
  static bool Available();
};

}  // namespace metro::testing
