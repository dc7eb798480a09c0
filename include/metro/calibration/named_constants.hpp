// The constants of a calibration by name, as a spec (docs/conformity.md) and the registry
// (docs/registry.md) name them: "<sensor>.<parameter>" with the parameter names of
// calibration.json's `parameters` (docs/calibration-format.md):
//
//   accel.b_x accel.b_y accel.b_z        b0 [input unit]
//   accel.k_x accel.k_y accel.k_z        diagonal of K [output unit / input unit]
//   accel.a_yz accel.a_zy accel.a_zx     misalignment [rad]
//   accel.b1_x accel.b1_y accel.b1_z     temperature term [input unit / degC] (when fitted)
//   gyro.b_x ... gyro.g_yz gyro.g_zy gyro.g_xz gyro.g_zx gyro.g_xy gyro.g_yx gyro.b1_z
//
// Units are UDUNITS-2 text (metro/core/units.hpp): the calibration's `g` (standard gravity)
// is written g_n, so "g_n/LSB" for the scale of a raw accelerometer.
#pragma once

#include <string>
#include <vector>

#include "metro/calibration/calibrate.hpp"

namespace metro {

struct NamedConstant {
  std::string name;  // "accel.b_x"
  double value = 0.0;
  double u = 0.0;    // Standard uncertainty (k = 1); 0 for a constant the model holds.
  std::string unit;  // UDUNITS-2 text, e.g. "LSB", "g_n/LSB", "rad", "LSB/degC".
  // Row of the sensor's `covariance` (FreeNames order), -1 for a held constant.
  int covariance_index = -1;
};

// Every constant of the tag's sensors (accelerometer first), b, k, misalignment and, when the
// model has a temperature term, b1. Held constants (k of a `bias` model) are listed with u 0.
std::vector<NamedConstant> NamedConstants(const TagCalibration& tag);

// The UDUNITS-2 text of a calibration's unit symbol ("g" -> "g_n"; others unchanged).
std::string CalibrationUnitText(const std::string& symbol);

}  // namespace metro
