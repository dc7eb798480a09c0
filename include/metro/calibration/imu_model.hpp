// The sensor error model of the accelerometer and gyroscope calibration.
//
//   calibrated = M * (raw - b(temp_c)),   M = T * K,
//   b(temp_c)  = b0 + b1 * (temp_c - t_ref_c)        (b1 only when a temperature term is fitted)
//
// The bias is removed BEFORE scaling (as imu_tk does; basalt removes it after), so b0 and b1 are
// in input units (LSB, g, m/s^2, deg/s or rad/s) and M maps input units to output units (g for
// the accelerometer, deg/s for the gyroscope).
//
//   K = diag(k_x, k_y, k_z)          scale, output units per input unit
//   T (accelerometer, 3 terms)       T (gyroscope, 6 terms)
//     [ 1  -a_yz   a_zy ]             [  1     -g_yz   g_zy ]
//     [ 0    1    -a_zx ]             [  g_xz    1    -g_zx ]
//     [ 0    0      1   ]             [ -g_xy   g_yx    1   ]
//
// The accelerometer's axes define the body frame (its x axis is the body x axis and its x-y
// plane the body x-y plane), which is why its T has only 3 terms; the gyroscope's T then
// expresses the gyroscope axes in that body frame. The terms are small angles [rad].
//
// Parameter layout (the order of the covariance matrices in calibration.json):
//   accelerometer  [b0(3), k(3), a_yz a_zy a_zx, b1(3)]
//   gyroscope      [b0(3), k(3), g_yz g_zy g_xz g_zx g_xy g_yx, b1(3)]
// Identity: b0 = 0, k = 1, all misalignment terms 0, b1 = 0.
//
// Models: kBias estimates b0 only (K held at its nominal value, T = I); kScale estimates b0 and
// K (T = I); kFull estimates b0, K and T. Any of them may add b1 (linear temperature term).
#pragma once

#include <Eigen/Core>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "metro/io/columns.hpp"

namespace metro {

enum class ModelKind { kBias, kScale, kFull };
const char* ModelKindName(ModelKind kind);  // "bias", "scale", "full"
std::optional<ModelKind> ParseModelKind(std::string_view name);

enum class ImuSensor { kAccel, kGyro };
const char* ImuSensorName(ImuSensor sensor);  // "accel", "gyro"

// Number of misalignment terms: 3 for the accelerometer, 6 for the gyroscope.
int MisalignmentCount(ImuSensor sensor);

// T from the misalignment terms in the layout above (`terms` holds MisalignmentCount values).
Eigen::Matrix3d MisalignmentMatrix(ImuSensor sensor, const double* terms);

struct SensorModel {
  ImuSensor sensor = ImuSensor::kAccel;
  ModelKind kind = ModelKind::kFull;
  std::string input_unit;                           // "LSB", "g", "m/s^2", "deg/s", "rad/s".
  std::string output_unit;                          // "g" (accelerometer) or "deg/s" (gyroscope).
  Eigen::Vector3d bias = Eigen::Vector3d::Zero();   // b0 [input unit]
  Eigen::Vector3d scale = Eigen::Vector3d::Ones();  // k [output unit / input unit]
  std::vector<double> misalignment;                 // 3 or 6 terms [rad]; empty = all zero
  bool has_temperature = false;
  Eigen::Vector3d bias_per_c = Eigen::Vector3d::Zero();  // b1 [input unit / degC]
  double t_ref_c = 0.0;                                  // Reference temperature [degC].

  // M = T * K.
  Eigen::Matrix3d Matrix() const;
  // b(temp_c); temp_c is ignored without a temperature term.
  Eigen::Vector3d BiasAt(double temp_c) const;
  // calibrated = M * (raw - b(temp_c)).
  Eigen::Vector3d Apply(const Eigen::Vector3d& raw, double temp_c = 0.0) const;
  // raw = M^-1 * calibrated + b(temp_c): the exact inverse of Apply.
  Eigen::Vector3d Invert(const Eigen::Vector3d& calibrated, double temp_c = 0.0) const;
};

// The session columns' name for the sensor: kAccelerometer or kGyroscope (columns.hpp).
SensorKind ColumnSensorKind(ImuSensor sensor);

// "accelerometer", "gyroscope": the sensor as messages name it.
const char* ImuSensorLongName(ImuSensor sensor);

// The unit of the calibrated output: g (accelerometer), deg/s (gyroscope).
const Unit& OutputUnit(ImuSensor sensor);

// The unit with symbol `input_unit` if it is one of the sensor's column units (AxisUnits:
// LSB, g, m/s^2 or LSB, deg/s, rad/s); nullptr otherwise.
const Unit* InputUnit(ImuSensor sensor, std::string_view input_unit);

// The three session columns of the sensor in `input_unit`, x y z ("LSB" for the
// accelerometer: ax_lsb, ay_lsb, az_lsb); empty when InputUnit is nullptr.
std::vector<std::string> InputColumns(ImuSensor sensor, std::string_view input_unit);

// Nominal scale [output unit / input unit] of an input unit: for "LSB" the MPU6050 sensitivity
// at the full-scale setting `full_scale` (g or deg/s; datasheet PS-MPU-6000A-00 rev 3.4:
// 16384/8192/4096/2048 LSB/g at +-2/4/8/16 g, 131/65.5/32.8/16.4 LSB/(deg/s) at
// +-250/500/1000/2000 deg/s; 32768/full_scale for any other range), for physical units the unit
// conversion to the output unit (ConversionFactor). Returns nullopt for a unit that does not
// belong to the sensor or a full_scale <= 0.
std::optional<double> NominalScale(ImuSensor sensor, std::string_view input_unit,
                                   double full_scale);

// Standard gravity [m/s^2] (the definition of the unit g, CGPM 1901).
inline constexpr double kStandardGravityMps2 = 9.80665;

}  // namespace metro
