// "line:column" (1-based) of byte `offset` of `text`, counted here independently of the
// library's readers, for tests that check where an error points.
#pragma once

#include <cstddef>
#include <string>

namespace metro::testing {

inline std::string LineColumn(const std::string& text, size_t offset) {
  int line = 1, column = 1;
  for (size_t i = 0; i < offset && i < text.size(); ++i) {
    if (text[i] == '\n') {
      ++line;
      column = 1;
    } else {
      ++column;
    }
  }
  return std::to_string(line) + ":" + std::to_string(column);
}

}  // namespace metro::testing
