#include "metro/core/file_lock.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <ctime>

namespace metro {

FileLock::~FileLock() {
  if (fd_ >= 0) ::close(fd_);
}

Result<FileLockAttempt> TryLockFile(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd < 0) {
    return MakeError(path, 0,
                     fmt::format("cannot create the lock file {}: {}", path, std::strerror(errno)));
  }
  FileLock lock(fd);
  FileLockAttempt out;
  if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
    const int err = errno;
    if (err != EWOULDBLOCK) {
      return MakeError(path, 0, fmt::format("cannot lock {}: {}", path, std::strerror(err)));
    }
    // The holder wrote who it is when it took the lock.
    char holder[256] = {};
    const ssize_t n = ::pread(fd, holder, sizeof holder - 1, 0);
    out.holder = n > 0 ? std::string(holder, static_cast<size_t>(n)) : std::string();
    while (!out.holder.empty() && (out.holder.back() == '\n' || out.holder.back() == ' ')) {
      out.holder.pop_back();
    }
    return out;
  }
  char host[128] = {};
  ::gethostname(host, sizeof host - 1);
  const std::string who = fmt::format("pid {} on {}, since {}", ::getpid(), host,
                                      static_cast<long long>(::time(nullptr)));
  if (::ftruncate(fd, 0) == 0) {
    [[maybe_unused]] const ssize_t written = ::pwrite(fd, who.data(), who.size(), 0);
  }
  out.lock.emplace(std::move(lock));
  return out;
}

}  // namespace metro
