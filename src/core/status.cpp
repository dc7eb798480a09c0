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

Error Error::WithContext(const std::string& prefix) const {
  Error out = *this;
  out.message = prefix + ": " + message;
  return out;
}

Error Error::WithKind(ErrorKind new_kind) const {
  Error out = *this;
  out.kind = new_kind;
  return out;
}

const char* ErrorKindName(ErrorKind kind) {
  switch (kind) {
    case ErrorKind::kInput:
      return "input";
    case ErrorKind::kFailed:
      return "failed";
    case ErrorKind::kIo:
      return "io";
  }
  return "input";
}

Error MakeError(std::string message) { return Error{"", 0, 0, std::move(message)}; }

Error MakeError(std::string file, int64_t line, std::string message) {
  return Error{std::move(file), line, 0, std::move(message)};
}

Error MakeError(std::string file, int64_t line, int64_t column, std::string message) {
  return Error{std::move(file), line, column, std::move(message)};
}

Error MakeFailedError(std::string message) {
  return Error{"", 0, 0, std::move(message), ErrorKind::kFailed};
}

Error MakeFailedError(std::string file, int64_t line, std::string message) {
  return Error{std::move(file), line, 0, std::move(message), ErrorKind::kFailed};
}

Error MakeIoError(std::string message) {
  return Error{"", 0, 0, std::move(message), ErrorKind::kIo};
}

Error MakeIoError(std::string file, int64_t line, std::string message) {
  return Error{std::move(file), line, 0, std::move(message), ErrorKind::kIo};
}

}  // namespace metro
