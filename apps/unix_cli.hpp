// How both metro programs behave as Unix tools (docs/unix.md): `-` names standard input
// (a session) or standard output (a report), --version, --quiet, outputs that never
// destroy anything, and text that is safe on a terminal. Shared by both programs
// (unix_cli.cpp).
#pragma once

#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <initializer_list>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "exit_codes.hpp"
#include "metro/core/file.hpp"
#include "metro/core/status.hpp"
#include "metro/core/terminal_text.hpp"
#include "metro/core/version.hpp"

namespace metro::apps {

// `-` where a session is read names standard input (the library's LoadSession reads it);
// where an output is written, standard output.
inline bool IsStdio(const std::string& path) { return path == "-"; }

// --quiet: set while the command line is parsed (before any command runs), read by the
// commands. Quiet runs print no progress, notes or human-readable tables; results (a report
// on stdout, a file) and errors and warnings are never suppressed.
inline bool& QuietFlag() {
  static bool quiet = false;
  return quiet;
}
inline bool Quiet() { return QuietFlag(); }

// Everything below that prints text (errors, notes, tables, warnings) escapes the control
// characters in it (metro/core/terminal_text.hpp): file names, CSV headers, tag names and
// blob metadata never reach a terminal or a log raw. Errors are one line (a newline in
// them is shown as \n); notes, tables and warnings keep their own line breaks.

// Prints `text` to `stream` with its control characters escaped, line breaks kept.
inline void PrintText(std::FILE* stream, std::string_view text) {
  const std::string safe = EscapeControlCharsKeepLines(text);
  std::fwrite(safe.data(), 1, safe.size(), stream);
}

// Prints "error: <message>" to stderr, on one line.
inline void PrintError(const Error& error) {
  const std::string line = "error: " + EscapeControlChars(error.ToString()) + "\n";
  std::fwrite(line.data(), 1, line.size(), stderr);
}

// Prints "error: <message>" to stderr and returns the exit code of its kind (ExitCodeFor:
// 2 for bad input or usage, 1 for a run or a write that failed).
inline int PrintErrorExit(const Error& error) {
  PrintError(error);
  return ExitCodeFor(error);
}

// Prints "error: <message>" to stderr, on one line (a newline in `message` is shown as \n).
inline void PrintErrorText(std::string_view message) {
  const std::string line = "error: " + EscapeControlChars(message) + "\n";
  std::fwrite(line.data(), 1, line.size(), stderr);
}

// Prints "<prefix>warning: <text>" to stderr on one line: a warning is one record, so a
// newline in the data it quotes (a tag name, a file name, a label) is shown as \n.
inline void PrintWarning(std::string_view text, std::string_view prefix = "") {
  const std::string line = std::string(prefix) + "warning: " + EscapeControlChars(text) + "\n";
  std::fwrite(line.data(), 1, line.size(), stderr);
}

// Prints `text` (a note, "wrote FILE", a summary) to stderr unless --quiet.
inline void Note(std::string_view text) {
  if (!Quiet()) PrintText(stderr, text);
}

// Prints the human-readable table of a report unless --quiet: to stdout, or to stderr when
// the report itself goes to stdout (`output` is `-`).
inline void PrintTable(std::string_view table, const std::string& output) {
  if (Quiet()) return;
  std::FILE* stream = IsStdio(output) ? stderr : stdout;
  PrintText(stream, table);
  std::fflush(stream);
}

// Call last in main: output still buffered for stdout is flushed, and a write to stdout that
// failed at any point (`> /dev/full`, a closed descriptor) turns a successful `exit_code`
// into kExitFailed (1) with "error: cannot write to stdout: ...". Another exit code is kept.
int FinishStdout(int exit_code);

// True when `path` names an existing file (an output about to be replaced).
inline bool OutputExists(const std::string& path) {
  struct stat st {};
  return !path.empty() && !IsStdio(path) && ::stat(path.c_str(), &st) == 0;
}

// Prints "note: replaced existing FILE" (not under --quiet): called once the new file is in
// place, so a run that fails never claims to have replaced anything.
inline void NoteReplaced(const std::string& path) {
  Note(fmt::format("note: replaced existing {}\n", path));
}

// Writes `contents` to standard output (`path` is `-`; flushed, a failed write is an
// error, e.g. a full disk behind a redirection) or atomically to the file `path`.
inline Status WriteOutput(const std::string& path, std::string_view contents) {
  if (!IsStdio(path)) {
    const bool existed = OutputExists(path);
    if (Status s = WriteFileAtomically(path, contents); !s.ok()) return s;
    if (existed) NoteReplaced(path);
    return Status::Ok();
  }
  std::fwrite(contents.data(), 1, contents.size(), stdout);
  if (std::fflush(stdout) != 0 || std::ferror(stdout)) {
    return MakeIoError(std::string("cannot write to stdout: ") + std::strerror(errno));
  }
  return Status::Ok();
}

// The outputs of one run, replaced together: every file is written to its temporary and
// flushed, then the one that goes to stdout (if any) is written, and only when all of that
// succeeded are the files renamed into place. So a JSON report and its HTML are both
// replaced or neither is (a full disk while writing the second leaves the first as it was).
// Pairs of (path, contents); an empty path is skipped.
Status WriteOutputs(const std::vector<std::pair<std::string, std::string_view>>& outputs);

// A streamed output: the file `path` written atomically (AtomicFileWriter), or stdout
// when `path` is `-` (a failed write, e.g. a closed pipe or a full disk, is an error).
// Commit() = Finish() + Publish(); two outputs finished first and then published are
// replaced together.
class StreamedOutput {
 public:
  explicit StreamedOutput(std::string path) : path_(path), file_(std::move(path)) {}
  Status Open() { return IsStdio(path_) ? Status::Ok() : file_.Open(); }
  Status Write(std::string_view chunk) {
    if (!IsStdio(path_)) return file_.Write(chunk);
    if (std::fwrite(chunk.data(), 1, chunk.size(), stdout) != chunk.size()) {
      return MakeIoError(std::string("cannot write to stdout: ") + std::strerror(errno));
    }
    return Status::Ok();
  }
  Status Finish() { return IsStdio(path_) ? WriteOutput(path_, "") : file_.Finish(); }
  Status Publish() {
    if (IsStdio(path_)) return Status::Ok();
    const bool existed = OutputExists(path_);
    if (Status s = file_.Publish(); !s.ok()) return s;
    if (existed) NoteReplaced(path_);
    return Status::Ok();
  }
  Status Commit() {
    if (Status s = Finish(); !s.ok()) return s;
    return Publish();
  }

 private:
  std::string path_;
  AtomicFileWriter file_;
};

// Binary data (a blob) is not written to a terminal, as gzip refuses to.
inline Status CheckBinaryStdout(const std::string& path) {
  if (IsStdio(path) && ::isatty(STDOUT_FILENO)) {
    return MakeError("refusing to write binary data to a terminal: redirect stdout or name a file");
  }
  return Status::Ok();
}

// An option that cannot write to standard output: `-` is a usage error, not a file named
// "-". `why` says what to do instead.
inline Status RefuseStdout(const std::string& path, const std::string& option,
                           const std::string& why) {
  if (!IsStdio(path)) return Status::Ok();
  return MakeError(fmt::format("{} -: {}", option, why));
}

// At most one output goes to standard output.
inline Status CheckOneStdout(
    std::initializer_list<std::pair<const char*, const std::string*>> outs) {
  const char* first = nullptr;
  for (const auto& [option, path] : outs) {
    if (!IsStdio(*path)) continue;
    if (first != nullptr) {
      return MakeError(
          fmt::format("{} and {} both name stdout (-): give one a file", first, option));
    }
    first = option;
  }
  return Status::Ok();
}

// A path given on the command line and the option (or argument) that named it, e.g.
// {"-o", "report.json"}, {"--tag-registry", "tags.json"}, {"SESSION", "-"}.
struct NamedPath {
  std::string option;
  std::string path;
};

// The rule every command applies to its outputs before any work (docs/unix.md, "Outputs
// never destroy"); empty paths are skipped:
// - at most one output is `-` (CheckOneStdout); `-` is never checked further;
// - each output can be replaced: not a directory, device, FIFO or socket, not in /dev,
//   /proc or /sys, its directory exists (CheckReplaceableFile);
// - no output is the same file as an input (through symlinks and hard links; an input `-`
//   is the file behind stdin, if it is one) nor as another output (IsSameFile).
// - `updated` are files the command reads and updates in place (the registry's SQLite file,
//   an input and an output at once): each is absent or a regular file (CheckUpdatableFile),
//   and no output and no input is one of them;
// (The writers below print "note: replaced existing FILE" once an existing output was
// replaced.)
// Every error is a usage error (exit 2) and names both paths.
Status CheckOutputs(const std::vector<NamedPath>& outputs, const std::vector<NamedPath>& inputs,
                    const std::vector<NamedPath>& updated = {});

// Standard input is read once, and as a session only: at most one input may be `-`, and
// none with `imutk` (imu_tk pairs are read from named files).
inline Status CheckStdinInputs(const std::vector<std::string>& inputs, bool imutk = false) {
  int count = 0;
  for (const std::string& in : inputs) count += IsStdio(in) ? 1 : 0;
  if (count > 0 && imutk) {
    return MakeError("imu_tk files are read by name: stdin (-) takes a session.csv or a capture");
  }
  if (count > 1) return MakeError("stdin (-) can be read only once: name the other inputs");
  return Status::Ok();
}

}  // namespace metro::apps
