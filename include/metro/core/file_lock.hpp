// An exclusive advisory lock on a file (flock(2)), held while the object lives: what keeps two
// runs from writing into one output folder (characterize batch). POSIX only.
#pragma once

#include <optional>
#include <string>

#include "metro/core/status.hpp"

namespace metro {

// Closing the descriptor releases the lock.
class FileLock {
 public:
  explicit FileLock(int fd) : fd_(fd) {}
  FileLock(FileLock&& other) noexcept : fd_(other.fd_) { other.fd_ = -1; }
  FileLock& operator=(FileLock&&) = delete;
  FileLock(const FileLock&) = delete;
  ~FileLock();

 private:
  int fd_ = -1;
};

// What TryLockFile found: the lock, or (lock empty) the holder's own words.
struct FileLockAttempt {
  std::optional<FileLock> lock;
  std::string holder;  // "pid N on HOST, since UNIX-TIME" as the holder wrote it; may be empty.
};

// Opens `path` (created 0644 if missing) and locks it with flock(LOCK_EX | LOCK_NB), never
// waiting. Taken: the file then holds "pid N on HOST, since UNIX-TIME" of this process. Held by
// another process: an attempt without a lock, with what the holder wrote. Errors: the file
// cannot be created ("cannot create the lock file PATH: why") or locked for another reason
// ("cannot lock PATH: why"), at `path`.
Result<FileLockAttempt> TryLockFile(const std::string& path);

}  // namespace metro
