#include "unix_cli.hpp"

#include <sys/stat.h>

#include <iostream>
#include <memory>

#include "exit_codes.hpp"

namespace metro::apps {

int FinishStdout(int exit_code) {
  errno = 0;
  const bool flushed = std::fflush(stdout) == 0;
  const int flush_errno = errno;
  std::cout.flush();
  if (flushed && !std::ferror(stdout) && !std::cout.fail()) return exit_code;
  if (exit_code != kExitOk) return exit_code;  // The error that matters was printed.
  return PrintErrorExit(MakeIoError(fmt::format(
      "cannot write to stdout: {}: the output is incomplete",
      flush_errno != 0 ? std::strerror(flush_errno) : "a write failed (a full disk?)")));
}

Status WriteOutputs(const std::vector<std::pair<std::string, std::string_view>>& outputs) {
  std::vector<std::unique_ptr<AtomicFileWriter>> files;
  const std::string_view* to_stdout = nullptr;
  for (const auto& [path, contents] : outputs) {
    if (path.empty()) continue;
    if (IsStdio(path)) {
      to_stdout = &contents;
      continue;
    }
    files.push_back(std::make_unique<AtomicFileWriter>(path));
    AtomicFileWriter& file = *files.back();
    // On an error the temporaries written so far go with their writers.
    if (Status s = file.Open(); !s.ok()) return s;
    if (Status s = file.Write(contents); !s.ok()) return s;
    if (Status s = file.Finish(); !s.ok()) return s;
  }
  if (to_stdout != nullptr) {
    if (Status s = WriteOutput("-", *to_stdout); !s.ok()) return s;
  }
  std::vector<std::string> replaced;
  for (const auto& output : outputs) {
    if (OutputExists(output.first)) replaced.push_back(output.first);
  }
  for (auto& file : files) {
    if (Status s = file->Publish(); !s.ok()) return s;
  }
  for (const std::string& path : replaced) NoteReplaced(path);
  return Status::Ok();
}

Status CheckOutputs(const std::vector<NamedPath>& outputs, const std::vector<NamedPath>& inputs,
                    const std::vector<NamedPath>& updated) {
  // Files updated in place: regular files, never an input (nor each other).
  for (size_t i = 0; i < updated.size(); ++i) {
    const NamedPath& file = updated[i];
    if (file.path.empty()) continue;
    if (Status s = CheckUpdatableFile(file.path); !s.ok()) {
      return MakeError(fmt::format("{} {}", file.option, s.error().message));
    }
    for (const NamedPath& in : inputs) {
      if (in.path.empty()) continue;
      const std::string other = IsStdio(in.path) ? "/dev/stdin" : in.path;
      if (file.path == in.path || IsSameFile(file.path, other)) {
        return MakeError(fmt::format(
            "{} {} is also an input of the command ({} {}): the command updates it in place; "
            "name another file",
            file.option, file.path, in.option, IsStdio(in.path) ? "- (stdin)" : in.path));
      }
    }
    for (size_t j = 0; j < i; ++j) {
      if (!updated[j].path.empty() &&
          (file.path == updated[j].path || IsSameFile(file.path, updated[j].path))) {
        return MakeError(fmt::format("{} and {} name the same file ({} {}, {} {})", file.option,
                                     updated[j].option, updated[j].option, updated[j].path,
                                     file.option, file.path));
      }
    }
  }
  const char* first_stdout = nullptr;
  for (const NamedPath& out : outputs) {
    if (!IsStdio(out.path)) continue;
    if (first_stdout != nullptr) {
      return MakeError(
          fmt::format("{} and {} both name stdout (-): give one a file", first_stdout, out.option));
    }
    first_stdout = out.option.c_str();
  }
  for (size_t i = 0; i < outputs.size(); ++i) {
    const NamedPath& out = outputs[i];
    if (out.path.empty() || IsStdio(out.path)) continue;
    if (Status s = CheckReplaceableFile(out.path); !s.ok()) {
      return MakeError(fmt::format("{} {}", out.option, s.error().message));
    }
    for (const NamedPath& in : inputs) {
      if (in.path.empty()) continue;
      // `characterize - -o s.csv < s.csv`: stdin's own file.
      const std::string file = IsStdio(in.path) ? "/dev/stdin" : in.path;
      if (out.path == in.path || IsSameFile(out.path, file)) {
        return MakeError(fmt::format(
            "{} {} is the input file: refusing to overwrite it ({} {}); name another output file",
            out.option, out.path, in.option, IsStdio(in.path) ? "- (stdin)" : in.path));
      }
    }
    for (const NamedPath& file : updated) {
      if (file.path.empty()) continue;
      if (out.path == file.path || IsSameFile(out.path, file.path)) {
        return MakeError(fmt::format(
            "{} {} is the file the command updates in place ({} {}): refusing to overwrite "
            "it; name another output file",
            out.option, out.path, file.option, file.path));
      }
    }
    for (size_t j = 0; j < i; ++j) {
      const NamedPath& other = outputs[j];
      if (other.path.empty() || IsStdio(other.path)) continue;
      if (out.path == other.path || IsSameFile(out.path, other.path)) {
        return MakeError(
            fmt::format("{} and {} name the same file ({} {}, {} {}): give each "
                        "output its own file",
                        out.option, other.option, other.option, other.path, out.option, out.path));
      }
    }
  }
  return Status::Ok();
}

}  // namespace metro::apps
