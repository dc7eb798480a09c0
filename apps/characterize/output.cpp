
#include "output.hpp"

#include <fmt/format.h>
#include <sys/stat.h>

#include <cstdio>

#include "metro/core/file.hpp"

namespace metro::apps {

Status CheckOutputPath(const std::string& output, const std::vector<std::string>& inputs) {
  for (const std::string& input : inputs) {
    if (output == input || IsSameFile(output, input)) {
      return MakeError(
          fmt::format("output {} is the input file: refusing to overwrite it", output));
    }
  }
  struct stat st {};
  if (::stat(output.c_str(), &st) == 0) {
    fmt::print(stderr, "note: replacing existing {}\n", output);
  }
  return Status::Ok();
}

void PrintError(const Error& error) { fmt::print(stderr, "error: {}\n", error.ToString()); }

}  // namespace metro::apps
