// Shared output rules of the characterize subcommands: never write over an input, say so
// when an existing output is replaced, write atomically.
#pragma once

#include <string>
#include <vector>

#include "metro/core/status.hpp"

namespace metro::apps {

// Error if `output` is one of `inputs`; prints a note to stderr if it exists.
Status CheckOutputPath(const std::string& output, const std::vector<std::string>& inputs);

// Prints "error: <message>" to stderr.
void PrintError(const Error& error);

}  // namespace metro::apps
