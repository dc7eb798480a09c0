#include "metro/core/spill_file.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <utility>

namespace metro {
namespace {

// Appends are gathered into writes of this size.
constexpr size_t kWriteBufferBytes = size_t{1} << 20;

std::string TempDirectory() {
  const char* dir = std::getenv("TMPDIR");
  return dir != nullptr && *dir != '\0' ? dir : "/tmp";
}

}  // namespace

SpillFile::SpillFile(SpillFile&& other) noexcept
    : fd_(std::exchange(other.fd_, -1)),
      written_(std::exchange(other.written_, 0)),
      buffer_(std::move(other.buffer_)) {}

SpillFile& SpillFile::operator=(SpillFile&& other) noexcept {
  if (this != &other) {
    if (fd_ >= 0) ::close(fd_);
    fd_ = std::exchange(other.fd_, -1);
    written_ = std::exchange(other.written_, 0);
    buffer_ = std::move(other.buffer_);
  }
  return *this;
}

SpillFile::~SpillFile() {
  if (fd_ >= 0) ::close(fd_);
}

Status SpillFile::Open() {
  const std::string dir = TempDirectory();
  std::string path = dir + "/metro-spill-XXXXXX";
  const int fd = ::mkostemp(path.data(), O_CLOEXEC);
  if (fd < 0) {
    return MakeError(dir, 0,
                     std::string("cannot create a temporary file for streaming: ") +
                         std::strerror(errno) + "; expected a writable directory in TMPDIR");
  }
  ::unlink(path.c_str());
  if (fd_ >= 0) ::close(fd_);
  fd_ = fd;
  written_ = 0;
  buffer_.clear();
  buffer_.reserve(kWriteBufferBytes);
  return Status::Ok();
}

Status SpillFile::Flush() {
  size_t done = 0;
  while (done < buffer_.size()) {
    const ssize_t w = ::pwrite(fd_, buffer_.data() + done, buffer_.size() - done,
                               static_cast<off_t>(written_ + done));
    if (w < 0 && errno == EINTR) continue;
    if (w <= 0) {
      return MakeError(TempDirectory(), 0,
                       std::string("cannot write the streaming mode's temporary file: ") +
                           std::strerror(errno) + "; expected free space in TMPDIR");
    }
    done += static_cast<size_t>(w);
  }
  written_ += buffer_.size();
  buffer_.clear();
  return Status::Ok();
}

Status SpillFile::Append(const void* data, size_t bytes) {
  const char* p = static_cast<const char*>(data);
  while (bytes > 0) {
    const size_t take = std::min(bytes, kWriteBufferBytes - buffer_.size());
    buffer_.insert(buffer_.end(), p, p + take);
    p += take;
    bytes -= take;
    if (buffer_.size() == kWriteBufferBytes) {
      if (Status s = Flush(); !s.ok()) return s;
    }
  }
  return Status::Ok();
}

Status SpillFile::ReadAt(uint64_t offset, void* out, size_t bytes) const {
  char* p = static_cast<char*>(out);
  size_t done = 0;
  while (done < bytes) {
    const ssize_t r = ::pread(fd_, p + done, bytes - done, static_cast<off_t>(offset + done));
    if (r < 0 && errno == EINTR) continue;
    if (r <= 0) {
      return MakeError(TempDirectory(), 0,
                       std::string("cannot read back the streaming mode's temporary file: ") +
                           (r == 0 ? std::string("it is shorter than written")
                                   : std::string(std::strerror(errno))));
    }
    done += static_cast<size_t>(r);
  }
  return Status::Ok();
}

}  // namespace metro
