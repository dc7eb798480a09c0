#include "metro/core/status.hpp"

#include <catch2/catch.hpp>

#include "metro/core/file.hpp"

namespace metro {
namespace {

TEST_CASE("Error renders file:line:column: message", "[core]") {
  CHECK(MakeError("a.csv", 12, 3, "expected a number").ToString() ==
        "a.csv:12:3: expected a number");
  CHECK(MakeError("a.csv", 12, "bad").ToString() == "a.csv:12: bad");
  CHECK(MakeError("a.csv", 0, "empty file").ToString() == "a.csv: empty file");
  CHECK(MakeError("oops").ToString() == "oops");
}

TEST_CASE("Result holds a value or an error", "[core]") {
  Result<int> good = 3;
  REQUIRE(good.ok());
  CHECK(good.value() == 3);
  Result<int> bad = MakeError("f", 1, "no");
  REQUIRE_FALSE(bad.ok());
  CHECK(bad.error().line == 1);
  CHECK_FALSE(bad.status().ok());
}

TEST_CASE("Error kinds: MakeError is input and MakeFailedError failed and MakeIoError io",
          "[core]") {
  CHECK(MakeError("bad row").kind == ErrorKind::kInput);
  CHECK(MakeError("a.csv", 3, "bad").kind == ErrorKind::kInput);
  CHECK(MakeError("a.csv", 3, 4, "bad").kind == ErrorKind::kInput);
  CHECK(MakeFailedError("did not converge").kind == ErrorKind::kFailed);
  CHECK(MakeFailedError("b.json", 0, "did not settle").kind == ErrorKind::kFailed);
  CHECK(MakeIoError("cannot write").kind == ErrorKind::kIo);
  CHECK(MakeIoError("out.json", 0, "cannot write").ToString() == "out.json: cannot write");
  CHECK(std::string(ErrorKindName(ErrorKind::kInput)) == "input");
  CHECK(std::string(ErrorKindName(ErrorKind::kFailed)) == "failed");
  CHECK(std::string(ErrorKindName(ErrorKind::kIo)) == "io");
  // A Status and a Result keep the kind.
  Result<int> r = MakeFailedError("no");
  CHECK(r.error().kind == ErrorKind::kFailed);
  CHECK(r.status().error().kind == ErrorKind::kFailed);
}

TEST_CASE("WithContext prefixes the message and keeps the kind and the position", "[core]") {
  const Error e = MakeError("s.csv", 12, 3, "expected a number").WithKind(ErrorKind::kFailed);
  const Error c = e.WithContext("sensor 4");
  CHECK(c.ToString() == "s.csv:12:3: sensor 4: expected a number");
  CHECK(c.kind == ErrorKind::kFailed);
  CHECK(c.file == "s.csv");
  CHECK(c.line == 12);
  CHECK(c.column == 3);
  CHECK(MakeIoError("disk full").WithContext("sensor 1").kind == ErrorKind::kIo);
  CHECK(MakeError("x").WithContext("a").WithContext("b").message == "b: a: x");
}

TEST_CASE("File errors: a missing directory and a device are input errors", "[core]") {
  // The directory does not exist: the output cannot be created where it was named.
  Status missing = WriteFileAtomically("/nonexistent-metro-dir/out.json", "{}");
  REQUIRE_FALSE(missing.ok());
  CHECK(missing.error().kind == ErrorKind::kInput);
  // A device is refused before anything is written (input).
  Status device = WriteFileAtomically("/dev/full", "{}");
  REQUIRE_FALSE(device.ok());
  CHECK(device.error().kind == ErrorKind::kInput);
}

}  // namespace
}  // namespace metro
