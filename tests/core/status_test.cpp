#include "metro/core/status.hpp"

#include <catch2/catch.hpp>

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

}  // namespace
}  // namespace metro
