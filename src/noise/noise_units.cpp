#include "metro/noise/noise_units.hpp"

#include <cmath>

#include "metro/io/columns.hpp"

namespace metro {
namespace {

constexpr double kSqrtHourInSqrtSeconds = 60.0;
constexpr double kSecondsPerHour = 3600.0;

UnitConversion Base(const std::string& unit) { return {unit, unit, 1.0}; }

}  // namespace

NoiseUnits NoiseUnitsFor(const std::string& quantity_unit) {
  NoiseUnits u;
  u.quantity_unit = quantity_unit;
  const std::string& q = quantity_unit;
  auto& t = u.terms;
  const int kQ = static_cast<int>(NoiseTerm::kQuantization);
  const int kN = static_cast<int>(NoiseTerm::kRandomWalk);
  const int kB = static_cast<int>(NoiseTerm::kBiasInstability);
  const int kK = static_cast<int>(NoiseTerm::kRateRandomWalk);
  const int kR = static_cast<int>(NoiseTerm::kRateRamp);
  t[kQ] = Base(q + "*s");
  t[kN] = Base(q + "*sqrt(s)");
  t[kB] = Base(q);
  t[kK] = Base(q + "/sqrt(s)");
  t[kR] = Base(q + "/s");
  u.density = Base(q + "/sqrt(Hz)");

  const double h = kSecondsPerHour;
  const double h15 = h * kSqrtHourInSqrtSeconds;  // s^-1.5 -> h^-1.5: 3600^1.5 = 216000
  double to_deg = 0.0;                            // Gyro: factor from [q] to deg/s.
  double to_mps2 = 0.0;                           // Accelerometer: factor from [q] to m/s^2.
  // The units of the table above (columns.hpp); any other has conventional = base.
  const Unit& deg_per_s = *UnitBySymbol("deg/s");
  const Unit& mps2 = *UnitBySymbol("m/s^2");
  const double standard_gravity_mps2 = UnitBySymbol("g")->to_si;  // 9.80665, exact.
  const Unit* unit = UnitBySymbol(q);
  const Dimension dimension = unit != nullptr ? unit->dimension : Dimension::kDimensionless;
  if (dimension == Dimension::kAngularRate) {
    to_deg = ConversionFactor(*unit, deg_per_s).value();
  } else if (dimension == Dimension::kAcceleration) {
    to_mps2 = ConversionFactor(*unit, mps2).value();
  } else if (dimension == Dimension::kRawCount || q == "deg") {
    u.known = true;
  }
  const bool tabled = to_deg > 0.0 || to_mps2 > 0.0 || u.known;
  u.column_token = tabled ? std::string(unit->suffix) : "q";
  if (to_deg > 0.0) {
    u.known = true;
    t[kQ].unit_conventional = "arcsec";
    t[kQ].factor = to_deg * 3600.0;
    t[kN].unit_conventional = "deg/sqrt(h)";
    t[kN].factor = to_deg * kSqrtHourInSqrtSeconds;
    t[kB].unit_conventional = "deg/h";
    t[kB].factor = to_deg * h;
    t[kK].unit_conventional = "deg/h/sqrt(h)";
    t[kK].factor = to_deg * h15;
    t[kR].unit_conventional = "deg/h^2";
    t[kR].factor = to_deg * h * h;
    u.density.unit_conventional = "deg/s/sqrt(Hz)";
    u.density.factor = to_deg;
  }
  if (to_mps2 > 0.0) {
    u.known = true;
    t[kQ].unit_conventional = "m/s";
    t[kQ].factor = to_mps2;
    t[kN].unit_conventional = "m/s/sqrt(h)";
    t[kN].factor = to_mps2 * kSqrtHourInSqrtSeconds;
    t[kB].unit_conventional = "ug";
    t[kB].factor = to_mps2 / standard_gravity_mps2 * 1e6;
    t[kK].unit_conventional = "m/s/h/sqrt(h)";
    t[kK].factor = to_mps2 * h15;
    t[kR].unit_conventional = "m/s/h^2";
    t[kR].factor = to_mps2 * h * h;
    u.density.unit_conventional = "ug/sqrt(Hz)";
    u.density.factor = to_mps2 / standard_gravity_mps2 * 1e6;
  }
  return u;
}

}  // namespace metro
