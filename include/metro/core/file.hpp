// File helpers: atomic output, whole-file input and SHA-256 of inputs.
#pragma once

#include <cstddef>
#include <functional>
#include <string>
#include <string_view>

#include "metro/core/status.hpp"

namespace metro {

// Writes `contents` to `path` atomically: the data go to a temporary file in the same
// directory, are flushed to disk (fsync), and the temporary is renamed over `path`. A
// reader never sees a partial file and a failure leaves any previous `path` untouched.
Status WriteFileAtomically(const std::string& path, std::string_view contents);

// Reads a whole file. Errors name the path and the operating system's reason.
Result<std::string> ReadFile(const std::string& path);

// Lower-case hex SHA-256 of a byte string and of a file's contents.
std::string Sha256Hex(std::string_view bytes);
Result<std::string> Sha256File(const std::string& path);

// The same digest, hashed front to back `chunk_bytes` at a time (0 is taken as 1), calling
// on_hashed(n) from the calling thread after each chunk, n being the bytes hashed so far
// (the last has n == bytes.size(); empty bytes make no call). Lets a reader sharing the
// bytes know which the hasher has finished with.
std::string Sha256Hex(std::string_view bytes, size_t chunk_bytes,
                      const std::function<void(size_t)>& on_hashed);

// True if both paths name the same existing file (same device and inode). Used to refuse
// writing an output over one of the inputs.
bool IsSameFile(const std::string& a, const std::string& b);

}  // namespace metro

namespace metro {

// Streams a large output to `path` atomically: chunks go to a temporary file in the same
// directory; Commit() flushes, fsyncs and renames it over `path`. Destroying the writer
// without a successful Commit() removes the temporary and leaves `path` untouched.
class AtomicFileWriter {
 public:
  explicit AtomicFileWriter(std::string path);
  AtomicFileWriter(const AtomicFileWriter&) = delete;
  AtomicFileWriter& operator=(const AtomicFileWriter&) = delete;
  ~AtomicFileWriter();

  Status Open();
  Status Write(std::string_view chunk);
  Status Commit();

 private:
  std::string path_;
  std::string tmp_;
  int fd_ = -1;
};

}  // namespace metro
