#include "metro/core/status.hpp"

namespace metro {

std::string Error::ToString() const {
  std::string out;
  if (!file.empty()) {
    out += file;
    if (line > 0) {
      out += ":" + std::to_string(line);
      if (column > 0) out += ":" + std::to_string(column);
    }
    out += ": ";
  } else if (line > 0) {
    out += "line " + std::to_string(line) + ": ";
  }
  out += message;
  return out;
}

Error MakeError(std::string message) { return Error{"", 0, 0, std::move(message)}; }

Error MakeError(std::string file, int64_t line, std::string message) {
  return Error{std::move(file), line, 0, std::move(message)};
}

Error MakeError(std::string file, int64_t line, int64_t column, std::string message) {
  return Error{std::move(file), line, column, std::move(message)};
}

}  // namespace metro
