// Private: a read-only memory map of a whole file, for the session loaders. The mapping is
// guarded (core/mapping_guard.hpp): a file truncated while it is read gives zeros, not
// SIGBUS, and `ChangedSinceOpen` tells the loader to discard what it read.
#pragma once

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <memory>
#include <string>

#include "core/mapping_guard.hpp"
#include "metro/core/status.hpp"

namespace metro::internal {

class MappedFile {
 public:
  MappedFile() = default;
  MappedFile(const MappedFile&) = delete;
  MappedFile& operator=(const MappedFile&) = delete;
  ~MappedFile() {
    guard_.reset();
    if (data_ != nullptr) ::munmap(const_cast<char*>(data_), size_);
    if (fd_ >= 0) ::close(fd_);
  }

  Status Open(const std::string& path) {
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) return MakeError(path, 0, std::string("cannot open: ") + std::strerror(errno));
    struct stat st {};
    if (::fstat(fd, &st) != 0 || S_ISDIR(st.st_mode)) {
      ::close(fd);
      return MakeError(path, 0, "is not a regular file");
    }
    size_ = static_cast<size_t>(st.st_size);
    if (size_ > 0) {
      void* p = ::mmap(nullptr, size_, PROT_READ, MAP_PRIVATE, fd, 0);
      if (p == MAP_FAILED) {
        ::close(fd);
        return MakeError(path, 0, std::string("cannot map: ") + std::strerror(errno));
      }
      data_ = static_cast<const char*>(p);
      guard_ = std::make_unique<MappingGuard>(p, size_);
      ::madvise(p, size_, MADV_SEQUENTIAL);
    }
    // Kept open to compare the file after reading with the file as opened.
    fd_ = fd;
    identity_ = IdentityOf(st);
    return Status::Ok();
  }

  // "" when the file is as it was opened; else what changed (or that it shrank) while it
  // was read (ChangedWhileRead). Call after reading, before trusting what was read.
  std::string ChangedSinceOpen() const {
    if (fd_ < 0) return "";
    return ChangedWhileRead(fd_, identity_, guard_ != nullptr && guard_->Shrunk());
  }

  // Drops the pages from the one holding `begin` to the last one wholly before `end`
  // (ReleaseBehind's ranges follow each other, so no page is left behind; a page dropped
  // early is mapped again from the page cache by whoever reads it).
  void ReleaseBelow(size_t begin, size_t end) const {
    const size_t page = static_cast<size_t>(::sysconf(_SC_PAGESIZE));
    const size_t first = begin / page * page;
    const size_t last = end / page * page;
    if (last > first) ::madvise(const_cast<char*>(data_) + first, last - first, MADV_DONTNEED);
  }

  const char* data() const { return data_; }
  size_t size() const { return size_; }

 private:
  const char* data_ = nullptr;
  size_t size_ = 0;
  int fd_ = -1;
  FileIdentity identity_;
  std::unique_ptr<MappingGuard> guard_;
};

}  // namespace metro::internal
