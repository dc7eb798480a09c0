#include "support/allocation_limit.hpp"

#include <atomic>
#include <cstdint>
#include <cstdlib>
#include <new>

#include "support/sanitizer.hpp"

// A sanitizer's runtime replaces operator new itself.
#if METRO_UNDER_SANITIZER
#define METRO_REPLACE_OPERATOR_NEW 0
#else
#define METRO_REPLACE_OPERATOR_NEW 1
#endif

namespace metro::testing {
namespace {
std::atomic<size_t> max_request{SIZE_MAX};
}  // namespace

AllocationLimit::AllocationLimit(size_t max_bytes) { max_request.store(max_bytes); }
AllocationLimit::~AllocationLimit() { max_request.store(SIZE_MAX); }
bool AllocationLimit::Available() { return METRO_REPLACE_OPERATOR_NEW != 0; }

#if METRO_REPLACE_OPERATOR_NEW
namespace {
size_t MaxRequest() { return max_request.load(std::memory_order_relaxed); }
}  // namespace
#endif

}  // namespace metro::testing

#if METRO_REPLACE_OPERATOR_NEW
// The replaceable global allocation functions (C++17 [new.delete.single]): the library's
// own array, nothrow and sized forms call these two; the aligned forms are not replaced.
void* operator new(std::size_t bytes) {
  if (bytes > metro::testing::MaxRequest()) throw std::bad_alloc();
  void* p = std::malloc(bytes == 0 ? 1 : bytes);
  if (p == nullptr) throw std::bad_alloc();
  return p;
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
#endif
