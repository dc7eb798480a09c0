#include "io/stdin_input.hpp"

#include <fcntl.h>
#include <poll.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <string>
#include <utility>
#include <vector>

#include "metro/io/ulog.hpp"

namespace metro::internal {
namespace {

constexpr const char* kTerminalMessage =
    "reading a session from stdin, but stdin is a terminal: pipe a file in or name it";
constexpr const char* kNameTheFile = "; name the file instead of piping it";
constexpr int64_t kBinaryCheckBytes = int64_t{64} << 10;

Error StreamError(const std::string& name, const std::string& what, int errnum) {
  return MakeError(name, 0, what + ": " + std::strerror(errnum));
}

std::string ProcPath(int fd) { return "/proc/self/fd/" + std::to_string(fd); }

// True if `path` opens for reading (the /proc magic link of a descriptor we hold).
bool Opens(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return false;
  ::close(fd);
  return true;
}

// Waits until a non-blocking `fd` is readable (or hung up). False on a poll error.
bool WaitReadable(int fd) {
  struct pollfd p {};
  p.fd = fd;
  p.events = POLLIN;
  for (;;) {
    const int r = ::poll(&p, 1, -1);
    if (r >= 0) return true;
    if (errno != EINTR) return false;
  }
}

bool WriteAll(int fd, const char* data, size_t size) {
  while (size > 0) {
    const ssize_t n = ::write(fd, data, size);
    if (n < 0) {
      if (errno == EINTR) continue;
      return false;
    }
    data += n;
    size -= static_cast<size_t>(n);
  }
  return true;
}

}  // namespace

Result<int64_t> MaxStreamBytes() {
  const char* env = std::getenv(kMaxStreamBytesVariable);
  if (env == nullptr || *env == '\0') return kDefaultMaxStreamBytes;
  const std::string text = env;
  int64_t value = 0;
  bool digits = !text.empty();
  for (char c : text) {
    if (c < '0' || c > '9' || value > (INT64_MAX - 9) / 10) {
      digits = false;
      break;
    }
    value = value * 10 + (c - '0');
  }
  if (!digits || value < 1) {
    return MakeError(std::string(kMaxStreamBytesVariable) + "='" + text +
                     "': expected a whole number of bytes >= 1, e.g. " +
                     std::to_string(kDefaultMaxStreamBytes) + " (the default, 4 GiB)");
  }
  return value;
}

StdinFile::StdinFile(StdinFile&& other) noexcept { *this = std::move(other); }

StdinFile& StdinFile::operator=(StdinFile&& other) noexcept {
  if (this != &other) {
    Reset();
    fd_ = std::exchange(other.fd_, -1);
    path_ = std::move(other.path_);
    other.path_.clear();
    remove_path_ = std::exchange(other.remove_path_, false);
    size_bytes_ = std::exchange(other.size_bytes_, 0);
    storage_ = std::exchange(other.storage_, StdinStorage::kNone);
  }
  return *this;
}

StdinFile::~StdinFile() { Reset(); }

void StdinFile::Reset() {
  if (remove_path_) ::unlink(path_.c_str());
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
  path_.clear();
  remove_path_ = false;
  size_bytes_ = 0;
  storage_ = StdinStorage::kNone;
}

namespace {

// Copies `source` to `dest` in 1 MiB reads until its end: the bytes copied, or the error
// (binary data in the first 64 KiB unless a PX4 ULog's magic starts it, more than max_bytes,
// a read or write failure) naming the stream.
Result<int64_t> CopyChunks(int source, int dest, const std::string& name, const std::string& said,
                           int64_t max_bytes, bool to_memory) {
  std::vector<char> chunk(size_t{1} << 20);
  int64_t total = 0;
  std::string head;  // The first 7 bytes: a PX4 ULog (binary by design) starts with its magic.
  for (;;) {
    const ssize_t n = ::read(source, chunk.data(), chunk.size());
    if (n == 0) break;
    if (n < 0) {
      if (errno == EINTR) continue;
      if ((errno == EAGAIN || errno == EWOULDBLOCK) && WaitReadable(source)) continue;
      return StreamError(name, "cannot read " + said, errno);
    }
    if (head.size() < 7) head.append(chunk.data(), std::min<size_t>(n, 7 - head.size()));
    // Binary data is refused on its first bytes, not after the cap (/dev/zero never ends).
    // The ULog magic has no NUL byte, so a ULog is known before its first NUL is read.
    if (total < kBinaryCheckBytes && !IsULogMagic(head) &&
        std::memchr(chunk.data(), '\0',
                    std::min(static_cast<size_t>(n),
                             static_cast<size_t>(kBinaryCheckBytes - total))) != nullptr) {
      return MakeError(name, 0,
                       "binary data (NUL bytes) in the first 64 KiB: expected a text "
                       "session.csv, a receiver capture or a PX4 ULog");
    }
    if (n > max_bytes - total) {
      return MakeError(
          name, 0,
          "more than " + std::to_string(max_bytes) + " bytes: a stream may hold at most that (" +
              kMaxStreamBytesVariable +
              " sets another cap, in bytes); save the input to a file and name it, or raise "
              "the cap");
    }
    if (!WriteAll(dest, chunk.data(), static_cast<size_t>(n))) {
      const int why = errno;
      return StreamError(name,
                         "cannot copy " + said + " to a " + (to_memory ? "memory" : "temporary") +
                             " file" + kNameTheFile,
                         why);
    }
    total += n;
  }
  return total;
}

}  // namespace

Result<StdinFile> CopyStdinToFile(const StdinCopyOptions& options) {
  const int source = options.source_fd;
  // Errors name the stream as given ("<stdin>", a FIFO's path); messages say "stdin".
  const std::string& name = options.display_name;
  const std::string said = name == kStdinDisplayName ? std::string("stdin") : name;
  int64_t max_bytes = options.max_bytes;
  if (max_bytes <= 0) {
    Result<int64_t> cap = MaxStreamBytes();
    if (!cap.ok()) return cap.error();
    max_bytes = cap.value();
  }
  // First, before this function opens anything that could take a closed descriptor's
  // number (a closed stdin would otherwise read back our own, empty, copy).
  struct stat st {};
  if (::fstat(source, &st) != 0) {
    if (errno == EBADF) {
      return MakeError(name, 0, "stdin is closed: pipe a file in or name it");
    }
    return StreamError(name, "cannot read " + said, errno);
  }
  if (::isatty(source)) return MakeError(kTerminalMessage);

  StdinFile out;
  // A regular file read from its start is its own copy.
  if (S_ISREG(st.st_mode) && ::lseek(source, 0, SEEK_CUR) == 0) {
    const int fd = ::fcntl(source, F_DUPFD_CLOEXEC, 0);
    if (fd >= 0 && Opens(ProcPath(fd))) {
      out.fd_ = fd;
      out.path_ = ProcPath(fd);
      out.size_bytes_ = static_cast<int64_t>(st.st_size);
      out.storage_ = StdinStorage::kStdinItself;
      return out;
    }
    if (fd >= 0) ::close(fd);
  }

  if (options.try_memfd) {
    const int fd = ::memfd_create("metro-stdin", MFD_CLOEXEC | MFD_ALLOW_SEALING);
    if (fd >= 0 && Opens(ProcPath(fd))) {
      out.fd_ = fd;
      out.path_ = ProcPath(fd);
      out.storage_ = StdinStorage::kMemfd;
    } else if (fd >= 0) {
      ::close(fd);
    }
  }
  if (out.fd_ < 0) {
    std::string dir = options.tmp_dir;
    if (dir.empty()) {
      const char* env = std::getenv("TMPDIR");
      dir = env != nullptr && *env != '\0' ? env : "/tmp";
    }
    std::string tmp_name = dir + "/metro-stdin-XXXXXX";
    std::vector<char> buffer(tmp_name.begin(), tmp_name.end());
    buffer.push_back('\0');
    const int fd = ::mkostemp(buffer.data(), O_CLOEXEC);
    if (fd < 0) {
      const int why = errno;
      return StreamError(
          name, "cannot make a temporary file in " + dir + " to hold " + said + kNameTheFile, why);
    }
    tmp_name.assign(buffer.data());
    out.fd_ = fd;
    out.storage_ = StdinStorage::kTmpfile;
    if (Opens(ProcPath(fd))) {
      ::unlink(tmp_name.c_str());  // Gone with the descriptor, even if the process is killed.
      out.path_ = ProcPath(fd);
    } else {
      out.path_ = tmp_name;
      out.remove_path_ = true;
    }
  }

  Result<int64_t> copied =
      CopyChunks(source, out.fd_, name, said, max_bytes, out.storage_ == StdinStorage::kMemfd);
  if (!copied.ok()) return copied.error();
  const int64_t total = copied.value();
  out.size_bytes_ = total;
  if (out.storage_ == StdinStorage::kMemfd) {
    // The loaders map the file: sealed, its bytes cannot change under a mapping. A kernel
    // without seals leaves it unsealed, which is harmless (only we hold it).
    ::fcntl(out.fd_, F_ADD_SEALS, F_SEAL_SHRINK | F_SEAL_GROW | F_SEAL_WRITE | F_SEAL_SEAL);
  }
  return out;
}

}  // namespace metro::internal
