// The one vocabulary of session columns, quantities and units (metro/io/columns.hpp), checked
// against docs/formats.md's column table and the units' definitions: 1 deg = pi/180 rad (SI
// Brochure, 9th ed., table 8), 1 g = 9.80665 m/s^2 (3rd CGPM, 1901), 1 ms = 1e-3 s.
#include "metro/io/columns.hpp"

#include <catch2/catch.hpp>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

namespace metro {
namespace {

struct Expected {
  const char* name;
  ColumnRole role;
  const char* unit;  // Symbol; "" for none.
  SensorKind sensor;
  char axis;
  const char* family;
};

// docs/formats.md, "session.csv": every canonical column with its unit and meaning.
const Expected kCanonical[] = {
    {"t_s", ColumnRole::kTime, "s", SensorKind::kNone, 0, ""},
    {"sensor", ColumnRole::kSensor, "", SensorKind::kNone, 0, ""},
    {"qw", ColumnRole::kQuantity, "1", SensorKind::kQuaternion, 'w', "quat"},
    {"qx", ColumnRole::kQuantity, "1", SensorKind::kQuaternion, 'x', "quat"},
    {"qy", ColumnRole::kQuantity, "1", SensorKind::kQuaternion, 'y', "quat"},
    {"qz", ColumnRole::kQuantity, "1", SensorKind::kQuaternion, 'z', "quat"},
    {"yaw_deg", ColumnRole::kQuantity, "deg", SensorKind::kNone, 0, ""},
    {"pitch_deg", ColumnRole::kQuantity, "deg", SensorKind::kNone, 0, ""},
    {"roll_deg", ColumnRole::kQuantity, "deg", SensorKind::kNone, 0, ""},
    {"ax_g", ColumnRole::kQuantity, "g", SensorKind::kAccelerometer, 'x', "accel_g"},
    {"ay_g", ColumnRole::kQuantity, "g", SensorKind::kAccelerometer, 'y', "accel_g"},
    {"az_g", ColumnRole::kQuantity, "g", SensorKind::kAccelerometer, 'z', "accel_g"},
    {"ax_mps2", ColumnRole::kQuantity, "m/s^2", SensorKind::kAccelerometer, 'x', "accel_mps2"},
    {"ay_mps2", ColumnRole::kQuantity, "m/s^2", SensorKind::kAccelerometer, 'y', "accel_mps2"},
    {"az_mps2", ColumnRole::kQuantity, "m/s^2", SensorKind::kAccelerometer, 'z', "accel_mps2"},
    {"ax_lsb", ColumnRole::kQuantity, "LSB", SensorKind::kAccelerometer, 'x', "accel_lsb"},
    {"ay_lsb", ColumnRole::kQuantity, "LSB", SensorKind::kAccelerometer, 'y', "accel_lsb"},
    {"az_lsb", ColumnRole::kQuantity, "LSB", SensorKind::kAccelerometer, 'z', "accel_lsb"},
    {"gx_dps", ColumnRole::kQuantity, "deg/s", SensorKind::kGyroscope, 'x', "gyro_dps"},
    {"gy_dps", ColumnRole::kQuantity, "deg/s", SensorKind::kGyroscope, 'y', "gyro_dps"},
    {"gz_dps", ColumnRole::kQuantity, "deg/s", SensorKind::kGyroscope, 'z', "gyro_dps"},
    {"gx_rads", ColumnRole::kQuantity, "rad/s", SensorKind::kGyroscope, 'x', "gyro_rads"},
    {"gy_rads", ColumnRole::kQuantity, "rad/s", SensorKind::kGyroscope, 'y', "gyro_rads"},
    {"gz_rads", ColumnRole::kQuantity, "rad/s", SensorKind::kGyroscope, 'z', "gyro_rads"},
    {"gx_lsb", ColumnRole::kQuantity, "LSB", SensorKind::kGyroscope, 'x', "gyro_lsb"},
    {"gy_lsb", ColumnRole::kQuantity, "LSB", SensorKind::kGyroscope, 'y', "gyro_lsb"},
    {"gz_lsb", ColumnRole::kQuantity, "LSB", SensorKind::kGyroscope, 'z', "gyro_lsb"},
    {"temp_c", ColumnRole::kQuantity, "degC", SensorKind::kNone, 0, ""},
    {"table_rate_dps", ColumnRole::kQuantity, "deg/s", SensorKind::kNone, 0, ""},
    {"table_angle_deg", ColumnRole::kQuantity, "deg", SensorKind::kNone, 0, ""},
    {"payload_hex", ColumnRole::kText, "", SensorKind::kNone, 0, ""},
};

TEST_CASE("ClassifyColumn knows every canonical column of docs/formats.md", "[io][columns]") {
  for (const Expected& e : kCanonical) {
    INFO(e.name);
    const ColumnInfo info = ClassifyColumn(e.name);
    CHECK(info.role == e.role);
    CHECK(info.UnitSymbol() == e.unit);
    CHECK(info.sensor == e.sensor);
    CHECK(info.axis == e.axis);
    CHECK(info.family == e.family);
    CHECK(IsValidColumnName(e.name));
    // Only the table columns may be empty ("unknown").
    const std::string name = e.name;
    CHECK(info.allow_empty == (name == "table_rate_dps" || name == "table_angle_deg"));
  }
}

TEST_CASE("Time columns: t_s, t_ms, t_us, t_ns in that order, with their units", "[io][columns]") {
  const std::vector<std::string> names(TimeColumnNames().begin(), TimeColumnNames().end());
  CHECK(names == std::vector<std::string>{"t_s", "t_ms", "t_us", "t_ns"});
  const struct {
    const char* name;
    const char* unit;
    double seconds;  // One unit in seconds.
  } kTimes[] = {
      {"t_s", "s", 1.0}, {"t_ms", "ms", 1e-3}, {"t_us", "us", 1e-6}, {"t_ns", "ns", 1e-9}};
  const Unit& second = *UnitBySymbol("s");
  for (const auto& t : kTimes) {
    INFO(t.name);
    const ColumnInfo info = ClassifyColumn(t.name);
    CHECK(info.role == ColumnRole::kTime);
    REQUIRE(info.unit != nullptr);
    CHECK(info.UnitSymbol() == t.unit);
    CHECK(info.unit->dimension == Dimension::kTime);
    CHECK(info.sensor == SensorKind::kNone);
    CHECK(ConversionFactor(*info.unit, second).value() == Approx(t.seconds).epsilon(1e-15));
  }
  // t_min is not a time column: "min" is no unit of metro's.
  CHECK(ClassifyColumn("t_min").role == ColumnRole::kUnknown);
}

TEST_CASE("Unknown columns carry the unit their suffix implies, or none", "[io][columns]") {
  const struct {
    const char* name;
    const char* unit;
  } kUnknown[] = {
      {"foo_hz", "Hz"},    {"bar_c", "degC"},      {"supply_v", "V"},      {"baseline_m", "m"},
      {"lag_s", "s"},      {"heading_deg", "deg"}, {"spin_rads", "rad/s"}, {"count_lsb", "LSB"},
      {"wx_dps", "deg/s"}, {"ext_mps2", "m/s^2"},  {"ext_ax_g", "g"},      {"gx_c", "degC"},
      {"foo", ""},         {"foo_bar", ""},        {"foo_", ""},           {"q1", ""},
      {"qa", ""},          {"gw_dps", "deg/s"}};
  for (const auto& u : kUnknown) {
    INFO(u.name);
    const ColumnInfo info = ClassifyColumn(u.name);
    CHECK(info.role == ColumnRole::kUnknown);
    CHECK(info.UnitSymbol() == u.unit);
    CHECK(info.sensor == SensorKind::kNone);
    CHECK(info.axis == 0);
    CHECK(info.family.empty());
  }
  // An axis name in a unit that is not the sensor's (temperature for a gyroscope axis, g for a
  // gyroscope, deg/s for an accelerometer) is no axis column.
  CHECK(ClassifyColumn("gx_g").role == ColumnRole::kUnknown);
  CHECK(ClassifyColumn("ax_dps").role == ColumnRole::kUnknown);
  CHECK(ClassifyColumn("ax_dps").UnitSymbol() == "deg/s");
}

TEST_CASE("Column names: [a-z][a-z0-9_]*", "[io][columns]") {
  CHECK(IsValidColumnName("a"));
  CHECK(IsValidColumnName("x_1_2"));
  CHECK_FALSE(IsValidColumnName(""));
  CHECK_FALSE(IsValidColumnName("Pitch (deg)"));
  CHECK_FALSE(IsValidColumnName("1x"));
  CHECK_FALSE(IsValidColumnName("_x"));
  CHECK_FALSE(IsValidColumnName("ax-g"));
  CHECK_FALSE(IsValidColumnName("aX_g"));
}

TEST_CASE("Units by symbol and by suffix name the same unit", "[io][columns]") {
  const struct {
    const char* symbol;
    const char* suffix;
    Dimension dimension;
  } kUnits[] = {{"s", "s", Dimension::kTime},
                {"ms", "ms", Dimension::kTime},
                {"us", "us", Dimension::kTime},
                {"ns", "ns", Dimension::kTime},
                {"deg", "deg", Dimension::kAngle},
                {"rad", "rad", Dimension::kAngle},
                {"deg/s", "dps", Dimension::kAngularRate},
                {"rad/s", "rads", Dimension::kAngularRate},
                {"g", "g", Dimension::kAcceleration},
                {"m/s^2", "mps2", Dimension::kAcceleration},
                {"LSB", "lsb", Dimension::kRawCount},
                {"degC", "c", Dimension::kTemperature},
                {"Hz", "hz", Dimension::kFrequency},
                {"m", "m", Dimension::kLength},
                {"V", "v", Dimension::kVoltage}};
  for (const auto& u : kUnits) {
    INFO(u.symbol);
    const Unit* by_symbol = UnitBySymbol(u.symbol);
    REQUIRE(by_symbol != nullptr);
    CHECK(by_symbol == UnitBySuffix(u.suffix));
    CHECK(by_symbol->suffix == u.suffix);
    CHECK(by_symbol->dimension == u.dimension);
  }
  REQUIRE(UnitBySymbol("1") != nullptr);
  CHECK(UnitBySymbol("1")->dimension == Dimension::kDimensionless);
  CHECK(UnitBySuffix("") == nullptr);  // The dimensionless unit has no suffix to look up.
  CHECK(UnitBySymbol("") == nullptr);
  CHECK(UnitBySymbol("dps") == nullptr);  // A suffix is not a symbol.
  CHECK(UnitBySuffix("deg/s") == nullptr);
  CHECK(UnitBySymbol("furlong") == nullptr);
  CHECK(std::string(DimensionName(Dimension::kAngularRate)) == "angular rate");
}

TEST_CASE("ConversionFactor: the units' definitions, and nothing across dimensions",
          "[io][columns]") {
  const double pi = std::acos(-1.0);
  auto factor = [](const char* from, const char* to) {
    return ConversionFactor(*UnitBySymbol(from), *UnitBySymbol(to));
  };
  // 1 deg = pi/180 rad.
  REQUIRE(factor("deg/s", "rad/s"));
  CHECK(*factor("deg/s", "rad/s") == Approx(pi / 180.0).epsilon(1e-15));
  CHECK(*factor("rad/s", "deg/s") == Approx(180.0 / pi).epsilon(1e-15));
  CHECK(*factor("deg", "rad") == Approx(pi / 180.0).epsilon(1e-15));
  // 1 g = 9.80665 m/s^2 exactly (a definition: no rounding allowed).
  REQUIRE(factor("g", "m/s^2"));
  CHECK(*factor("g", "m/s^2") == 9.80665);
  CHECK(*factor("m/s^2", "g") == Approx(1.0 / 9.80665).epsilon(1e-15));
  // Time.
  CHECK(*factor("ms", "s") == 1e-3);
  CHECK(*factor("s", "ms") == Approx(1e3).epsilon(1e-15));
  CHECK(*factor("ns", "us") == Approx(1e-3).epsilon(1e-15));
  // Identity.
  for (const char* u : {"s", "deg", "deg/s", "g", "LSB", "degC", "1", "Hz"}) {
    INFO(u);
    REQUIRE(factor(u, u));
    CHECK(*factor(u, u) == 1.0);
  }
  // Round trips: a factor and its reverse multiply to 1.
  for (const auto& [a, b] : std::vector<std::pair<const char*, const char*>>{
           {"deg/s", "rad/s"}, {"g", "m/s^2"}, {"ms", "ns"}, {"deg", "rad"}}) {
    INFO(a << " <-> " << b);
    CHECK(*factor(a, b) * *factor(b, a) == Approx(1.0).epsilon(1e-15));
  }
  // Different dimensions never convert.
  CHECK_FALSE(factor("deg/s", "g"));
  CHECK_FALSE(factor("g", "deg/s"));
  CHECK_FALSE(factor("deg", "deg/s"));
  CHECK_FALSE(factor("s", "Hz"));
  CHECK_FALSE(factor("1", "rad"));
  // Raw counts and degC have no SI scale: no conversion to a physical unit.
  CHECK_FALSE(factor("LSB", "g"));
  CHECK_FALSE(factor("LSB", "deg/s"));
  CHECK_FALSE(factor("g", "LSB"));
  CHECK_FALSE(factor("degC", "s"));
}

TEST_CASE("AxisColumn, FamilyColumns and ClassifyColumn agree", "[io][columns]") {
  const Unit& dps = *UnitBySymbol("deg/s");
  CHECK(AxisColumn(SensorKind::kGyroscope, 'x', dps) == "gx_dps");
  CHECK(AxisColumn(SensorKind::kAccelerometer, 'z', *UnitBySymbol("m/s^2")) == "az_mps2");
  CHECK(AxisColumn(SensorKind::kQuaternion, 'w', *UnitBySymbol("1")) == "qw");
  CHECK(FamilyColumns(SensorKind::kGyroscope, &dps) ==
        std::vector<std::string>{"gx_dps", "gy_dps", "gz_dps"});
  CHECK(FamilyColumns(SensorKind::kQuaternion, nullptr) ==
        std::vector<std::string>{"qw", "qx", "qy", "qz"});
  CHECK(FamilyColumns(SensorKind::kGyroscope, nullptr).empty());

  // The units of each sensor, raw counts first.
  auto symbols = [](SensorKind s) {
    std::vector<std::string> out;
    for (const Unit* u : AxisUnits(s)) out.emplace_back(u->symbol);
    return out;
  };
  CHECK(symbols(SensorKind::kAccelerometer) == std::vector<std::string>{"LSB", "g", "m/s^2"});
  CHECK(symbols(SensorKind::kGyroscope) == std::vector<std::string>{"LSB", "deg/s", "rad/s"});
  CHECK(symbols(SensorKind::kQuaternion) == std::vector<std::string>{"1"});
  CHECK(AxisUnits(SensorKind::kNone).empty());

  // Round trip: every family column classifies back to its sensor, axis, unit and family.
  for (SensorKind s :
       {SensorKind::kAccelerometer, SensorKind::kGyroscope, SensorKind::kQuaternion}) {
    for (const Unit* u : AxisUnits(s)) {
      const std::vector<std::string> family = FamilyColumns(s, u);
      const std::string axes = s == SensorKind::kQuaternion ? "wxyz" : "xyz";
      REQUIRE(family.size() == axes.size());
      for (size_t i = 0; i < family.size(); ++i) {
        INFO(family[i]);
        const ColumnInfo info = ClassifyColumn(family[i]);
        CHECK(info.role == ColumnRole::kQuantity);
        CHECK(info.sensor == s);
        CHECK(info.unit == u);
        CHECK(info.axis == axes[i]);
        CHECK(info.family == ClassifyColumn(family[0]).family);
        CHECK(AxisColumn(s, info.axis, *u) == family[i]);
      }
    }
  }
}

TEST_CASE("MissingColumns lists the family's absent columns in family order", "[io][columns]") {
  const std::vector<std::string> gyro =
      FamilyColumns(SensorKind::kGyroscope, UnitBySymbol("deg/s"));
  const std::vector<std::string> quat = FamilyColumns(SensorKind::kQuaternion, nullptr);
  using Names = std::vector<std::string>;
  // One gyroscope axis is a valid session; the family is then two columns short.
  CHECK(MissingColumns(gyro, {"t_s", "gz_dps"}) == Names{"gx_dps", "gy_dps"});
  CHECK(MissingColumns(gyro, {"gz_dps", "gy_dps", "gx_dps"}).empty());
  CHECK(MissingColumns(gyro, {}) == gyro);
  // Another unit's columns do not complete the family.
  CHECK(MissingColumns(gyro, {"gx_rads", "gy_rads", "gz_rads"}) == gyro);
  CHECK(MissingColumns(quat, {"qx", "sensor", "qw"}) == Names{"qy", "qz"});
  CHECK(MissingColumns({}, {"qw"}).empty());
}

TEST_CASE("IsRateQuantity: the 18 accelerometer and gyroscope axis columns", "[io][columns]") {
  const char* kRates[] = {"ax_g",    "ay_g",    "az_g",    "ax_mps2", "ay_mps2", "az_mps2",
                          "ax_lsb",  "ay_lsb",  "az_lsb",  "gx_dps",  "gy_dps",  "gz_dps",
                          "gx_rads", "gy_rads", "gz_rads", "gx_lsb",  "gy_lsb",  "gz_lsb"};
  for (const char* name : kRates) {
    INFO(name);
    CHECK(IsRateQuantity(name));
  }
  for (const char* name : {"yaw_deg", "pitch_deg", "roll_deg", "temp_c", "qw", "qx", "t_s", "t_ms",
                           "sensor", "payload_hex", "table_rate_dps", "table_angle_deg", "wx_dps",
                           "gx_g", "ax_dps", "foo_hz", ""}) {
    INFO(name);
    CHECK_FALSE(IsRateQuantity(name));
  }
}

}  // namespace
}  // namespace metro
