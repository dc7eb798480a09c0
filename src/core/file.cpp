#include "metro/core/file.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <openssl/evp.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <climits>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <memory>
#include <random>
#include <vector>

#include "core/mapping_guard.hpp"
#include "metro/core/check.hpp"

namespace metro {
namespace {

namespace fs = std::filesystem;

std::string OsError(const std::string& what, const std::string& path) {
  return what + " '" + path + "': " + std::strerror(errno);
}

std::string DirectoryOf(const std::string& path) {
  const auto slash = path.find_last_of('/');
  if (slash == std::string::npos) return ".";
  if (slash == 0) return "/";
  return path.substr(0, slash);
}

// The temporaries the SIGINT/SIGTERM/SIGHUP handler removes (InstallInterruptCleanup). A
// fixed table the handler can read without allocating or locking: a slot is free (0), being
// filled (1), registered (2) or taken by the handler (3). Register fills a free slot and
// marks it registered; Unregister frees a registered slot; the handler takes each
// registered slot before it unlinks its path, so a slot it reads is never refilled.
constexpr int kCleanupSlots = 64;
struct CleanupSlot {
  std::atomic<int> state{0};
  char path[PATH_MAX];
};
CleanupSlot g_cleanup[kCleanupSlots];
static_assert(std::atomic<int>::is_always_lock_free, "the signal handler needs lock-free ints");

extern "C" void OnInterrupt(int signal) {
  for (CleanupSlot& slot : g_cleanup) {
    int registered = 2;
    if (slot.state.compare_exchange_strong(registered, 3)) ::unlink(slot.path);
  }
  // End as the signal would have: its default action (restored by SA_RESETHAND), delivered
  // when the handler returns.
  ::signal(signal, SIG_DFL);
  ::raise(signal);
}

}  // namespace

void InstallInterruptCleanup() {
  for (int signal : {SIGINT, SIGTERM, SIGHUP}) {
    struct sigaction old {};
    // A signal the caller ignores (nohup, a background job of a script) stays ignored.
    if (::sigaction(signal, nullptr, &old) == 0 && old.sa_handler == SIG_IGN) continue;
    struct sigaction action {};
    action.sa_handler = OnInterrupt;
    sigfillset(&action.sa_mask);
    action.sa_flags = SA_RESETHAND;
    ::sigaction(signal, &action, nullptr);
  }
  // A write past the file size limit fails with EFBIG (the full-disk path) instead of killing.
  ::signal(SIGXFSZ, SIG_IGN);
}

RemoveOnInterrupt::RemoveOnInterrupt(const std::string& path) { Reset(path); }

RemoveOnInterrupt::~RemoveOnInterrupt() { Reset(); }

void RemoveOnInterrupt::Reset(const std::string& path) {
  if (slot_ >= 0) {
    int registered = 2;
    g_cleanup[slot_].state.compare_exchange_strong(registered, 0);
    slot_ = -1;
  }
  if (path.empty() || path.size() >= PATH_MAX) return;
  for (int i = 0; i < kCleanupSlots; ++i) {
    int free_slot = 0;
    if (!g_cleanup[i].state.compare_exchange_strong(free_slot, 1)) continue;
    std::memcpy(g_cleanup[i].path, path.c_str(), path.size() + 1);
    g_cleanup[i].state.store(2);
    slot_ = i;
    return;
  }
}

AtomicFileWriter::AtomicFileWriter(std::string path) : path_(std::move(path)) {}

AtomicFileWriter::~AtomicFileWriter() {
  if (fd_ >= 0) ::close(fd_);
  if (!tmp_.empty()) ::unlink(tmp_.c_str());
}

Status AtomicFileWriter::Open() {
  METRO_CHECK(fd_ < 0 && tmp_.empty());
  if (Status s = CheckReplaceableFile(path_); !s.ok()) return s;
  target_ = path_;
  struct stat link {};
  if (::lstat(path_.c_str(), &link) == 0 && S_ISLNK(link.st_mode)) {
    // Replace the file the link points to and keep the link (a dangling link is replaced).
    std::error_code ec;
    const fs::path resolved = fs::weakly_canonical(path_, ec);
    if (!ec) target_ = resolved.string();
  }
  struct stat old {};
  const bool replacing = ::stat(target_.c_str(), &old) == 0;
  // A short name beside the target: `path` may be as long as a name can be (255 bytes).
  static const char kAlphabet[] = "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789";
  std::random_device entropy;
  const std::string dir = DirectoryOf(target_);
  for (int attempt = 0; attempt < 100 && fd_ < 0; ++attempt) {
    std::string name = ".metro-";
    uint32_t bits = entropy();
    for (int k = 0; k < 6; ++k, bits /= 62) name += kAlphabet[bits % 62];
    tmp_ = (dir == "/" ? "" : dir) + "/" + name;
    // 0666 minus the umask, as any new file.
    fd_ = ::open(tmp_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
    if (fd_ < 0 && errno != EEXIST) break;
  }
  if (fd_ >= 0) cleanup_.Reset(tmp_);
  if (fd_ < 0) {
    // No space or a failing device is a write that failed; anything else (no permission,
    // a read-only file system) an output that cannot be created where it was named.
    const int err = errno;
    const std::string why = OsError("cannot create a temporary file beside", path_);
    tmp_.clear();
    const bool io = err == ENOSPC || err == EDQUOT || err == EIO;
    return io ? MakeIoError(why) : MakeError(why);
  }
  if (replacing) {
    // The replaced file keeps its permissions (a 0600 report stays 0600) and, where the
    // system allows it, its owner and group.
    if (old.st_uid != ::geteuid() || old.st_gid != ::getegid()) {
      [[maybe_unused]] const int ignored = ::fchown(fd_, old.st_uid, old.st_gid);
    }
    if (::fchmod(fd_, old.st_mode & 07777) != 0) {
      return MakeIoError(OsError("cannot keep the permissions of", path_));
    }
  }
  return Status::Ok();
}

Status AtomicFileWriter::Write(std::string_view chunk) {
  METRO_CHECK(fd_ >= 0);
  const char* data = chunk.data();
  size_t left = chunk.size();
  while (left > 0) {
    const ssize_t n = ::write(fd_, data, left);
    if (n < 0) {
      if (errno == EINTR) continue;
      return MakeIoError(OsError("cannot write", path_));
    }
    data += n;
    left -= static_cast<size_t>(n);
  }
  return Status::Ok();
}

Status AtomicFileWriter::Finish() {
  METRO_CHECK(fd_ >= 0);
  const bool flushed = ::fsync(fd_) == 0;
  const int flush_errno = errno;
  const bool closed = ::close(fd_) == 0;
  fd_ = -1;
  if (!flushed || !closed) {
    if (!flushed) errno = flush_errno;
    const std::string why = OsError("cannot flush", path_);
    ::unlink(tmp_.c_str());
    tmp_.clear();
    cleanup_.Reset();
    return MakeIoError(why);
  }
  finished_ = true;
  return Status::Ok();
}

Status AtomicFileWriter::Publish() {
  METRO_CHECK(finished_ && !tmp_.empty());
  if (::rename(tmp_.c_str(), target_.c_str()) != 0) {
    const std::string why = OsError("cannot rename temporary file onto", path_);
    ::unlink(tmp_.c_str());
    tmp_.clear();
    cleanup_.Reset();
    return MakeIoError(why);
  }
  tmp_.clear();
  cleanup_.Reset();
  // Make the rename itself durable.
  const int dir_fd = ::open(DirectoryOf(target_).c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dir_fd >= 0) {
    ::fsync(dir_fd);
    ::close(dir_fd);
  }
  return Status::Ok();
}

Status AtomicFileWriter::Commit() {
  if (Status s = Finish(); !s.ok()) return s;
  return Publish();
}

Status WriteFileAtomically(const std::string& path, std::string_view contents) {
  AtomicFileWriter writer(path);
  if (Status s = writer.Open(); !s.ok()) return s;
  if (Status s = writer.Write(contents); !s.ok()) return s;
  return writer.Commit();
}

Status WriteFilesAtomically(const std::vector<std::pair<std::string, std::string_view>>& files) {
  std::vector<std::unique_ptr<AtomicFileWriter>> writers;
  for (const auto& [path, contents] : files) {
    writers.push_back(std::make_unique<AtomicFileWriter>(path));
    AtomicFileWriter& w = *writers.back();
    if (Status s = w.Open(); !s.ok()) return s;
    if (Status s = w.Write(contents); !s.ok()) return s;
    if (Status s = w.Finish(); !s.ok()) return s;
  }
  // Every file is on disk under its temporary name: now the renames, which do not fail for
  // lack of space. The writers not yet published remove their temporaries on the way out.
  for (auto& w : writers) {
    if (Status s = w->Publish(); !s.ok()) return s;
  }
  return Status::Ok();
}

namespace {

// The one check behind CheckReplaceableFile and CheckUpdatableFile: `path` is absent or a
// regular file (through symlinks), its directory exists, and it is not in /dev, /proc or
// /sys. `refuse(what)` makes the error for a file of the wrong kind.
template <typename Refuse>
Status CheckRegularOrAbsent(const std::string& path, const Refuse& refuse) {
  if (path.empty()) return MakeError("an output with an empty file name");
  struct stat st {};
  if (::stat(path.c_str(), &st) == 0) {
    if (S_ISDIR(st.st_mode)) return refuse("is a directory");
    if (S_ISCHR(st.st_mode)) return refuse("is a character device");
    if (S_ISBLK(st.st_mode)) return refuse("is a block device");
    if (S_ISFIFO(st.st_mode)) return refuse("is a FIFO (named pipe)");
    if (S_ISSOCK(st.st_mode)) return refuse("is a socket");
    if (!S_ISREG(st.st_mode)) return refuse("is not a regular file");
  }
  // The directory the new file goes into (the link's own directory for a dangling link,
  // the target's for a link that resolves), symlinks resolved.
  std::error_code ec;
  std::string target = path;
  struct stat link {};
  if (::lstat(path.c_str(), &link) == 0 && S_ISLNK(link.st_mode)) {
    const fs::path resolved = fs::weakly_canonical(path, ec);
    if (!ec) target = resolved.string();
  }
  const std::string dir = DirectoryOf(target);
  struct stat dir_st {};
  if (::stat(dir.c_str(), &dir_st) != 0) {
    return MakeError(
        fmt::format("{}: the directory {} does not exist: create it first", path, dir));
  }
  if (!S_ISDIR(dir_st.st_mode)) {
    return MakeError(fmt::format("{}: {} is not a directory", path, dir));
  }
  const std::string canonical_dir = fs::canonical(dir, ec).string();
  for (const char* system : {"/dev", "/proc", "/sys"}) {
    const std::string prefix = system;
    if (!ec && (canonical_dir == prefix || canonical_dir.rfind(prefix + "/", 0) == 0)) {
      return refuse("is in " + prefix);
    }
  }
  return Status::Ok();
}

}  // namespace

Status CheckReplaceableFile(const std::string& path) {
  return CheckRegularOrAbsent(path, [&path](const std::string& what) {
    return MakeError(fmt::format(
        "{} {}: metro writes an output to a new file and renames it into place, which would "
        "replace it; name a regular file (or - for stdout, redirected where you want it)",
        path, what));
  });
}

Status CheckUpdatableFile(const std::string& path) {
  return CheckRegularOrAbsent(path, [&path](const std::string& what) {
    return MakeError(fmt::format(
        "{} {}: metro reads and updates this file in place (a database); name a regular file", path,
        what));
  });
}

Result<std::string> ReadFile(const std::string& path, int64_t max_bytes) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return MakeError(OsError("cannot open", path));
  struct stat st {};
  if (::fstat(fd, &st) != 0) {
    const std::string why = OsError("cannot stat", path);
    ::close(fd);
    return MakeError(why);
  }
  if (S_ISDIR(st.st_mode)) {
    ::close(fd);
    return MakeError(path + ": is a directory, expected a file");
  }
  auto too_large = [&](const std::string& what) {
    return MakeError(path, 0,
                     fmt::format("{}: more than {} bytes, which no file of this kind holds; "
                                 "expected a text document of at most that size",
                                 what, max_bytes));
  };
  if (S_ISREG(st.st_mode) && st.st_size > max_bytes) {
    ::close(fd);
    return too_large(fmt::format("{} bytes", static_cast<int64_t>(st.st_size)));
  }
  std::string out;
  if (st.st_size > 0) out.reserve(static_cast<size_t>(st.st_size));
  char buffer[1 << 16];
  for (;;) {
    const ssize_t n = ::read(fd, buffer, sizeof buffer);
    if (n < 0) {
      if (errno == EINTR) continue;
      const std::string why = OsError("cannot read", path);
      ::close(fd);
      return MakeError(why);
    }
    if (n == 0) break;
    if (n > max_bytes - static_cast<int64_t>(out.size())) {
      ::close(fd);
      return too_large("still reading");
    }
    out.append(buffer, static_cast<size_t>(n));
  }
  // A regular file written to or truncated while it was read gives no text at all.
  const std::string changed =
      S_ISREG(st.st_mode) ? internal::ChangedWhileRead(fd, internal::IdentityOf(st), false) : "";
  ::close(fd);
  if (!changed.empty()) return MakeError(path, 0, changed);
  return out;
}

namespace {

std::string HexDigest(const unsigned char* digest, unsigned int length) {
  static const char kHex[] = "0123456789abcdef";
  std::string out;
  out.reserve(2 * length);
  for (unsigned int i = 0; i < length; ++i) {
    out += kHex[digest[i] >> 4];
    out += kHex[digest[i] & 0xF];
  }
  return out;
}

}  // namespace

std::string Sha256Hex(std::string_view bytes) {
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int length = 0;
  EVP_Digest(bytes.data(), bytes.size(), digest, &length, EVP_sha256(), nullptr);
  return HexDigest(digest, length);
}

std::string Sha256Hex(std::string_view bytes, size_t chunk_bytes,
                      const std::function<void(size_t)>& on_hashed) {
  std::unique_ptr<EVP_MD_CTX, decltype(&EVP_MD_CTX_free)> ctx(EVP_MD_CTX_new(), EVP_MD_CTX_free);
  EVP_DigestInit_ex(ctx.get(), EVP_sha256(), nullptr);
  const size_t chunk = std::max<size_t>(chunk_bytes, 1);
  for (size_t offset = 0; offset < bytes.size(); offset += chunk) {
    const size_t n = std::min(chunk, bytes.size() - offset);
    EVP_DigestUpdate(ctx.get(), bytes.data() + offset, n);
    if (on_hashed) on_hashed(offset + n);
  }
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int length = 0;
  EVP_DigestFinal_ex(ctx.get(), digest, &length);
  return HexDigest(digest, length);
}

Result<std::string> Sha256File(const std::string& path) {
  // Streamed in 1 MiB chunks: hashing a large session costs no memory.
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return MakeError(OsError("cannot open", path));
  // A regular file is hashed from a read-only mapping of the page cache (no copy into a
  // buffer), 4 MiB at a time, each chunk's pages unmapped once hashed so the resident size
  // stays a few MB. Anything that cannot be mapped is read instead.
  struct stat st {};
  if (::fstat(fd, &st) == 0 && S_ISREG(st.st_mode) && st.st_size > 0) {
    const size_t size = static_cast<size_t>(st.st_size);
    void* map = ::mmap(nullptr, size, PROT_READ, MAP_PRIVATE, fd, 0);
    if (map != MAP_FAILED) {
      ::madvise(map, size, MADV_SEQUENTIAL);
      constexpr size_t kChunkBytes = size_t{4} << 20;  // A multiple of the page size.
      char* data = static_cast<char*>(map);
      size_t released = 0;
      std::string digest;
      std::string changed;
      {
        // A file truncated while it is hashed reads as zeros, not SIGBUS, and is an error.
        internal::MappingGuard guard(map, size);
        digest = Sha256Hex(std::string_view(data, size), kChunkBytes, [&](size_t hashed) {
          ::madvise(data + released, hashed - released, MADV_DONTNEED);
          released = hashed;
        });
        changed = internal::ChangedWhileRead(fd, internal::IdentityOf(st), guard.Shrunk());
      }
      ::munmap(map, size);
      ::close(fd);
      if (!changed.empty()) return MakeError(path, 0, changed);
      return digest;
    }
  }
  std::unique_ptr<EVP_MD_CTX, decltype(&EVP_MD_CTX_free)> ctx(EVP_MD_CTX_new(), EVP_MD_CTX_free);
  EVP_DigestInit_ex(ctx.get(), EVP_sha256(), nullptr);
  std::vector<char> buffer(size_t{1} << 20);
  for (;;) {
    const ssize_t n = ::read(fd, buffer.data(), buffer.size());
    if (n < 0) {
      if (errno == EINTR) continue;
      const std::string why = OsError("cannot read", path);
      ::close(fd);
      return MakeError(why);
    }
    if (n == 0) break;
    EVP_DigestUpdate(ctx.get(), buffer.data(), static_cast<size_t>(n));
  }
  ::close(fd);
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int length = 0;
  EVP_DigestFinal_ex(ctx.get(), digest, &length);
  return HexDigest(digest, length);
}

bool IsSameFile(const std::string& a, const std::string& b) {
  struct stat sa {
  }, sb{};
  const bool a_exists = ::stat(a.c_str(), &sa) == 0;
  const bool b_exists = ::stat(b.c_str(), &sb) == 0;
  if (a_exists && b_exists) return sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
  if (a_exists || b_exists) return false;
  // Neither exists yet: the files they would become.
  std::error_code ea, eb;
  const fs::path ca = fs::weakly_canonical(a, ea);
  const fs::path cb = fs::weakly_canonical(b, eb);
  if (ea || eb) return a == b;
  return ca == cb;
}

}  // namespace metro
