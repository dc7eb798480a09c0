// Error, Status and Result<T>: how the library reports expected failures.
//
// The library does not throw for bad input or a failed computation. A loader returns a
// Result<T> holding either the value or an Error that names the file, the 1-based line and
// column (0 when they do not apply) and what was expected. Error::ToString() renders the
// conventional "file:line:column: message" form used on the command line.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <variant>

#include "metro/core/check.hpp"

namespace metro {

struct Error {
  std::string file;     // Input file the error is about; empty if none.
  int64_t line = 0;     // 1-based line number; 0 when not about a line.
  int64_t column = 0;   // 1-based column (field for CSV); 0 when not about a column.
  std::string message;  // What was found and what was expected.

  // "file:line:column: message", omitting the parts that are empty or zero.
  std::string ToString() const;
};

// Convenience constructors.
Error MakeError(std::string message);
Error MakeError(std::string file, int64_t line, std::string message);
Error MakeError(std::string file, int64_t line, int64_t column, std::string message);

// Success, or an Error. A default-constructed Status is OK.
class Status {
 public:
  Status() = default;
  Status(Error error) : error_(std::move(error)) {}  // NOLINT: implicit by design.
  static Status Ok() { return Status(); }

  bool ok() const { return !error_.has_value(); }
  const Error& error() const {
    METRO_CHECK(error_.has_value());
    return *error_;
  }

 private:
  std::optional<Error> error_;
};

// A value of type T, or an Error.
template <typename T>
class Result {
 public:
  Result(T value) : data_(std::move(value)) {}      // NOLINT: implicit by design.
  Result(Error error) : data_(std::move(error)) {}  // NOLINT: implicit by design.
  Result(Status status) : data_(status.error()) {}  // NOLINT: only from a failed Status.

  bool ok() const { return std::holds_alternative<T>(data_); }
  const T& value() const& {
    METRO_CHECK(ok());
    return std::get<T>(data_);
  }
  T& value() & {
    METRO_CHECK(ok());
    return std::get<T>(data_);
  }
  T&& value() && {
    METRO_CHECK(ok());
    return std::get<T>(std::move(data_));
  }
  const Error& error() const {
    METRO_CHECK(!ok());
    return std::get<Error>(data_);
  }
  Status status() const { return ok() ? Status() : Status(error()); }

 private:
  std::variant<T, Error> data_;
};

}  // namespace metro
