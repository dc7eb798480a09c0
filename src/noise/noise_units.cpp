#include "metro/noise/noise_units.hpp"

#include <cmath>

namespace metro {
namespace {

constexpr double kStandardGravity = 9.80665;  // m/s^2, exact (CGPM 1901).
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
  if (q == "deg/s") {
    to_deg = 1.0;
    u.column_token = "dps";
  } else if (q == "rad/s") {
    to_deg = 180.0 / 3.14159265358979323846;
    u.column_token = "rads";
  } else if (q == "g") {
    to_mps2 = kStandardGravity;
    u.column_token = "g";
  } else if (q == "m/s^2") {
    to_mps2 = 1.0;
    u.column_token = "mps2";
  } else if (q == "LSB") {
    u.column_token = "lsb";
    u.known = true;
  } else if (q == "deg") {
    u.column_token = "deg";
    u.known = true;
  } else {
    u.column_token = "q";
  }
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
    t[kB].factor = to_mps2 / kStandardGravity * 1e6;
    t[kK].unit_conventional = "m/s/h/sqrt(h)";
    t[kK].factor = to_mps2 * h15;
    t[kR].unit_conventional = "m/s/h^2";
    t[kR].factor = to_mps2 * h * h;
    u.density.unit_conventional = "ug/sqrt(Hz)";
    u.density.factor = to_mps2 / kStandardGravity * 1e6;
  }
  return u;
}

}  // namespace metro
