// A temporary file that holds a column of numbers on disk instead of in memory, for the
// streaming mode of long records (issue #38 step 2): the first pass appends each column as it
// parses the input, later passes read it back in order, as often as they need, through small
// buffers. The file is unlinked as soon as it is created (it disappears with the process,
// even one killed by SIGINT), in $TMPDIR or /tmp. Reads use pread: the file's pages stay in
// the page cache, not in the process's resident memory.
//
// Values are written and read back bit for bit (the raw bytes of T).
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "metro/core/status.hpp"

namespace metro {

class SpillFile {
 public:
  SpillFile() = default;
  SpillFile(const SpillFile&) = delete;
  SpillFile& operator=(const SpillFile&) = delete;
  SpillFile(SpillFile&& other) noexcept;
  SpillFile& operator=(SpillFile&& other) noexcept;
  ~SpillFile();

  // Creates the unlinked file. Errors name the directory and the system's reason.
  Status Open();
  bool is_open() const { return fd_ >= 0; }

  // Appends `bytes` bytes (buffered; Flush before reading).
  Status Append(const void* data, size_t bytes);
  Status Flush();
  // Bytes written, buffered ones included.
  uint64_t size() const { return written_ + buffer_.size(); }

  // Reads `bytes` bytes at `offset` (which must lie within the flushed size).
  Status ReadAt(uint64_t offset, void* out, size_t bytes) const;

 private:
  int fd_ = -1;
  uint64_t written_ = 0;
  std::vector<char> buffer_;
};

// Reads values [begin, begin + count) of a record into out: how the analyses of the streaming
// mode read a column, from a SpillColumn or, in tests, from memory.
using ChunkReader = std::function<Status(size_t begin, size_t count, double* out)>;

// A column of T in a SpillFile, appended once and read back in chunks.
template <typename T>
class SpillColumn {
 public:
  Status Open() { return file_.Open(); }
  Status Append(const T* values, size_t count) { return file_.Append(values, count * sizeof(T)); }
  Status Finish() { return file_.Flush(); }
  size_t size() const { return static_cast<size_t>(file_.size() / sizeof(T)); }
  // values[begin, begin + count) into out (Finish first).
  Status Read(size_t begin, size_t count, T* out) const {
    return file_.ReadAt(static_cast<uint64_t>(begin) * sizeof(T), out, count * sizeof(T));
  }

 private:
  SpillFile file_;
};

}  // namespace metro
