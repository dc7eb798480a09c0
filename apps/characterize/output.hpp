// Shared output rules of the characterize subcommands: never write over an input, say so
// when an existing output is replaced, write atomically; `-` is standard output
// (unix_cli.hpp).
#pragma once

#include <string>
#include <vector>

#include "metro/core/status.hpp"
#include "unix_cli.hpp"

namespace metro::apps {

// Error if `output` is one of `inputs` (an input `-` is stdin: the file behind it, if it is
// one); prints a note to stderr if it exists (not under --quiet). An `output` of `-`
// (stdout) is no file and always passes.
Status CheckOutputPath(const std::string& output, const std::vector<std::string>& inputs);

// Prints "error: <message>" to stderr.
void PrintError(const Error& error);

}  // namespace metro::apps
