// The raw line format: good lines, saturation, and every class of bad line with its position.
#include "metro/station/raw_line.hpp"

#include <catch2/catch.hpp>

using metro::station::FormatRawLine;
using metro::station::IsSkippedRawLine;
using metro::station::ParseRawLine;
using metro::station::RawSample;

TEST_CASE("A raw line gives six counts and an optional clock", "[station]") {
  auto r = ParseRawLine("-412,83,16390,-12,40,7", "port", 3);
  REQUIRE(r.ok());
  CHECK(r.value().accel_lsb == std::array<int32_t, 3>{-412, 83, 16390});
  CHECK(r.value().gyro_lsb == std::array<int32_t, 3>{-12, 40, 7});
  CHECK_FALSE(r.value().t_ms.has_value());
  CHECK_FALSE(r.value().saturated);
  auto t = ParseRawLine(" 1, +2 ,3,4,5,6,\t1234.5\r", "port", 4);
  REQUIRE(t.ok());
  CHECK(t.value().accel_lsb[1] == 2);
  CHECK(t.value().t_ms.value() == 1234.5);
  // Round trip through the writer.
  auto back = ParseRawLine(FormatRawLine(t.value()), "x", 1);
  REQUIRE(back.ok());
  CHECK(back.value().t_ms.value() == 1234.5);
  CHECK(back.value().gyro_lsb == t.value().gyro_lsb);
}

TEST_CASE("A count at the int16 limit is saturated and names its axis", "[station]") {
  auto r = ParseRawLine("1,2,32767,4,5,6", "port", 9);
  REQUIRE(r.ok());
  CHECK(r.value().saturated);
  CHECK(r.value().saturated_axis == "az");
  auto g = ParseRawLine("1,2,3,-32768,5,6", "port", 9);
  REQUIRE(g.ok());
  CHECK(g.value().saturated_axis == "gx");
  CHECK_FALSE(ParseRawLine("1,2,32766,-32767,5,6", "port", 9).value().saturated);
}

TEST_CASE("A bad raw line is refused with line, column and the expected shape", "[station]") {
  struct Case {
    const char* line;
    const char* where;
    const char* what;
  };
  const Case cases[] = {
      {"1,2,16x90,4,5,6", "port:7:7:", "field 3 (az) \"16x90\" is not an integer count"},
      {"1,2,3,4,5", "port:7:10:", "5 fields where 6 or 7 are expected"},
      {"ax,ay,az,gx,gy,gz", "port:7:1:", "field 1 (ax) \"ax\" is not an integer count"},
      {"1,2,,4,5,6", "port:7:5:", "field 3 (az) \"\" is not an integer count"},
      {"1,2,3,4,5,6,7,8", "port:7:15:", "more than 7 fields"},
      {"1,2,40000,4,5,6", "port:7:5:", "field 3 (az) 40000 is outside the int16 range"},
      {"1,2,3,4,5,6,abc", "port:7:13:", "field 7 (t_ms) \"abc\" is not a time"},
      {"1.5,2,3,4,5,6", "port:7:2:", "field 1 (ax) \"1.5\" is not an integer count"},
      {"MPU6050 connection successful", "port:7:30:", "1 field where 6 or 7 are expected"},
  };
  for (const Case& c : cases) {
    auto r = ParseRawLine(c.line, "port", 7);
    INFO(c.line);
    REQUIRE_FALSE(r.ok());
    const std::string text = r.error().ToString();
    INFO(text);
    CHECK(text.rfind(c.where, 0) == 0);
    CHECK_THAT(text, Catch::Contains(c.what));
    CHECK_THAT(text, Catch::Contains("expected ax,ay,az,gx,gy,gz[,t_ms]"));
  }
}

TEST_CASE("Empty and comment lines are skipped by the reader, not the parser", "[station]") {
  CHECK(IsSkippedRawLine(""));
  CHECK(IsSkippedRawLine("  \r"));
  CHECK(IsSkippedRawLine("# started"));
  CHECK_FALSE(IsSkippedRawLine("1,2,3,4,5,6"));
  CHECK_FALSE(ParseRawLine("", "p", 1).ok());
}
