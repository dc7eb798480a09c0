#include "metro/core/file.hpp"

#include <fcntl.h>
#include <openssl/evp.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <memory>
#include <random>
#include <vector>

#include "metro/core/check.hpp"

namespace metro {
namespace {

std::string OsError(const std::string& what, const std::string& path) {
  return what + " '" + path + "': " + std::strerror(errno);
}

std::string DirectoryOf(const std::string& path) {
  const auto slash = path.find_last_of('/');
  if (slash == std::string::npos) return ".";
  if (slash == 0) return "/";
  return path.substr(0, slash);
}

}  // namespace

AtomicFileWriter::AtomicFileWriter(std::string path) : path_(std::move(path)) {}

AtomicFileWriter::~AtomicFileWriter() {
  if (fd_ >= 0) {
    ::close(fd_);
    ::unlink(tmp_.c_str());
  }
}

Status AtomicFileWriter::Open() {
  std::random_device entropy;
  tmp_ = path_ + ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(entropy() & 0xFFFFFFu);
  fd_ = ::open(tmp_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
  if (fd_ < 0) return MakeError(OsError("cannot create temporary file for", path_));
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
      return MakeError(OsError("cannot write", path_));
    }
    data += n;
    left -= static_cast<size_t>(n);
  }
  return Status::Ok();
}

Status AtomicFileWriter::Commit() {
  METRO_CHECK(fd_ >= 0);
  const bool flushed = ::fsync(fd_) == 0;
  const bool closed = ::close(fd_) == 0;
  fd_ = -1;
  if (!flushed || !closed) {
    const std::string why = OsError("cannot flush", path_);
    ::unlink(tmp_.c_str());
    return MakeError(why);
  }
  if (::rename(tmp_.c_str(), path_.c_str()) != 0) {
    const std::string why = OsError("cannot rename temporary file onto", path_);
    ::unlink(tmp_.c_str());
    return MakeError(why);
  }
  // Make the rename itself durable.
  const int dir_fd = ::open(DirectoryOf(path_).c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dir_fd >= 0) {
    ::fsync(dir_fd);
    ::close(dir_fd);
  }
  return Status::Ok();
}

Status WriteFileAtomically(const std::string& path, std::string_view contents) {
  AtomicFileWriter writer(path);
  if (Status s = writer.Open(); !s.ok()) return s;
  if (Status s = writer.Write(contents); !s.ok()) return s;
  return writer.Commit();
}

Result<std::string> ReadFile(const std::string& path) {
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
    out.append(buffer, static_cast<size_t>(n));
  }
  ::close(fd);
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
      ::close(fd);
      ::madvise(map, size, MADV_SEQUENTIAL);
      constexpr size_t kChunkBytes = size_t{4} << 20;  // A multiple of the page size.
      char* data = static_cast<char*>(map);
      size_t released = 0;
      std::string digest = Sha256Hex(std::string_view(data, size), kChunkBytes, [&](size_t hashed) {
        ::madvise(data + released, hashed - released, MADV_DONTNEED);
        released = hashed;
      });
      ::munmap(map, size);
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
  if (::stat(a.c_str(), &sa) != 0 || ::stat(b.c_str(), &sb) != 0) return false;
  return sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
}

}  // namespace metro
