// Standard input as a session file (private to io): `-` where a loader takes a path.
//
// The loaders open their input by path more than once (format detection, the parse's
// mapping, the SHA-256) and map it, which a pipe does not allow. So standard input is first
// copied whole into an anonymous file, and the loaders open that by a path that lives as
// long as the copy: "/proc/self/fd/N". Where the copy lives:
//  - stdin is a regular file at offset 0 (`characterize - < s.csv`): no copy; the file
//    itself, through a duplicate of the descriptor;
//  - else an anonymous in-memory file (memfd_create(2), Linux), sealed once filled, so
//    its bytes cannot change under a mapping: it holds the whole input in memory (or swap);
//  - if memfd_create fails (old kernel, seccomp filter) or /proc is not mounted: an
//    unlinked temporary file in $TMPDIR (default /tmp). Without /proc it keeps its name
//    until the copy is destroyed.
#pragma once

#include <unistd.h>

#include <cstdint>
#include <string>

#include "metro/core/status.hpp"

namespace metro::internal {

// The path that names standard input on the command line and in LoadSession.
inline constexpr const char* kStdinPath = "-";
inline bool IsStdinPath(const std::string& path) { return path == kStdinPath; }

// The file name errors about reading standard input carry (Error::file).
inline constexpr const char* kStdinDisplayName = "<stdin>";

// Where a StdinFile's bytes are (see the top of this file).
enum class StdinStorage { kNone, kStdinItself, kMemfd, kTmpfile };

// What a stream (stdin, a FIFO, a character device named as the session) may hold at most
// by default: 4 GiB, above a day at 400 Hz of six channels as CSV (2.8 GB). The environment
// variable METRO_MAX_STREAM_BYTES (a whole number of bytes) sets another cap.
inline constexpr int64_t kDefaultMaxStreamBytes = int64_t{4} << 30;
inline constexpr const char* kMaxStreamBytesVariable = "METRO_MAX_STREAM_BYTES";

// The cap in force: METRO_MAX_STREAM_BYTES when set, else kDefaultMaxStreamBytes. Errors: the
// variable is set but is not a whole number of bytes >= 1.
Result<int64_t> MaxStreamBytes();

struct StdinCopyOptions {
  int source_fd = STDIN_FILENO;  // Read from here (tests use a pipe).
  bool try_memfd = true;         // false: straight to the temporary-file fallback (tests).
  std::string tmp_dir;           // Fallback directory; empty: $TMPDIR, else /tmp.
  // The stream's name in errors: "<stdin>", or the FIFO's or device's path.
  std::string display_name = kStdinDisplayName;
  int64_t max_bytes = 0;  // More is refused; 0: MaxStreamBytes().
};

// A file holding the bytes read from standard input. Owns its descriptor (closed, and a
// named fallback file removed, on destruction); path() opens the same bytes, read-only,
// while the object lives. Move-only.
class StdinFile {
 public:
  StdinFile() = default;
  StdinFile(StdinFile&& other) noexcept;
  StdinFile& operator=(StdinFile&& other) noexcept;
  StdinFile(const StdinFile&) = delete;
  StdinFile& operator=(const StdinFile&) = delete;
  ~StdinFile();

  int fd() const { return fd_; }
  // "/proc/self/fd/N", or the fallback file's name where /proc is not mounted.
  const std::string& path() const { return path_; }
  int64_t size_bytes() const { return size_bytes_; }
  StdinStorage storage() const { return storage_; }

 private:
  friend Result<StdinFile> CopyStdinToFile(const StdinCopyOptions& options);
  void Reset();

  int fd_ = -1;
  std::string path_;
  bool remove_path_ = false;  // The named fallback file, removed on destruction.
  int64_t size_bytes_ = 0;
  StdinStorage storage_ = StdinStorage::kNone;
};

// Reads `source_fd` to its end (EINTR retried, partial reads and writes continued, a
// non-blocking descriptor waited on with poll) into a StdinFile. An empty stdin gives an
// empty file, which the loaders then report as "empty file". Errors (Error::file is
// options.display_name, except the first, which needs no file name):
//  - more than max_bytes: the cap and how to raise it (an endless `yes |` stops there);
//  - NUL bytes in the first 64 KiB (binary data, /dev/zero): refused at once, not after the
//    cap;
//  - source_fd is a terminal: "reading a session from stdin, but stdin is a terminal: pipe
//    a file in or name it" (nobody is going to type a session);
//  - source_fd is closed: "stdin is closed: pipe a file in or name it";
//  - a read fails (the OS's reason);
//  - neither an in-memory nor a temporary file can be made or filled (e.g. ENOSPC, ENOMEM):
//    the message suggests naming the file instead.
Result<StdinFile> CopyStdinToFile(const StdinCopyOptions& options = {});

}  // namespace metro::internal
