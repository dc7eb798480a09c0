// Error, Status and Result<T>: how the library reports expected failures.
//
// The library does not throw for bad input or a failed computation. A loader returns a
// Result<T> holding either the value or an Error that names the file, the 1-based line and
// column (0 when they do not apply) and what was expected. Error::ToString() renders the
// conventional "file:line:column: message" form used on the command line.
//
// Every Error carries a kind, set where it is created (the programs map it to their exit
// code, docs/unix.md "Exit codes"):
//   ErrorKind::kInput   bad input or usage: a malformed row, a missing or unreadable input
//                       file, an unknown option value, invalid options, an output path that
//                       cannot be created (a missing directory, a device). Exit 2.
//                       The default: MakeError(...) makes one.
//   ErrorKind::kFailed  the run itself failed on valid input: a fit that did not converge,
//                       an adaptive Monte Carlo that did not settle, a failed batch session,
//                       no valid calibration found. Exit 1. MakeFailedError(...).
//   ErrorKind::kIo      a write that failed after it started: a full disk, `> /dev/full`, a
//                       rename or fsync that failed. Exit 1. MakeIoError(...).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <variant>

#include "metro/core/check.hpp"

namespace metro {

// What kind of failure an Error is (see above).
enum class ErrorKind {
  kInput,   // Bad input or usage (exit 2).
  kFailed,  // The run failed on valid input (exit 1).
  kIo,      // A write failed after it started (exit 1).
};

// "input", "failed" or "io".
const char* ErrorKindName(ErrorKind kind);

struct Error {
  std::string file;     // Input file the error is about; empty if none.
  int64_t line = 0;     // 1-based line number; 0 when not about a line.
  int64_t column = 0;   // 1-based column (field for CSV); 0 when not about a column.
  std::string message;  // What was found and what was expected.
  ErrorKind kind = ErrorKind::kInput;

  // "file:line:column: message", omitting the parts that are empty or zero.
  std::string ToString() const;

  // The same error (kind, file, line, column kept) with "prefix: " before its message, e.g.
  // WithContext("sensor 3") on "12 samples; ..." gives "sensor 3: 12 samples; ...".
  Error WithContext(const std::string& prefix) const;

  // The same error with another kind, for a caller that knows better than the function that
  // made it (e.g. a page rendered from the run's own results: a failure is not the input's).
  Error WithKind(ErrorKind new_kind) const;
};

// Convenience constructors. MakeError makes an input error (ErrorKind::kInput).
Error MakeError(std::string message);
Error MakeError(std::string file, int64_t line, std::string message);
Error MakeError(std::string file, int64_t line, int64_t column, std::string message);
// A run that failed on valid input (ErrorKind::kFailed).
Error MakeFailedError(std::string message);
Error MakeFailedError(std::string file, int64_t line, std::string message);
// A write that failed after it started (ErrorKind::kIo).
Error MakeIoError(std::string message);
Error MakeIoError(std::string file, int64_t line, std::string message);

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
