// The spec library (issue #40 step 5): the shipped figures, unit factors by closed form, the
// ADIS16448 sources' disagreement from the published values, the datasheet -> Kalibr
// conversion, and every class of bad input at its file:line:column.
#include "metro/noise/spec_library.hpp"

#include <catch2/catch.hpp>
#include <cmath>
#include <map>
#include <string>

#include "metro/noise/noise_config_reader.hpp"
#include "support/text_position.hpp"

namespace metro {
namespace {

const std::string kLibrary = METRO_SOURCE_DIR "/datasets/specs/specs.json";
constexpr double kPi = 3.14159265358979323846;

const SpecLibrary& Shipped() {
  static const SpecLibrary lib = [] {
    Result<SpecLibrary> r = LoadSpecLibrary(kLibrary);
    REQUIRE(r.ok());
    return r.value();
  }();
  return lib;
}

const SpecPart& Part(const char* name) {
  Result<const SpecPart*> p = Shipped().Find(name);
  REQUIRE(p.ok());
  return *p.value();
}

std::optional<double> Value(const SpecSourceRow& row, const std::string& source) {
  for (const SpecSourceValue& v : row.values) {
    if (v.source == source) return v.value;
  }
  return std::nullopt;
}

TEST_CASE("spec units convert by their closed-form factors", "[specs]") {
  CHECK(SpecUnitOf("deg/s/sqrt(Hz)")->si_factor == Approx(kPi / 180.0).epsilon(1e-15));
  CHECK(SpecUnitOf("mdps/sqrt(Hz)")->si_factor == Approx(kPi / 180000.0).epsilon(1e-15));
  CHECK(SpecUnitOf("ug/sqrt(Hz)")->si_factor == Approx(9.80665e-6).epsilon(1e-15));
  CHECK(SpecUnitOf("mg")->si_factor == Approx(9.80665e-3).epsilon(1e-15));
  CHECK(SpecUnitOf("deg/h")->si_factor == Approx(kPi / 648000.0).epsilon(1e-15));
  CHECK(SpecUnitOf("deg/sqrt(h)")->si_factor == Approx(kPi / 10800.0).epsilon(1e-15));
  CHECK(SpecUnitOf("m/s/sqrt(h)")->si_factor == Approx(1.0 / 60.0).epsilon(1e-15));
  CHECK(SpecUnitOf("ug/sqrt(Hz)")->si_unit == "m/s^2/sqrt(Hz)");
  CHECK_FALSE(SpecUnitOf("dps/rtHz"));
}

TEST_CASE("the shipped library holds the published figures as printed", "[specs]") {
  const SpecPart& mpu = Part("mpu-6050");  // Spelling-insensitive.
  CHECK(mpu.part == "MPU6050");
  REQUIRE(mpu.figures.size() == 2);
  CHECK(mpu.figures[0].value == 0.005);
  CHECK(mpu.figures[0].kind == SpecKind::kUnstated);  // Column not visible: not "typ".
  CHECK(mpu.Document("datasheet")->number == "PS-MPU-6000A-00");
  // N = d / sqrt(2) (docs/noise.md section 5): 0.005 deg/s/sqrt(Hz) -> rad/s/sqrt(Hz).
  CHECK(mpu.figures[0].CoefficientSi() ==
        Approx(0.005 * kPi / 180.0 / std::sqrt(2.0)).epsilon(1e-14));
  CHECK(Part("MPU9250").figures[1].value == 300.0);
  CHECK(Part("ICM-20948").figures[0].value == 230.0);
  CHECK(Part("ICM-42688-P").figures[0].kind == SpecKind::kUnstated);
  Result<const SpecPart*> missing = Shipped().Find("BMI999");
  REQUIRE_FALSE(missing.ok());
  CHECK_THAT(missing.error().message,
             Catch::Contains("no part 'BMI999'") && Catch::Contains("MPU6050, MPU9250"));
}

TEST_CASE("ADIS16448: EuRoC's accelerometer random walk is 6.93x Kalibr's", "[specs]") {
  const SpecPart& adis = Part("ADIS16448");
  bool seen = false;
  for (const SpecSourceRow& row : CompareSpecSources(adis)) {
    if (row.kalibr_key != "accelerometer_random_walk") continue;
    seen = true;
    // The published values: EuRoC sensor.yaml 3.0000e-3, Kalibr's imu.yaml 4.33e-04.
    REQUIRE(Value(row, "euroc_sensor_yaml") == 3.0e-3);
    REQUIRE(Value(row, "kalibr_imu_yaml") == 4.33e-4);
    CHECK(*Value(row, "euroc_sensor_yaml") / *Value(row, "kalibr_imu_yaml") ==
          Approx(6.928406466512702).epsilon(1e-12));
  }
  CHECK(seen);
  Result<std::string> table = SpecSourcesTable(adis, "kalibr_imu_yaml");
  REQUIRE(table.ok());
  CHECK_THAT(table.value(), Catch::Contains("ratio 6.928"));  // accelerometer_random_walk
  CHECK_THAT(table.value(), Catch::Contains("ratio 1.075"));  // 2.0e-3 / 1.86e-3
  CHECK_FALSE(SpecSourcesTable(adis, "nope").ok());
}

TEST_CASE("datasheet -> Kalibr: N = d/sqrt(2) in SI, K refused by name", "[specs]") {
  const SpecPart& mpu = Part("MPU6050");
  SpecToKalibrOptions o;
  o.update_rate_hz = 200.0;
  Result<std::string> refused = SpecToKalibrYaml(mpu, o, kLibrary);
  REQUIRE_FALSE(refused.ok());
  CHECK_THAT(refused.error().message,
             Catch::Contains("accelerometer_random_walk, gyroscope_random_walk: refused") &&
                 Catch::Contains("not a random walk"));
  o.partial = true;
  Result<std::string> text = SpecToKalibrYaml(mpu, o, kLibrary);
  REQUIRE(text.ok());
  CHECK_THAT(text.value(), Catch::Contains("N = d / sqrt(2)") &&
                               Catch::Contains("NOT WRITTEN: accelerometer_random_walk"));
  Result<NoiseConfigFile> back = ReadNoiseConfig(text.value(), "imu.yaml");
  REQUIRE(back.ok());
  std::map<std::string, double> v;
  for (const NoiseConfigEntry& e : back.value().entries) {
    if (e.number) v[e.key] = *e.number;
  }
  CHECK(v.at("accelerometer_noise_density") ==
        Approx(400e-6 * 9.80665 / std::sqrt(2.0)).epsilon(1e-15));
  CHECK(v.at("gyroscope_noise_density") ==
        Approx(0.005 * kPi / 180.0 / std::sqrt(2.0)).epsilon(1e-15));
  CHECK(v.at("update_rate") == 200.0);
  CHECK(v.count("accelerometer_random_walk") == 0);
  o.update_rate_hz = std::nan("");
  CHECK_THAT(SpecToKalibrYaml(mpu, o, kLibrary).error().message,
             Catch::Contains("--update-rate-hz"));
  // ADIS16448 has only published configs here: no datasheet to convert.
  o.update_rate_hz = 200.0;
  CHECK_FALSE(SpecToKalibrYaml(Part("ADIS16448"), o, kLibrary).ok());
  // ICM-20948: no gyroscope figure in the library (SOURCE.md lists it missing).
  CHECK_THAT(SpecToKalibrYaml(Part("ICM20948"), o, kLibrary).error().message,
             Catch::Contains("no gyroscope noise figure"));
}

TEST_CASE("datasheet -> Kalibr with every term given writes the four keys", "[specs]") {
  // A test part (not a datasheet): ARW 0.5 deg/sqrt(h), VRW 0.06 m/s/sqrt(h) as N, and K.
  const std::string text = R"j({"schema": "metro.specs/1", "parts": [{"part": "T1", "names": [],
  "manufacturer": "m", "documents": [{"id": "ds", "title": "t", "number": "n", "revision": "1",
  "read_at": "here"}], "figures": [
  {"source": "ds", "sensor": "gyroscope", "convention": "random_walk_coefficient", "kind": "typ",
   "value": 0.5, "unit": "deg/sqrt(h)", "printed": "0.5", "page": "1", "table": "T"},
  {"source": "ds", "sensor": "accelerometer", "convention": "random_walk_coefficient",
   "kind": "typ", "value": 0.06, "unit": "m/s/sqrt(h)", "printed": "0.06", "page": "1",
   "table": "T"},
  {"source": "ds", "sensor": "gyroscope", "convention": "bias_random_walk_coefficient",
   "kind": "typ", "value": 1e-5, "unit": "rad/s^2/sqrt(Hz)", "printed": "1e-5", "page": "1",
   "table": "T"},
  {"source": "ds", "sensor": "accelerometer", "convention": "bias_random_walk_coefficient",
   "kind": "typ", "value": 2e-4, "unit": "m/s^3/sqrt(Hz)", "printed": "2e-4", "page": "1",
   "table": "T"}]}]})j";
  Result<SpecLibrary> lib = ParseSpecLibrary(text, "t.json");
  REQUIRE(lib.ok());
  SpecToKalibrOptions o;
  o.update_rate_hz = 400.0;
  o.rostopic = "/imu";
  Result<std::string> yaml = SpecToKalibrYaml(lib.value().parts.front(), o, "t.json");
  REQUIRE(yaml.ok());
  CHECK(yaml.value().find("NOT WRITTEN") == std::string::npos);
  Result<NoiseConfigFile> back = ReadNoiseConfig(yaml.value(), "imu.yaml");
  REQUIRE(back.ok());
  std::map<std::string, std::string> v;
  for (const NoiseConfigEntry& e : back.value().entries) v[e.key] = e.text;
  // ARW and VRW are N already (no sqrt(2)): deg/sqrt(h) = pi/180/60 rad/sqrt(s).
  CHECK(std::stod(v.at("gyroscope_noise_density")) ==
        Approx(0.5 * kPi / 180.0 / 60.0).epsilon(1e-15));
  CHECK(std::stod(v.at("accelerometer_noise_density")) == Approx(0.06 / 60.0).epsilon(1e-15));
  CHECK(std::stod(v.at("gyroscope_random_walk")) == 1e-5);
  CHECK(std::stod(v.at("accelerometer_random_walk")) == 2e-4);
  CHECK(v.at("rostopic") == "/imu");
  o.source = "nope";
  CHECK_THAT(SpecToKalibrYaml(lib.value().parts.front(), o, "t.json").error().message,
             Catch::Contains("no datasheet document with noise figures named nope"));
}

// A one-part library with `figure` as its only figure.
std::string OnePart(const std::string& figure) {
  return R"j({"schema": "metro.specs/1", "parts": [{"part": "X1", "names": [],
  "manufacturer": "m", "documents": [{"id": "ds", "title": "t", "number": "n",
  "revision": "1", "read_at": "here"}], "figures": [)j" +
         figure + "]}]}";
}

const std::string kGood =
    R"j({"source": "ds", "sensor": "gyroscope", "convention": "one_sided_density", "kind": "max",
  "value": 0.01, "unit": "deg/s/sqrt(Hz)", "printed": "0.01", "page": "1", "table": "T"})j";

std::string Replace(std::string s, const std::string& from, const std::string& to) {
  s.replace(s.find(from), from.size(), to);
  return s;
}

void ExpectError(const std::string& text, const std::string& at, const std::string& what) {
  Result<SpecLibrary> r = ParseSpecLibrary(text, "s.json");
  REQUIRE_FALSE(r.ok());
  const std::string where = "s.json:" + testing::LineColumn(text, text.find(at));
  CHECK_THAT(r.error().ToString(), Catch::StartsWith(where) && Catch::Contains(what));
}

TEST_CASE("spec library bad input stops at file:line:column", "[specs]") {
  REQUIRE(ParseSpecLibrary(OnePart(kGood), "s.json").ok());
  const std::string good = OnePart(kGood);
  ExpectError(Replace(good, "\"page\"", "\"pgae\""), "\"1\", \"table\"",
              "no member 'pgae' (a spec entry holds source, sensor");
  ExpectError(Replace(good, "\"max\"", "\"maximum\""), "\"maximum\"",
              "a kind (typ, min, max, unstated, config), not 'maximum'");
  ExpectError(Replace(good, "deg/s/sqrt(Hz)", "ug/sqrt(Hz)"), "\"ug/sqrt(Hz)\"",
              "a unit of a gyroscope one_sided_density figure (deg/s/sqrt(Hz), mdps/sqrt(Hz)");
  ExpectError(Replace(good, "0.01,", "-0.01,"), "-0.01", "a finite non-negative number");
  ExpectError(Replace(good, "\"gyroscope\"", "\"gyro\""), "\"gyro\"",
              "\"gyroscope\" or \"accelerometer\", not 'gyro'");
  ExpectError(Replace(good, "\"source\": \"ds\"", "\"source\": \"dx\""), "\"dx\"",
              "the id of one of X1's documents, not 'dx'");
  ExpectError(Replace(good, "metro.specs/1", "metro.specs/2"), "\"metro.specs/2\"",
              "\"metro.specs/1\", not 'metro.specs/2'");
  ExpectError(Replace(good, "\"convention\": \"one_sided_density\", ", ""), "{\"source\": \"ds\"",
              "convention");
  // The same part twice (spelled differently): at the second one's name.
  const std::string two = Replace(good, "]}]}",
                                  "]}, {\"part\": \"x-1\", \"names\": [], "
                                  "\"manufacturer\": \"m\", \"documents\": [], \"figures\": []}]}");
  ExpectError(two, "\"x-1\"", "a part named once, not 'x-1' again");
  Result<SpecLibrary> syntax = ParseSpecLibrary("{\"schema\": ", "s.json");
  REQUIRE_FALSE(syntax.ok());
  CHECK_THAT(syntax.error().ToString(), Catch::StartsWith("s.json:1:"));
}

}  // namespace
}  // namespace metro
