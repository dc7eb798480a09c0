// Private: keeps a read-only file mapping readable when the file shrinks under it.
//
// A page of a file mapping that lies beyond the file's end, after another process has
// truncated the file, raises SIGBUS when it is touched, which ends the process without a
// word. While a MappingGuard lives, such a fault inside its range is answered by mapping
// zero-filled anonymous pages over the rest of the range: the reader goes on (it reads
// zeros) and `Shrunk()` says that it happened. Whoever owns the mapping checks `Changed`
// before trusting anything read from it (docs/security.md, part 3).
#pragma once

#include <sys/stat.h>

#include <atomic>
#include <cstddef>
#include <string>

namespace metro::internal {

class MappingGuard {
 public:
  // Registers [begin, begin + size). At most kMaxGuards guards live at once; beyond that
  // the range is not guarded (the reader then behaves as without a guard) and
  // `Guarded()` is false.
  MappingGuard(const void* begin, size_t size);
  MappingGuard(const MappingGuard&) = delete;
  MappingGuard& operator=(const MappingGuard&) = delete;
  ~MappingGuard();

  bool Guarded() const { return slot_ >= 0; }
  // A page beyond the file's end was touched (and read as zeros).
  bool Shrunk() const;

  static constexpr int kMaxGuards = 64;

 private:
  int slot_ = -1;
};

// What a file was when it was opened: compared with what it is after reading, to tell a
// file that changed while metro read it.
struct FileIdentity {
  dev_t device = 0;
  ino_t inode = 0;
  off_t size = 0;
  timespec modified{};
};
FileIdentity IdentityOf(const struct stat& st);

// The error text (without the file's name) for a file that changed while it was read, or
// "" when it did not: `shrunk` (a guard saw pages beyond the end), or `fd`'s size or
// modification time now differ from `before`.
std::string ChangedWhileRead(int fd, const FileIdentity& before, bool shrunk);

}  // namespace metro::internal
