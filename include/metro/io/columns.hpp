// The one vocabulary of session columns, quantities and units (docs/formats.md).
//
// A canonical column name is `<stem>_<suffix>`: the suffix names the unit ("gx_dps" is the
// gyroscope's x axis in deg/s, "t_ms" is time in milliseconds). Every module that needs to
// know what a column holds (the loaders, calibration, noise, the reports, the certificate)
// asks here instead of keeping its own suffix rules.
//
//   suffix  unit     dimension         to SI (value_si = value * to_si)
//   s       s        time              1
//   ms      ms       time              1e-3
//   us      us       time              1e-6
//   ns      ns       time              1e-9
//   deg     deg      angle             pi/180 rad
//   rad     rad      angle             1
//   dps     deg/s    angular rate      pi/180 rad/s
//   rads    rad/s    angular rate      1
//   g       g        acceleration      9.80665 m/s^2 (standard gravity, exact)
//   mps2    m/s^2    acceleration      1
//   lsb     LSB      raw count         (none: a count of the sensor's ADC)
//   c       degC     temperature       (offset scale: not converted)
//   hz      Hz       frequency         1
//   m       m        length            1
//   v       V        voltage           1
// and the dimensionless "1" of the quaternion components qw, qx, qy, qz (no suffix).
//
// Axis families: a sensor's three axes in one unit, e.g. {gx_dps, gy_dps, gz_dps}, and the
// quaternion {qw, qx, qy, qz}. A session may hold any subset of a family's columns; methods
// that need the whole family (calibration, quaternion-derived angles) ask MissingColumns.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace metro {

enum class Dimension {
  kDimensionless,  // "1": quaternion components.
  kTime,
  kAngle,
  kAngularRate,
  kAcceleration,
  kRawCount,  // LSB: counts of a sensor's ADC.
  kTemperature,
  kFrequency,
  kLength,
  kVoltage,
};

// "time", "angular rate", ...
const char* DimensionName(Dimension dimension);

struct Unit {
  std::string_view symbol;  // As in reports and JSON: "deg/s", "m/s^2", "LSB", "degC".
  std::string_view suffix;  // Column-name suffix without the underscore: "dps"; "" for "1".
  Dimension dimension = Dimension::kDimensionless;
  double to_si = 1.0;  // value_si = value * to_si; 0 where there is no SI scale (LSB, degC).
};

// The unit with this symbol ("deg/s") or column suffix ("dps"); nullptr if metro does not
// know it.
const Unit* UnitBySymbol(std::string_view symbol);
const Unit* UnitBySuffix(std::string_view suffix);

// Factor taking a value in `from` to `to` (value_to = value_from * factor): 1 from a unit to
// itself; nullopt when the dimensions differ or, between two different units, either has
// no SI scale (LSB, degC). Where quantities
// combine, this is the check that their units may.
std::optional<double> ConversionFactor(const Unit& from, const Unit& to);

// What a column name says of itself.
enum class ColumnRole {
  kTime,      // t_s, t_ms, t_us, t_ns
  kSensor,    // sensor
  kQuantity,  // a known numeric quantity
  kText,      // a known text column (payload_hex)
  kUnknown,   // not in the registry (carried through)
};

enum class SensorKind { kNone, kAccelerometer, kGyroscope, kQuaternion };

struct ColumnInfo {
  ColumnRole role = ColumnRole::kUnknown;
  const Unit* unit = nullptr;  // Known quantities and time; for unknown columns the
                               // suffix's unit when it has one; nullptr otherwise.
  SensorKind sensor = SensorKind::kNone;
  char axis = 0;             // 'x', 'y', 'z' (accelerometer, gyroscope) or 'w'.. (quaternion).
  std::string family;        // "accel_g", "gyro_dps", "quat", ... ; empty if none.
  bool allow_empty = false;  // An empty field means "unknown" (NaN).
  // The unit symbol ("" when none): what Quantity::unit holds.
  std::string UnitSymbol() const { return unit ? std::string(unit->symbol) : std::string(); }
};

ColumnInfo ClassifyColumn(std::string_view name);

// True if `name` is a legal canonical column name: [a-z][a-z0-9_]*.
bool IsValidColumnName(std::string_view name);

// The time columns in the order they are looked for: t_s, t_ms, t_us, t_ns.
const std::array<std::string_view, 4>& TimeColumnNames();

// The column of `sensor`'s `axis` in `unit`: AxisColumn(kGyroscope, 'x', deg/s) = "gx_dps";
// "" for SensorKind::kNone.
std::string AxisColumn(SensorKind sensor, char axis, const Unit& unit);

// The units an accelerometer or gyroscope column may have, raw counts first:
// accelerometer LSB, g, m/s^2; gyroscope LSB, deg/s, rad/s.
std::vector<const Unit*> AxisUnits(SensorKind sensor);

// The columns of a whole family: {"gx_dps","gy_dps","gz_dps"}, {"qw","qx","qy","qz"}.
std::vector<std::string> FamilyColumns(SensorKind sensor, const Unit* unit);

// Of the family's columns, those not in `present` (in family order).
std::vector<std::string> MissingColumns(const std::vector<std::string>& family,
                                        const std::vector<std::string>& present);

// A rate quantity: an accelerometer or gyroscope axis (any of its units), the input of
// Allan deviation and the IEEE 952 noise terms.
bool IsRateQuantity(std::string_view name);

// A component of the orientation quaternion (qw qx qy qz, dimensionless): evaluated, but not
// plotted by default (the Euler angles are plotted instead).
bool IsQuaternionComponent(std::string_view name);

}  // namespace metro
