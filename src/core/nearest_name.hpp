// The nearest of a set of names to a misspelt one, for "unknown key ...; nearest: ..." messages.
// Private to the library and its tests.
#pragma once

#include <string>
#include <vector>

namespace metro {

// The element of `known` nearest to `key` by edit distance (Levenshtein: insertions, deletions,
// substitutions count 1), the first of equals; empty when `known` is.
std::string Nearest(const std::string& key, const std::vector<std::string>& known);

}  // namespace metro
