#include "metro/core/cancel.hpp"

namespace metro {
namespace {
thread_local const CancelFlag* current_flag = nullptr;
}  // namespace

const CancelFlag* CurrentCancelFlag() { return current_flag; }

ScopedCancel::ScopedCancel(const CancelFlag* flag) : previous_(current_flag) {
  current_flag = flag;
}

ScopedCancel::~ScopedCancel() { current_flag = previous_; }

void ThrowIfCancelled() {
  if (current_flag != nullptr && current_flag->cancelled()) throw Cancelled();
}

}  // namespace metro
