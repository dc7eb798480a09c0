// A tag's calibration as an autopilot's parameters (issue #40 step 4): PX4 and ArduPilot.
//
// Both autopilots correct each sensor axis by axis, in SI units, from the driver's data (the
// raw counts times the part's nominal sensitivity):
//
//   corrected = (data - offset) .* scale          (accelerometer, m/s^2)
//   corrected =  data - offset                    (gyroscope, rad/s: an offset only)
//
// PX4: src/lib/sensor_calibration (CAL_ACCn_{X,Y,Z}OFF, CAL_ACCn_{X,Y,Z}SCALE,
// CAL_GYROn_{X,Y,Z}OFF; CAL_ACCn_ID / CAL_GYROn_ID name the device the values belong to);
// ArduPilot: AP_InertialSensor_Backend::_rotate_and_correct_accel (INS_ACCOFFS_{X,Y,Z},
// INS_ACCSCAL_{X,Y,Z}, INS_GYROFFS_{X,Y,Z}; INS_ACC2OFFS... for the second IMU).
//
// metro's model (imu_model.hpp) is calibrated = T K (raw - b0 - b1 (temp - t_ref)) with the
// output in g_n or deg/s. With data = c_in raw and corrected = c_out calibrated (c_in, c_out the
// unit factors into SI; for counts c_in is the nominal sensitivity full_scale / 32768):
//
//   offset = c_in b0,   scale = (c_out / c_in) k
//
// is exact when T = I and b1 = 0. What the form cannot hold is named, with its size:
// misalignment (the largest relative error of the corrected vector, the spectral norm of
// T - I), a temperature term (b1 in SI per degC), and for the gyroscope a scale other than 1
// (the largest |scale - 1|). Every value carries its standard uncertainty (k = 1), propagated
// from calibration.json's u of b0 and k (a linear map, JCGM 100 5.1.2).
#pragma once

#include <Eigen/Core>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "metro/calibration/calibrate.hpp"
#include "metro/core/status.hpp"

namespace metro {

enum class AutopilotFormat { kPx4, kArduPilot };

// "px4", "ardupilot".
const char* AutopilotFormatName(AutopilotFormat format);
std::optional<AutopilotFormat> ParseAutopilotFormat(std::string_view name);

// One sensor in the autopilots' form.
struct AutopilotSensorForm {
  ImuSensor sensor = ImuSensor::kAccel;
  double input_to_si = 1.0;                          // c_in: SI units per calibration input unit.
  double output_to_si = 1.0;                         // c_out: SI units per calibration output unit.
  std::string si_unit;                               // "m/s^2" or "rad/s".
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();  // [si_unit]
  Eigen::Vector3d offset_u = Eigen::Vector3d::Zero();  // k = 1
  Eigen::Vector3d scale = Eigen::Vector3d::Ones();     // [1]
  Eigen::Vector3d scale_u = Eigen::Vector3d::Zero();
  bool scale_held = true;  // False for the gyroscope: both autopilots hold an offset only.
  // What the form leaves out, each with its size (empty: the form is exact).
  std::vector<std::string> not_held;

  // corrected = (data - offset) .* scale (scale only when held), in SI.
  Eigen::Vector3d Correct(const Eigen::Vector3d& data_si) const;
};

// The form of one sensor of a calibration. Errors: an input unit the form cannot be given in
// (counts without the full-scale setting calibration.json records).
Result<AutopilotSensorForm> AutopilotForm(const SensorCalibration& calibration);

struct AutopilotExportOptions {
  AutopilotFormat format = AutopilotFormat::kPx4;
  int sensor = 1;    // The tag in calibration.json.
  int instance = 0;  // The autopilot's IMU index: PX4 CAL_ACC<instance>_..., ArduPilot 0 ->
                     // INS_ACC, 1 -> INS_ACC2, 2 -> INS_ACC3. 0..3 (PX4), 0..2 (ArduPilot).
  // PX4 applies CAL_ACCn_* only to the device whose ID is CAL_ACCn_ID; given: written.
  std::optional<int64_t> px4_accel_device_id;
  std::optional<int64_t> px4_gyro_device_id;
};

struct AutopilotExport {
  std::string text;  // The parameter file, its conventions in a leading '#' comment block.
  std::vector<std::string> warnings;  // What the form does not hold, per sensor.
};

// Errors: the tag is missing, a model_rejected sensor, a bad instance, AutopilotForm's.
Result<AutopilotExport> ExportAutopilotParameters(const Calibration& calibration,
                                                  const AutopilotExportOptions& options);

}  // namespace metro
