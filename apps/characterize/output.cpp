
#include "output.hpp"

#include <fmt/format.h>
#include <sys/stat.h>

#include <cstdio>

#include "metro/core/file.hpp"

namespace metro::apps {

Status CheckOutputPath(const std::string& output, const std::vector<std::string>& inputs) {
  if (IsStdio(output)) return Status::Ok();
  for (const std::string& input : inputs) {
    // `characterize - -o s.csv < s.csv`: stdin's own file.
    const std::string file = IsStdio(input) ? "/dev/stdin" : input;
    if (output == input || IsSameFile(output, file)) {
      return MakeError(
          fmt::format("output {} is the input file: refusing to overwrite it", output));
    }
  }
  struct stat st {};
  if (::stat(output.c_str(), &st) == 0) {
    Note(fmt::format("note: replacing existing {}\n", output));
  }
  return Status::Ok();
}

void PrintError(const Error& error) { fmt::print(stderr, "error: {}\n", error.ToString()); }

}  // namespace metro::apps
