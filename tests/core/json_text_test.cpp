#include "core/json_text.hpp"

#include <catch2/catch.hpp>
#include <cstdint>
#include <string>
#include <utility>

namespace metro {
namespace {

TEST_CASE("JSON text: errors at line and column, never an exception", "[core]") {
  // nlohmann::json's own position for a syntax error: it stops at the 'o' of "no".
  Result<nlohmann::json> r = ParseJsonText("{\n  \"a\": no}", "f.json");
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().file == "f.json");
  CHECK(r.error().line == 2);
  CHECK(r.error().column == 9);
  CHECK(r.error().message.rfind("invalid JSON: ", 0) == 0);

  // A number past DBL_MAX (1.7976931348623157e308) threw out_of_range 406, which terminated
  // the budget, registry, calibration and report readers (issue #20, fuzz/crashes/README.md).
  for (const char* huge : {"1e999", "-1e999", "1.8e308", "7.90436972062e8841"}) {
    const std::string text = std::string("{\"u\": [1.5, \"1e999\",\n   ") + huge + "]}";
    r = ParseJsonText(text, "b.json");
    REQUIRE_FALSE(r.ok());
    CHECK(r.error().line == 2);
    CHECK(r.error().column == 4);
    CHECK(r.error().message.find("number overflow parsing") != std::string::npos);
    CHECK(ParseOrderedJsonText(text, "b.json").error().ToString() == r.error().ToString());
  }
  // The largest double and the smallest subnormal are numbers like any other.
  r = ParseJsonText("[1.7976931348623157e308, 4.9e-324, -1.7976931348623157e308]", "ok.json");
  REQUIRE(r.ok());
  CHECK(r.value()[0].get<double>() == 1.7976931348623157e308);

  // Nesting: 64 levels parse; the bracket opening level 65 is named, brackets inside strings
  // do not count.
  CHECK(ParseJsonText(std::string(64, '[') + std::string(64, ']'), "d.json").ok());
  const std::string quoted = "[\"[[[[\\\"[[\", " + std::string(63, '[') + std::string(64, ']');
  CHECK(ParseJsonText(quoted, "q.json").ok());
  r = ParseJsonText("\n" + std::string(65, '{'), "deep.json");
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().line == 2);
  CHECK(r.error().column == 65);
  CHECK(r.error().message.rfind("JSON nested deeper than 64 levels", 0) == 0);
}

TEST_CASE("JSON text: an object of more than 4096 members is refused at the comma past them",
          "[core]") {
  // {"k0":0, ... "k{n-1}":n-1} on one line; the comma before member m sits right after
  // member m-1's text.
  auto object = [](int n) {
    std::string text = "{";
    for (int i = 0; i < n; ++i) text += (i ? "," : "") + ("\"k" + std::to_string(i) + "\":0");
    return text + "}";
  };
  CHECK(ParseOrderedJsonText(object(4096), "ok.json").ok());
  const std::string text = object(4097);
  Result<nlohmann::ordered_json> r = ParseOrderedJsonText(text, "wide.json");
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().line == 1);
  CHECK(static_cast<size_t>(r.error().column) == text.find(",\"k4096\"") + 1);
  CHECK(r.error().message.rfind("a JSON object with more than 4096 members", 0) == 0);
  CHECK(ParseJsonText(text, "wide.json").error().ToString() == r.error().ToString());
  // Arrays are not bounded, nor are members of nested objects counted with their parent's,
  // nor commas inside strings.
  std::string items = "[";
  for (int i = 0; i < 10000; ++i)
    items += i ? ",{\"a\":1,\"b\":\",,,,\"}" : "{\"a\":1,\"b\":\",,,,\"}";
  CHECK(ParseOrderedJsonText(items + "]", "items.json").ok());
  CHECK(
      ParseOrderedJsonText("{\"a\":" + object(4000) + ",\"b\":" + object(4000) + "}", "nested.json")
          .ok());
}

TEST_CASE("JSON text: the element of a top-level array is located at its opening brace", "[core]") {
  // Positions counted by hand: line 5 column 5 and line 6 column 5 open the two elements;
  // the key inside a string and the nested member of the same name are not the array.
  const std::string text =
      "{\n"
      "  \"note\": \"a \\\"tolerances\\\": [{ inside a string\",\n"
      "  \"nested\": {\"tolerances\": [{\"x\": 1}]},\n"
      "  \"tolerances\": [\n"
      "    {\"constant\": \"accel.b_x\", \"lower\": [1, {\"deep\": 2}]},\n"
      "    {\"constant\": \"gyro.b_y\"}\n"
      "  ]\n"
      "}\n";
  REQUIRE(ParseJsonText(text, "spec.json").ok());
  using LineColumn = std::pair<int64_t, int64_t>;
  CHECK(TopLevelArrayElementLineColumn(text, "tolerances", 0) == LineColumn{5, 5});
  CHECK(TopLevelArrayElementLineColumn(text, "tolerances", 1) == LineColumn{6, 5});
  CHECK(TopLevelArrayElementLineColumn(text, "tolerances", 2) == LineColumn{0, 0});
  CHECK(TopLevelArrayElementLineColumn(text, "missing", 0) == LineColumn{0, 0});
  CHECK(TopLevelArrayElementLineColumn(text, "note", 0) == LineColumn{0, 0});
}

}  // namespace
}  // namespace metro
