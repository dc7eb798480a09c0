// File helpers: atomic output, whole-file input and SHA-256 of inputs.
#pragma once

#include <cstddef>
#include <functional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "metro/core/status.hpp"

namespace metro {

// Writes `contents` to `path` atomically: the data go to a temporary file in the same
// directory, are flushed to disk (fsync), and the temporary is renamed over `path`. A
// reader never sees a partial file and a failure leaves any previous `path` untouched.
// The rules of AtomicFileWriter apply (a replaced file keeps its mode; `path` must be
// replaceable, CheckReplaceableFile).
Status WriteFileAtomically(const std::string& path, std::string_view contents);

// Several files replaced together: all are written to temporaries and flushed first, and
// only when every one succeeded are they renamed into place, in order. A failure while
// writing (a full disk) leaves every previous file untouched. `files` are (path, contents).
Status WriteFilesAtomically(const std::vector<std::pair<std::string, std::string_view>>& files);

// Ok if `path` can be an output that metro replaces by renaming a new file over it: it does
// not exist yet, or it is a regular file (or a symlink to one; the link's target is
// replaced and the link kept), and the directory it goes into exists. Refused, with an
// error naming `path` and saying what to do instead: a directory, a character or block
// device (/dev/null, /dev/full), a FIFO, a socket, anything in /dev, /proc or /sys, a
// missing directory.
Status CheckReplaceableFile(const std::string& path);

// Ok if `path` can be a file metro reads and updates in place (the registry's SQLite file):
// it does not exist yet or is a regular file (or a symlink to one), and its directory
// exists. Refused as CheckReplaceableFile refuses, with an error naming `path`: a directory,
// a device, a FIFO, a socket, anything in /dev, /proc or /sys, a missing directory.
Status CheckUpdatableFile(const std::string& path);

// What ReadFile reads at most by default: 64 MiB, far above any document metro reads whole
// (reports, budgets, calibration.json, tags, specs, segments, column maps: kilobytes to a few
// megabytes), so /dev/zero or an endless FIFO named as one stops at once or at the bound.
inline constexpr int64_t kMaxDocumentBytes = int64_t{64} << 20;

// Reads a whole file of at most max_bytes (a regular file larger than that is refused before
// it is read; a FIFO or device when it reaches the bound). Errors name the path and the
// operating system's reason, or the bound.
Result<std::string> ReadFile(const std::string& path, int64_t max_bytes = kMaxDocumentBytes);

// Lower-case hex SHA-256 of a byte string and of a file's contents.
std::string Sha256Hex(std::string_view bytes);
Result<std::string> Sha256File(const std::string& path);

// The same digest, hashed front to back `chunk_bytes` at a time (0 is taken as 1), calling
// on_hashed(n) from the calling thread after each chunk, n being the bytes hashed so far
// (the last has n == bytes.size(); empty bytes make no call). Lets a reader sharing the
// bytes know which the hasher has finished with.
std::string Sha256Hex(std::string_view bytes, size_t chunk_bytes,
                      const std::function<void(size_t)>& on_hashed);

// True if both paths name the same file: the same device and inode when both exist (so
// through symlinks and hard links), else the same canonical path (symlinked directories
// and `..` resolved) for files not written yet. Used to refuse writing an output over an
// input or over another output of the same command.
bool IsSameFile(const std::string& a, const std::string& b);

// SIGINT, SIGTERM and SIGHUP while metro writes: the handler removes every temporary still
// registered (RemoveOnInterrupt: an AtomicFileWriter's until it is published, a plot's, a
// copy of stdin) and ends the process by the signal, as it would have ended without the
// handler. The old outputs stay as they were (nothing was renamed over them). A signal the
// caller ignores (SIG_IGN) stays ignored. SIGXFSZ is ignored, so a write past the file-size
// limit (ulimit -f) fails with EFBIG and takes the full-disk path (exit 1, old outputs kept)
// instead of killing the process. Both programs call it first in main.
void InstallInterruptCleanup();

// Registers a temporary file for the handler of InstallInterruptCleanup until Reset() or
// destruction (which unregister it; they do not remove the file). At most 64 files are
// registered at once; more are not (and are then left behind by a signal).
class RemoveOnInterrupt {
 public:
  RemoveOnInterrupt() = default;
  explicit RemoveOnInterrupt(const std::string& path);
  RemoveOnInterrupt(const RemoveOnInterrupt&) = delete;
  RemoveOnInterrupt& operator=(const RemoveOnInterrupt&) = delete;
  ~RemoveOnInterrupt();
  // Unregisters the file registered before, if any, and registers `path` (none if empty).
  void Reset(const std::string& path = "");

 private:
  int slot_ = -1;
};

}  // namespace metro

namespace metro {

// Streams a large output to `path` atomically: chunks go to a temporary file in the same
// directory; Commit() flushes, fsyncs and renames it over `path`. Destroying the writer
// without a successful Commit() removes the temporary and leaves `path` untouched; so does
// SIGINT or SIGTERM once InstallInterruptCleanup ran.
//
// The temporary is `.metro-XXXXXX` beside the target (O_EXCL, so never an existing file):
// short, so any name the file system accepts for `path` works. A file that is replaced
// keeps its permission bits (and, where allowed, its owner and group); a new file gets
// 0666 minus the umask. When `path` is a symlink, the file it points to is replaced and
// the link stays. Open() refuses a `path` that CheckReplaceableFile refuses.
class AtomicFileWriter {
 public:
  explicit AtomicFileWriter(std::string path);
  AtomicFileWriter(const AtomicFileWriter&) = delete;
  AtomicFileWriter& operator=(const AtomicFileWriter&) = delete;
  ~AtomicFileWriter();

  Status Open();
  Status Write(std::string_view chunk);
  // Finish() + Publish().
  Status Commit();
  // Flushes (fsync) and closes the temporary; `path` is still untouched.
  Status Finish();
  // Renames the finished temporary over `path`. Several writers finished first and then
  // published replace their files together (WriteFilesAtomically).
  Status Publish();

 private:
  std::string path_;    // As given, for messages.
  std::string target_;  // The file replaced: `path_`, or where the symlink `path_` points.
  std::string tmp_;
  int fd_ = -1;
  bool finished_ = false;
  RemoveOnInterrupt cleanup_;  // tmp_ while it exists.
};

}  // namespace metro
