// calibration.json (metro::Calibration, docs/calibration-format.md) -> blob constants
// (docs/calibration-blob.md section 10).
//
// The calibrator's model, raw input in `input_unit`, output in g (accelerometer) or deg/s
// (gyroscope):
//
//   y_cal = M_c * (r - b0_c - b1_c * (T - t_ref_c)),   M_c = T K   (imu_model.hpp)
//
// The firmware's model, raw int16 counts in, SI out (m/s^2, rad/s):
//
//   y_si = M * (r - b0 - b1*dT - b2*dT^2),   dT = clamp(T, t_valid_min_c, t_valid_max_c) - t_ref_c
//
// Both remove the bias before scaling, so with raw counts as the calibrator's input (input_unit
// "LSB") the mapping is exact apart from the output unit:
//
//   M = c * M_c,  c = 9.80665 m/s^2 per g (the unit g, CGPM 1901) or pi/180 rad per deg
//   b0 = b0_c [LSB],  b1 = b1_c [LSB/degC],  b2 = 0,  t_ref_c = t_ref_c
//   u(M_ij) = c * u(M_c,ij),  u(b0) = u(b0_c),  u(b1) = u(b1_c)       (k = 1)
//
// c is a defined constant, so the uncertainties scale exactly (JCGM 100:2008 5.1.2 with a
// sensitivity coefficient c and no uncertainty of its own). fs_sel is the declared full-scale
// setting's, or the setting whose nominal sensitivity the mean row norm of M_c matches within
// 10 % (settings are a factor 2 apart, so at most one can match); see SensorProfile, which
// also says when a section v2.0 declares s_nom and the input instead (then b0 = b0_c - 32768
// for unsigned counts).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "metro/blob/blob.hpp"
#include "metro/calibration/calibrate.hpp"
#include "metro/core/status.hpp"

namespace metro::blob {

// The IMU a blob is for (`calibrate blob --profile`), which sets the nominal sensitivity a
// section declares (docs/calibration-blob.md section 10, "Nominal sensitivity"):
//   kMpu6050  a section v1.0 whose fs_sel declares the MPU6050 datasheet's sensitivity of the
//             declared full-scale setting (+-2, 4, 8, 16 g; +-250, 500, 1000, 2000 deg/s), or
//             without one of the setting M matches within 10 %; else refused;
//   kGeneric  another IMU: a section v1.0 when the tag firmware uses one (the fs_sel nearest to
//             32768 / the declared full scale, or to M's own mean row norm), so that tags with
//             an older firmware accept it too; otherwise a section v2.0 (issue #25) that declares
//             s_nom itself (that nominal, SI per LSB) and the raw input: int16, or unsigned
//             16-bit counts about the mid-scale 32768 when only those hold the biases (b0 is
//             then the calibrator's bias minus 32768).
// The blob is refused only when no section the firmware accepts can hold the constants
// (section 3.1: s_nom 2^-14 .. 2^-7 SI per LSB, row norms within +-10 % of s_nom, bias and
// temperature-coefficient limits), with a message naming the figures and what a section holds.
enum class SensorProfile { kMpu6050, kGeneric };
const char* SensorProfileName(SensorProfile profile);  // "mpu6050", "generic"
std::optional<SensorProfile> ParseSensorProfile(std::string_view name);

struct BlobFromCalibrationOptions {
  int sensor = 0;          // The tag in calibration.json (`tags[].sensor`), >= 1.
  uint64_t device_id = 0;  // (FICR DEVICEID[1] << 32) | DEVICEID[0].
  uint32_t seq = 1;        // 1 .. kSeqMax.
  uint8_t dlpf_cfg = 3;    // The tag firmware's MPU6050 DLPF_CFG (0..6); the tag refuses a
                           // section whose value differs from its own configuration.
  // Temperature validity range: the firmware clamps T to it before the temperature terms.
  // Unset: per sensor, the span the fit used (calibration.json `static_pose_temperature`)
  // widened by 5 degC each side, within -40 .. 85 degC; without a recorded span the operating
  // range -40 .. 85 degC, with a warning (metro::TemperatureValidityRange, calibration_io.hpp,
  // which `calibrate apply` uses too, so host and tag clamp alike). Set: replaces that end; a
  // range beyond the default is accepted with a warning.
  std::optional<double> t_valid_min_c;
  std::optional<double> t_valid_max_c;
  uint32_t due_after_s = 365u * 86400u;  // due_time_utc = cal_time_utc + due_after_s.
  std::string reference_id;              // ASCII, at most 16 characters.
  bool provisional = false;              // Header flag b3.
  SensorProfile profile = SensorProfile::kMpu6050;
  // Declared full-scale settings (`--accel-fs-g`, `--gyro-fs-dps`); unset: from M (above).
  std::optional<double> accel_fs_g;
  std::optional<double> gyro_fs_dps;
  // Constants calibration.json marks `model_rejected` (model_check, issue #36: a model the data
  // reject, or an exact fit, whose u does not cover what it leaves out) are refused (an input
  // error naming the reason) unless this is set (`--accept-rejected-model`); then written with
  // a warning.
  bool accept_rejected_model = false;

  // sensor >= 1, seq in 1..kSeqMax, dlpf_cfg <= 6, each t_valid end that is set within
  // -40 .. 85 and, both set, t_valid_min_c + 2 <= t_valid_max_c (ValidityOptions::IsValid),
  // reference_id printable ASCII of at most 16 characters, a declared full scale > 0 and, for
  // kMpu6050, one of the MPU6050's settings.
  bool IsValid(std::string* why) const;
};

// fs_sel of a section v1.0 for sensor calibration matrix `m_out_per_lsb` under options.profile
// and the declared full scale (above); for kGeneric an error only means that no v1.0 section
// holds M (SensorConstantsFromCalibration then tries a section v2.0). Errors say why the format
// cannot represent M: a declared setting the MPU6050 does not have, or a sensitivity more than 10 %
// from the nominal of every fs_sel the format can declare (naming the nearest and the representable
// ranges).
Result<uint8_t> NominalFsSel(ImuSensor sensor, const Eigen::Matrix3d& m_out_per_lsb,
                             const BlobFromCalibrationOptions& options);

// fs_sel (0..3) of the MPU6050 full-scale setting whose nominal sensitivity, in the
// calibrator's output unit per LSB (accelerometer (1 << fs_sel) / 16384 g, gyroscope
// (250 << fs_sel) / 32768 deg/s), is within 10 % of the mean row norm of `m_out_per_lsb`.
// Error when none is.
Result<uint8_t> InferFsSel(ImuSensor sensor, const Eigen::Matrix3d& m_out_per_lsb);

// The blob section of one sensor calibration (mapping above). Errors: an input unit other than
// "LSB" (the tag applies the constants to raw counts), no representable fs_sel
// (NominalFsSel; kGeneric: no section v1.0 or v2.0 the firmware accepts), a model with free scale
// terms but no `matrix_u`, a temperature coefficient |b1| above the plausibility limit
// (TempcoLimitLsbPerC at that fs_sel), a validity range the rule cannot give
// (TemperatureValidityRange). The validity range's warnings, each starting with the sensor's name,
// are appended to *warnings when it is not null.
Result<SensorConstants> SensorConstantsFromCalibration(
    const SensorCalibration& calibration, const BlobFromCalibrationOptions& options,
    std::vector<std::string>* warnings = nullptr);

// Everything the blob of options.sensor holds: both sensor sections and META
// (cal_time_utc from date_utc, tool_version from "metro X.Y.Z", raw_data_sha256 = the input's
// SHA-256, or the SHA-256 of the inputs' hex digests joined by '\n' for several inputs,
// session_uuid = RFC 9562 version-8 UUID from SHA-256(date_utc '\n' sensor '\n'
// raw_data_sha256 hex), g_local_mps2 = gravity_mps2, temp_mean/min/max_c = the first sensor's
// static_pose_temperature (without one t_ref_c of a temperature model, else 0), procedure_id 1
// (calibrate fit), unc_k_x10 = round(10 * coverage_factor_95), tag_label "tag<N>"). Errors name
// the file's key, with what was expected, and for a calibration read from a file are at the
// file:line:column of the value they are about (CalibrationErrorAt, calibration_io.hpp): a
// missing sensor at `tags`, constants marked model_rejected at their `model_rejected`, a
// constant the blob cannot hold at it (or at its sensor object), a date_utc outside 1970..2106
// at it; each section is checked with the firmware's rules (WriteBlob) before it is taken.
// Warnings (the validity ranges', "sensor N accel: ...") are appended to *warnings when it is
// not null.
Result<BlobContents> BlobContentsFromCalibration(const Calibration& calibration,
                                                 const BlobFromCalibrationOptions& options,
                                                 std::vector<std::string>* warnings = nullptr);

// The procedure_id META carries for `calibrate fit` (multi-pose static + rotations).
inline constexpr uint16_t kProcedureCalibrateFit = 1;

}  // namespace metro::blob
