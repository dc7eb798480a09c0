// Units of the noise terms of a rate quantity [q], and their conventional forms. This is the
// one place where unit conversions of metro's noise module live.
//
// Base units follow from the model (noise_model.hpp): Q [q]*s, N [q]*sqrt(s), B [q],
// K [q]/sqrt(s), R [q]/s, and the one-sided white-noise density sqrt(2) N in [q]/sqrt(Hz).
// A datasheet's "noise density" is one-sided, so a white rate of density d has
// sigma(1 s) = N = d / sqrt(2) (MPU6050 gyro: 0.005 deg/s/sqrt(Hz) -> 0.0035 deg/s).
//
// Conventional units (value_conventional = value * factor):
//   quantity  Q         N             B      K               R         density
//   deg/s     arcsec    deg/sqrt(h)   deg/h  deg/h/sqrt(h)   deg/h^2   deg/s/sqrt(Hz)
//             x3600     x60           x3600  x216000         x1.296e7  x1
//   rad/s     the same after x180/pi
//   g         m/s       m/s/sqrt(h)   ug     m/s/h/sqrt(h)   m/s/h^2   ug/sqrt(Hz)
//             x9.80665  x9.80665*60   x1e6   x9.80665*216000 x9.80665*1.296e7  x1e6
//   m/s^2     as g without the 9.80665 (B: x1e6/9.80665 to ug; density x1e6/9.80665)
//   LSB, deg and any other unit: conventional = base (factor 1).
// (sqrt(s) = sqrt(h)/60; standard gravity g0 = 9.80665 m/s^2 exactly.)
#pragma once

#include <array>
#include <string>

#include "metro/noise/noise_model.hpp"

namespace metro {

struct UnitConversion {
  std::string unit;               // Base unit, e.g. "deg/s*sqrt(s)".
  std::string unit_conventional;  // e.g. "deg/sqrt(h)".
  double factor = 1.0;            // value_conventional = value * factor.
};

struct NoiseUnits {
  bool known = false;         // The quantity unit is in the table above.
  std::string quantity_unit;  // As given, e.g. "deg/s".
  std::string column_token;   // For CSV headers: "dps", "rads", "g", "mps2", "lsb", "deg".
  std::array<UnitConversion, kNoiseTermCount> terms;  // Indexed by NoiseTerm.
  UnitConversion density;                             // One-sided white-noise density sqrt(2) N.
};

NoiseUnits NoiseUnitsFor(const std::string& quantity_unit);

}  // namespace metro
