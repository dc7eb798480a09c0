#include "metro/io/columns.hpp"

#include <algorithm>
#include <array>

namespace metro {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kStandardGravityMps2 = 9.80665;  // CGPM 1901, exact.

constexpr std::array<Unit, 16> kUnits = {{
    {"s", "s", Dimension::kTime, 1.0},
    {"ms", "ms", Dimension::kTime, 1e-3},
    {"us", "us", Dimension::kTime, 1e-6},
    {"ns", "ns", Dimension::kTime, 1e-9},
    {"deg", "deg", Dimension::kAngle, kPi / 180.0},
    {"rad", "rad", Dimension::kAngle, 1.0},
    {"deg/s", "dps", Dimension::kAngularRate, kPi / 180.0},
    {"rad/s", "rads", Dimension::kAngularRate, 1.0},
    {"g", "g", Dimension::kAcceleration, kStandardGravityMps2},
    {"m/s^2", "mps2", Dimension::kAcceleration, 1.0},
    {"LSB", "lsb", Dimension::kRawCount, 0.0},
    {"degC", "c", Dimension::kTemperature, 0.0},
    {"Hz", "hz", Dimension::kFrequency, 1.0},
    {"m", "m", Dimension::kLength, 1.0},
    {"V", "v", Dimension::kVoltage, 1.0},
    {"1", "", Dimension::kDimensionless, 1.0},
}};

const Unit& U(std::string_view symbol) {
  const Unit* u = UnitBySymbol(symbol);
  return *u;
}

char SensorPrefix(SensorKind sensor) {
  switch (sensor) {
    case SensorKind::kAccelerometer:
      return 'a';
    case SensorKind::kGyroscope:
      return 'g';
    case SensorKind::kQuaternion:
      return 'q';
    case SensorKind::kNone:
      break;
  }
  return 0;
}

const char* FamilyStem(SensorKind sensor) {
  return sensor == SensorKind::kAccelerometer ? "accel" : "gyro";
}

}  // namespace

const char* DimensionName(Dimension dimension) {
  switch (dimension) {
    case Dimension::kDimensionless:
      return "dimensionless";
    case Dimension::kTime:
      return "time";
    case Dimension::kAngle:
      return "angle";
    case Dimension::kAngularRate:
      return "angular rate";
    case Dimension::kAcceleration:
      return "acceleration";
    case Dimension::kRawCount:
      return "raw count";
    case Dimension::kTemperature:
      return "temperature";
    case Dimension::kFrequency:
      return "frequency";
    case Dimension::kLength:
      return "length";
    case Dimension::kVoltage:
      return "voltage";
  }
  return "?";
}

const Unit* UnitBySymbol(std::string_view symbol) {
  for (const Unit& u : kUnits) {
    if (u.symbol == symbol) return &u;
  }
  return nullptr;
}

const Unit* UnitBySuffix(std::string_view suffix) {
  if (suffix.empty()) return nullptr;
  for (const Unit& u : kUnits) {
    if (u.suffix == suffix) return &u;
  }
  return nullptr;
}

std::optional<double> ConversionFactor(const Unit& from, const Unit& to) {
  if (from.dimension != to.dimension) return std::nullopt;
  if (&from == &to || from.symbol == to.symbol) return 1.0;
  if (from.to_si == 0.0 || to.to_si == 0.0) return std::nullopt;
  return from.to_si / to.to_si;
}

ColumnInfo ClassifyColumn(std::string_view name) {
  ColumnInfo info;
  if (name == "sensor") {
    info.role = ColumnRole::kSensor;
    return info;
  }
  if (name == "payload_hex") {
    info.role = ColumnRole::kText;
    return info;
  }
  for (std::string_view t : TimeColumnNames()) {
    if (name == t) {
      info.role = ColumnRole::kTime;
      info.unit = UnitBySuffix(name.substr(2));
      return info;
    }
  }
  if (name.size() == 2 && name[0] == 'q' &&
      std::string_view("wxyz").find(name[1]) != std::string_view::npos) {
    info.role = ColumnRole::kQuantity;
    info.unit = &U("1");
    info.sensor = SensorKind::kQuaternion;
    info.axis = name[1];
    info.family = "quat";
    return info;
  }
  // Axis columns: [ag][xyz]_<unit> with a unit of the sensor's.
  if (name.size() > 3 && (name[0] == 'a' || name[0] == 'g') &&
      (name[1] == 'x' || name[1] == 'y' || name[1] == 'z') && name[2] == '_') {
    const SensorKind sensor = name[0] == 'a' ? SensorKind::kAccelerometer : SensorKind::kGyroscope;
    const Unit* unit = UnitBySuffix(name.substr(3));
    for (const Unit* allowed : AxisUnits(sensor)) {
      if (allowed == unit) {
        info.role = ColumnRole::kQuantity;
        info.unit = unit;
        info.sensor = sensor;
        info.axis = name[1];
        info.family = std::string(FamilyStem(sensor)) + "_" + std::string(unit->suffix);
        return info;
      }
    }
  }
  if (name == "yaw_deg" || name == "pitch_deg" || name == "roll_deg") {
    info.role = ColumnRole::kQuantity;
    info.unit = &U("deg");
    return info;
  }
  if (name == "temp_c") {
    info.role = ColumnRole::kQuantity;
    info.unit = &U("degC");
    return info;
  }
  if (name == "table_rate_dps" || name == "table_angle_deg") {
    info.role = ColumnRole::kQuantity;
    info.unit = name == "table_rate_dps" ? &U("deg/s") : &U("deg");
    info.allow_empty = true;
    return info;
  }
  // Unknown: the unit its suffix implies, if any.
  info.role = ColumnRole::kUnknown;
  const size_t underscore = name.rfind('_');
  if (underscore != std::string_view::npos && underscore > 0) {
    info.unit = UnitBySuffix(name.substr(underscore + 1));
  }
  return info;
}

bool IsValidColumnName(std::string_view name) {
  if (name.empty() || !(name[0] >= 'a' && name[0] <= 'z')) return false;
  for (char c : name) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_';
    if (!ok) return false;
  }
  return true;
}

const std::array<std::string_view, 4>& TimeColumnNames() {
  static constexpr std::array<std::string_view, 4> kNames = {"t_s", "t_ms", "t_us", "t_ns"};
  return kNames;
}

std::string AxisColumn(SensorKind sensor, char axis, const Unit& unit) {
  if (sensor == SensorKind::kNone) return "";
  if (sensor == SensorKind::kQuaternion) return std::string{'q', axis};
  return std::string{SensorPrefix(sensor), axis, '_'} + std::string(unit.suffix);
}

std::vector<const Unit*> AxisUnits(SensorKind sensor) {
  switch (sensor) {
    case SensorKind::kAccelerometer:
      return {&U("LSB"), &U("g"), &U("m/s^2")};
    case SensorKind::kGyroscope:
      return {&U("LSB"), &U("deg/s"), &U("rad/s")};
    case SensorKind::kQuaternion:
      return {&U("1")};
    case SensorKind::kNone:
      break;
  }
  return {};
}

std::vector<std::string> FamilyColumns(SensorKind sensor, const Unit* unit) {
  std::vector<std::string> names;
  if (sensor == SensorKind::kQuaternion) {
    for (char a : std::string_view("wxyz")) names.push_back(std::string{'q', a});
    return names;
  }
  if (unit == nullptr || sensor == SensorKind::kNone) return names;
  for (char a : std::string_view("xyz")) names.push_back(AxisColumn(sensor, a, *unit));
  return names;
}

std::vector<std::string> MissingColumns(const std::vector<std::string>& family,
                                        const std::vector<std::string>& present) {
  std::vector<std::string> missing;
  for (const std::string& name : family) {
    if (std::find(present.begin(), present.end(), name) == present.end()) {
      missing.push_back(name);
    }
  }
  return missing;
}

bool IsRateQuantity(std::string_view name) {
  const ColumnInfo info = ClassifyColumn(name);
  return info.role == ColumnRole::kQuantity &&
         (info.sensor == SensorKind::kAccelerometer || info.sensor == SensorKind::kGyroscope);
}

bool IsQuaternionComponent(std::string_view name) {
  return name == "qw" || name == "qx" || name == "qy" || name == "qz";
}

}  // namespace metro
