#include "core/mapping_guard.hpp"

#include <fmt/format.h>
#include <signal.h>
#include <sys/mman.h>
#include <unistd.h>

#include <atomic>
#include <cstdint>
#include <mutex>

namespace metro::internal {
namespace {

// One guarded range. `end` is written last when a slot is taken and cleared first when it
// is given back, so the handler never sees a half-written range.
struct Slot {
  std::atomic<uintptr_t> begin{0};
  std::atomic<uintptr_t> end{0};
  std::atomic<bool> shrunk{false};
  std::atomic<bool> taken{false};
};

Slot g_slots[MappingGuard::kMaxGuards];
struct sigaction g_previous {};

// SIGBUS: a fault inside a guarded range gets zero pages from the faulting page to the
// range's end (one mmap, whatever number of pages the file lost) and the instruction runs
// again. Any other SIGBUS goes to the handler that was there before (or the default
// action, which ends the process as it would have without metro's handler).
void OnSigbus(int signal, siginfo_t* info, void* context) {
  const uintptr_t address = reinterpret_cast<uintptr_t>(info->si_addr);
  for (Slot& slot : g_slots) {
    const uintptr_t end = slot.end.load(std::memory_order_acquire);
    if (end == 0) continue;
    const uintptr_t begin = slot.begin.load(std::memory_order_acquire);
    if (address < begin || address >= end) continue;
    const uintptr_t page = static_cast<uintptr_t>(::sysconf(_SC_PAGESIZE));
    const uintptr_t from = address & ~(page - 1);
    void* zeros = ::mmap(reinterpret_cast<void*>(from), end - from, PROT_READ,
                         MAP_PRIVATE | MAP_ANONYMOUS | MAP_FIXED, -1, 0);
    if (zeros != MAP_FAILED) {
      slot.shrunk.store(true, std::memory_order_release);
      return;
    }
    break;
  }
  if (g_previous.sa_flags & SA_SIGINFO) {
    if (g_previous.sa_sigaction != nullptr) {
      g_previous.sa_sigaction(signal, info, context);
      return;
    }
  } else if (g_previous.sa_handler != SIG_DFL && g_previous.sa_handler != SIG_IGN &&
             g_previous.sa_handler != nullptr) {
    g_previous.sa_handler(signal);
    return;
  }
  // The default action: restore it and return, so the faulting access runs again and ends
  // the process with SIGBUS as before.
  struct sigaction fallback {};
  fallback.sa_handler = SIG_DFL;
  sigemptyset(&fallback.sa_mask);
  ::sigaction(SIGBUS, &fallback, nullptr);
}

void InstallOnce() {
  static std::once_flag once;
  std::call_once(once, [] {
    struct sigaction action {};
    action.sa_sigaction = OnSigbus;
    action.sa_flags = SA_SIGINFO;
    sigemptyset(&action.sa_mask);
    ::sigaction(SIGBUS, &action, &g_previous);
  });
}

}  // namespace

MappingGuard::MappingGuard(const void* begin, size_t size) {
  if (begin == nullptr || size == 0) return;
  InstallOnce();
  for (int i = 0; i < kMaxGuards; ++i) {
    bool expected = false;
    if (!g_slots[i].taken.compare_exchange_strong(expected, true)) continue;
    const uintptr_t b = reinterpret_cast<uintptr_t>(begin);
    g_slots[i].shrunk.store(false, std::memory_order_relaxed);
    g_slots[i].begin.store(b, std::memory_order_release);
    g_slots[i].end.store(b + size, std::memory_order_release);
    slot_ = i;
    return;
  }
}

MappingGuard::~MappingGuard() {
  if (slot_ < 0) return;
  g_slots[slot_].end.store(0, std::memory_order_release);
  g_slots[slot_].begin.store(0, std::memory_order_release);
  g_slots[slot_].taken.store(false, std::memory_order_release);
}

bool MappingGuard::Shrunk() const {
  return slot_ >= 0 && g_slots[slot_].shrunk.load(std::memory_order_acquire);
}

FileIdentity IdentityOf(const struct stat& st) {
  return FileIdentity{st.st_dev, st.st_ino, st.st_size, st.st_mtim};
}

std::string ChangedWhileRead(int fd, const FileIdentity& before, bool shrunk) {
  struct stat now {};
  const bool stat_ok = ::fstat(fd, &now) == 0;
  if (!shrunk && stat_ok && now.st_size == before.size &&
      now.st_mtim.tv_sec == before.modified.tv_sec &&
      now.st_mtim.tv_nsec == before.modified.tv_nsec) {
    return "";
  }
  const std::string size_now =
      stat_ok ? fmt::format("{} bytes now", static_cast<int64_t>(now.st_size)) : "unknown now";
  return fmt::format(
      "the file changed while metro read it ({} bytes when opened, {}{}): "
      "nothing read from it is used; read a file that no program is writing "
      "(copy it first, or wait for the writer to finish)",
      static_cast<int64_t>(before.size), size_now, shrunk ? "; it shrank under the reader" : "");
}

}  // namespace metro::internal
