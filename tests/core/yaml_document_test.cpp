// The YAML reader of other tools' files (src/core/yaml_document.hpp): nodes keep their
// 1-based line and column; what it refuses, it refuses at file:line:column.
#include "core/yaml_document.hpp"

#include <catch2/catch.hpp>
#include <string>

#include "core/nearest_name.hpp"

namespace metro {
namespace {

TEST_CASE("YAML: block and flow nodes keep their positions", "[core][yaml]") {
  const std::string text =
      "%YAML:1.0\n"  // OpenCV FileStorage's header: read as a comment
      "imu0:\n"
      "  model: \"kalibr\"\n"
      "  M:\n"
      "  - [1, 2.5e-3, -.5]\n"
      "  rate: 0x10\n";
  const Result<YamlNode> r = ParseYaml(text, "a.yaml");
  INFO((r.ok() ? "" : r.error().ToString()));
  REQUIRE(r.ok());
  const YamlNode* imu = r.value().Find("imu0");
  REQUIRE(imu != nullptr);
  CHECK(imu->line == 3);
  CHECK(imu->column == 3);
  const YamlNode* model = imu->Find("model");
  REQUIRE(model != nullptr);
  CHECK(model->scalar == "kalibr");
  CHECK(model->quoted);
  CHECK_FALSE(model->Number());
  const YamlNode& row = imu->Find("M")->items.at(0);
  REQUIRE(row.items.size() == 3);
  CHECK(row.items[1].Number().value() == 2.5e-3);
  CHECK(row.items[2].Number().value() == -0.5);
  CHECK(row.items[2].line == 5);
  CHECK(row.items[2].column == 17);
  // Hexadecimal is not a YAML 1.1 float here: a string.
  CHECK_FALSE(imu->Find("rate")->Number());
  CHECK(imu->Find("rate")->Describe() == "the string \"0x10\"");
}

TEST_CASE("YAML: syntax errors, aliases, two documents and deep nesting are refused",
          "[core][yaml]") {
  CHECK(ParseYaml("a: [1, 2\n", "b.yaml").error().ToString().rfind("b.yaml:2:1: invalid YAML", 0) ==
        0);
  CHECK_THAT(ParseYaml("a: &x 1\nb: *x\n", "b.yaml").error().ToString(),
             Catch::StartsWith("b.yaml:1:4: a YAML anchor"));
  CHECK_THAT(ParseYaml("a: 1\n---\nb: 2\n", "b.yaml").error().ToString(),
             Catch::StartsWith("b.yaml:2:1: a second YAML document"));
  std::string deep;
  for (int i = 0; i < 40; ++i) deep += "[";
  for (int i = 0; i < 40; ++i) deep += "]";
  CHECK_THAT(ParseYaml(deep, "b.yaml").error().ToString(),
             Catch::Contains("YAML nested deeper than 32 levels"));
  // An empty document is an empty mapping.
  const Result<YamlNode> empty = ParseYaml("# nothing\n", "b.yaml");
  REQUIRE(empty.ok());
  CHECK(empty.value().IsMapping());
  CHECK(empty.value().members.empty());
}

TEST_CASE("Nearest name by edit distance", "[core][yaml]") {
  CHECK(Nearest("gyroscope", {"accelerometers", "gyroscopes", "model"}) == "gyroscopes");
  CHECK(Nearest("updte_rate", {"time_offset", "update_rate", "rostopic"}) == "update_rate");
  CHECK(Nearest("x", {}).empty());
}

}  // namespace
}  // namespace metro
