#include "core/json_reader.hpp"

#include <catch2/catch.hpp>
#include <cmath>
#include <string>

namespace metro {
namespace {

JsonDocument Parsed(const std::string& text) {
  Result<JsonDocument> document = JsonDocument::Parse(text, "r.json");
  REQUIRE(document.ok());
  return std::move(document).value();
}

TEST_CASE("JSON reader: a wrong type deep inside is reported at its own line and column",
          "[core]") {
  // The string "x" opens at line 4, column 25 (counted by hand: five spaces, "type_a" in
  // columns 6-13, ':' 14, ' ' 15, '{' 16, "mean" 17-22, ':' 23, ' ' 24).
  const JsonDocument document = Parsed(
      "{\n"
      "  \"sensors\": [\n"
      "    {\"sensor\": 2,\n"
      "     \"type_a\": {\"mean\": \"x\"}}\n"
      "  ]\n"
      "}\n");
  const JsonCursor root(document);
  const JsonCursor sensor = root["sensors"][size_t{0}];
  CHECK(sensor["sensor"].Integer() == 2);
  CHECK(root.ok());
  CHECK(sensor["type_a"]["mean"].Number() == 0.0);
  REQUIRE_FALSE(root.ok());
  const Error e = root.error();
  CHECK(e.ToString() ==
        "r.json:4:25: sensors[0].type_a.mean: expected a number, found the string \"x\"");
  CHECK(e.kind == ErrorKind::kInput);
  // The first error of the reading is kept: later failures do not replace it.
  CHECK(sensor["sensor"].String().empty());
  CHECK(sensor.error().ToString() == e.ToString());
}

TEST_CASE("JSON reader: a missing member is reported at the object it is missing from", "[core]") {
  // The object of "window" opens at line 2, column 12 (" \"window\": {": the brace is 12th).
  const JsonDocument document = Parsed("{\"a\": 1,\n \"window\": {\"n\": 3}}");
  const JsonCursor root(document);
  CHECK(root["window"]["n"].Integer() == 3);
  CHECK_FALSE(root.Has("b"));
  CHECK(root["window"].Has("n"));
  CHECK(root["window"]["t_first_s"].Number() == 0.0);
  REQUIRE_FALSE(root.ok());
  CHECK(root.error().ToString() ==
        "r.json:2:12: window.t_first_s: expected a number, found nothing (the member is "
        "missing)");
}

TEST_CASE("JSON reader: brackets and quotes inside strings and escaped keys do not mislead it",
          "[core]") {
  // Line 1: "t"'s element 1 is the object at column 24, its member "u" holds true at column
  // 30. The key "a\u0062" is "ab"; its value "7" opens at line 2, column 13.
  const JsonDocument document = Parsed(
      "{\"s\": \"[{\\\"\", \"t\": [1, {\"u\": true}],\n"
      " \"a\\u0062\": \"7\"}");
  const JsonCursor root(document);
  CHECK(root["s"].String() == "[{\"");
  CHECK(root["t"][size_t{1}]["u"].Bool());
  CHECK(root["t"][size_t{1}]["u"].Number() == 0.0);
  REQUIRE_FALSE(root.ok());
  CHECK(root.error().ToString() == "r.json:1:30: t[1].u: expected a number, found true");

  const JsonCursor again(document);
  CHECK(again["ab"].Integer() == 0);
  CHECK(again.error().ToString() == "r.json:2:13: ab: expected an integer, found the string \"7\"");
}

TEST_CASE("JSON reader: integers, nulls and arrays", "[core]") {
  const JsonDocument document =
      Parsed("{\"i\": 3.0, \"f\": 3.5, \"n\": null, \"v\": [1, null, 2.5], \"w\": [1, \"2\"]}");
  {
    const JsonCursor root(document);
    CHECK(root["i"].Integer() == 3);
    CHECK(std::isnan(root["n"].NumberOrNaN()));
    CHECK(std::isinf(root["n"].NumberOrInfinity()));
    CHECK(root["i"].NumberOrInfinity() == 3.0);
    CHECK_FALSE(root["n"].OptionalNumber().has_value());
    CHECK_FALSE(root["absent"].OptionalNumber().has_value());
    CHECK_FALSE(root["absent"].OptionalString().has_value());
    const std::vector<double> v = root["v"].NumbersOrNaN();
    REQUIRE(v.size() == 3);
    CHECK(v[0] == 1.0);
    CHECK(std::isnan(v[1]));
    CHECK(v[2] == 2.5);
    CHECK(root.ok());
    CHECK(root["f"].Integer() == 0);
    CHECK(root.error().ToString() == "r.json:1:17: f: expected an integer, found the number 3.5");
  }
  {
    const JsonCursor root(document);
    CHECK(root["w"].Numbers().size() == 2);
    // Element 1 of "w", the string "2", opens at column 63.
    CHECK(root.error().ToString() ==
          "r.json:1:63: w[1]: expected a number, found the string \"2\"");
  }
  {
    const JsonCursor root(document);
    CHECK(root.Keys() == std::vector<std::string>{"i", "f", "n", "v", "w"});
    CHECK(root["v"].Size() == 3);
    CHECK(root["i"].Size() == 0);
    root["v"].Fail("an object");
    CHECK(root.error().ToString() == "r.json:1:38: v: expected an object, found an array");
  }
}

TEST_CASE("JSON reader: a model read from text in one call", "[core]") {
  // ReadJsonText: the model, or the first error of its reading.
  auto read = [](const JsonCursor& c) { return c["dof"].NumberOrInfinity(); };
  double (*reader)(const JsonCursor&) = read;
  Result<double> dof = ReadJsonText<double>("{\"dof\": null}", "d.json", reader);
  REQUIRE(dof.ok());
  CHECK(std::isinf(dof.value()));
  dof = ReadJsonText<double>("{\"dof\": \"many\"}", "d.json", reader);
  REQUIRE_FALSE(dof.ok());
  CHECK(dof.error().ToString() ==
        "d.json:1:9: dof: expected a number or null (infinite degrees of freedom), found the "
        "string \"many\"");
  dof = ReadJsonText<double>("{\"dof\": ", "d.json", reader);
  REQUIRE_FALSE(dof.ok());
  CHECK(dof.error().line == 1);
}

TEST_CASE("JSON reader: a syntax error is reported by Parse at its position", "[core]") {
  Result<JsonDocument> document = JsonDocument::Parse("{\n  \"a\": no}", "f.json");
  REQUIRE_FALSE(document.ok());
  CHECK(document.error().line == 2);
  CHECK(document.error().column == 9);
}

}  // namespace
}  // namespace metro
