// Calibration interchange (issue #40 step 4): a tag's intrinsics in the forms Kalibr, OpenVINS,
// basalt, librealsense, PX4 and ArduPilot carry, and back into calibration.json.
//
// metro (imu_model.hpp) in SI units: with data = c_in raw and calibrated_si = c_out calibrated
// (c_in, c_out the SI factors of the calibration's input and output units; counts: the nominal
// sensitivity full_scale / 32768, as autopilot_export.hpp),
//
//   calibrated_si = M (data - b),   M = (c_out / c_in) T K,   b = c_in (b0 + b1 (temp - t_ref))
//
// bias removed BEFORE scaling. The forms, each in the format's IMU frame I, data in SI:
//
// kalibr: Kalibr's imu-chain yaml, model `scale-misalignment` (Kalibr
//   kalibr_imu_camera_calibration/IccSensors.py, IccScaledMisalignedImu, the error terms; Rehder
//   et al., "Extending kalibr", ICRA 2016). A measurement model, true -> raw:
//     a_raw = M_a a_I + b_a
//     w_raw = M_g C_gyro_i w_I + A C_gyro_i a_I + b_g
//   M_a (`accelerometers: M`) and M_g (`gyroscopes: M`) lower triangular (the design variables'
//   pattern [[1,0,0],[1,1,0],[1,1,1]]), C_gyro_i a rotation, A [(rad/s)/(m/s^2)] the
//   g-sensitivity. b_a, b_g are Kalibr's bias states (splines), not in the file.
// openvins: OpenVINS's kalibr_imu_chain.yaml with `model: kalibr` (OpenVINS
//   docs/propagation-analytical.dox "IMU Intrinsic Models"; ov_msckf VioManagerOptions.h reads
//   Tw, Ta, R_IMUtoGYRO, R_IMUtoACC, Tg and takes Dw = Tw^-1, Da = Ta^-1,
//   R_GYROtoIMU = R_IMUtoGYRO^T, R_ACCtoIMU = R_IMUtoACC^T):
//     w_I = R_IMUtoGYRO^T Tw^-1 (w_m - Tg a_I - b_g)
//     a_I = R_IMUtoACC^T  Ta^-1 (a_m - b_a)
//   kalibr model: Tw, Ta lower triangular, R_IMUtoACC = I (rpng model: upper triangular,
//   R_IMUtoGYRO = I; read, not written). b_g, b_a are the filter's states, not in the file.
//   The same matrices as Kalibr's: Tw = M_g, R_IMUtoGYRO = C_gyro_i, Ta = M_a, Tg = A C_gyro_i.
// basalt: basalt's calibration.json, value0 (basalt-headers calib_bias.hpp CalibAccelBias,
//   CalibGyroBias):
//     a_I = (I + S_a) a_raw - b_a    calib_accel_bias = [b_a(3), s1..s6], S_a lower triangular
//                                    [[s1,0,0],[s2,s4,0],[s3,s5,s6]]
//     w_I = (I + S_g) w_raw - b_g    calib_gyro_bias = [b_g(3), s1..s9], S_g column by column
//                                    [[s1,s4,s7],[s2,s5,s8],[s3,s6,s9]]
//   bias removed AFTER scaling.
// realsense: the calibration.json of librealsense's tools/rs-imu-calibration/rs-imu-calibration.py
//   (`imus[0].accelerometer|gyroscope.scale_and_alignment` (9), `.bias` (3)); its check_X
//   applies  a = a_raw . X[:3,:3] - X[3,:]  with X[:3,:3] = scale_and_alignment row by row, i.e.
//     a = S^T a_raw - bias,   S = scale_and_alignment read row by row
//   (bias removed after scaling). The device table the script also writes holds S^T; which of
//   the two librealsense applies on the device is not stated in the script (convention
//   uncertain beyond check_X; see docs/calibration-interchange.md).
// px4, ardupilot: autopilot_export.hpp (offsets and accelerometer scales, axis by axis).
//
// Frames: metro's accelerometer matrix is upper triangular (its x axis is the body x axis);
// Kalibr, OpenVINS's kalibr model and basalt hold a lower triangular one. The export factors
// M_a = R L (R a rotation, L lower triangular with a positive diagonal): the format's frame I is
// metro's body frame B turned by R (a_B = R a_I), by an angle of the order of the
// misalignment, and the gyroscope is written in the same frame (R^T M_g), so the two sensors keep
// their relative alignment. R is in the file's comments and the sidecar and named in a warning
// when it is not I; it belongs to the extrinsics the estimator calibrates (T_cam_imu). The
// import undoes it (M_a = Q^T U, U upper triangular), so export -> import returns metro's
// constants. realsense, px4 and ardupilot keep metro's frame.
//
// What a form cannot hold is named in a warning with its size: the bias (Kalibr, OpenVINS:
// estimator states), the temperature term b1 (every form), misalignment and the gyroscope's
// scale (px4, ardupilot).
//
// Covariance (the sidecar, FILE.covariance.json): every number the file holds is a function
// v = f(theta) of metro's free parameters; cov(v) = J cov(theta) J^T, J = df/dtheta by central
// differences at theta (JCGM 102:2011 6.2.1.3, the law of propagation for a vector output;
// JCGM 100:2008 5.1.2). The import reads it back with the Jacobian of the inverse conversion.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "metro/calibration/calibrate.hpp"
#include "metro/core/status.hpp"

namespace metro {

enum class InterchangeFormat { kKalibr, kOpenVins, kBasalt, kRealSense, kPx4, kArduPilot };

// "kalibr", "openvins", "basalt", "realsense", "px4", "ardupilot".
const char* InterchangeFormatName(InterchangeFormat format);
std::optional<InterchangeFormat> ParseInterchangeFormat(std::string_view name);

// One number of a format's file, named as the file names it ("imu0.accelerometers.M[1][0]",
// "value0.calib_gyro_bias[4]", "CAL_ACC0_XOFF").
struct InterchangeValue {
  std::string name;
  double value = 0.0;
  std::string unit;  // "m/s^2", "rad/s", "1", "(rad/s)/(m/s^2)".
};

// One sensor in SI: calibrated = matrix (data - bias), in the frame the form names.
struct SiSensorForm {
  Eigen::Matrix3d matrix = Eigen::Matrix3d::Identity();
  Eigen::Vector3d bias = Eigen::Vector3d::Zero();
  Eigen::Vector3d Apply(const Eigen::Vector3d& data_si) const { return matrix * (data_si - bias); }
};

// A sensor calibration's SI form at its reference temperature (the bias b0; b1 is not in it).
// Errors: AutopilotForm's (counts without a full scale).
Result<SiSensorForm> SiForm(const SensorCalibration& calibration);

struct InterchangeExportOptions {
  InterchangeFormat format = InterchangeFormat::kKalibr;
  int sensor = 1;    // The tag in calibration.json.
  int instance = 0;  // px4 / ardupilot IMU index (autopilot_export.hpp); kalibr/openvins imuN.
};

struct InterchangeExport {
  InterchangeFormat format = InterchangeFormat::kKalibr;
  std::string text;                      // The file, its conventions in a comment block or key.
  std::vector<std::string> warnings;     // What the form does not hold, the frame turn.
  std::vector<InterchangeValue> values;  // Every number the file holds, in layout order.
  Eigen::VectorXd u;                     // Standard uncertainty of each value (k = 1).
  Eigen::MatrixXd covariance;            // Of `values` (see above).
  // False when a sensor was imported without its uncertainties (interchange import): the
  // covariance is then zeros that mean nothing, and no sidecar is written.
  bool uncertainty_known = true;
  Eigen::Matrix3d body_from_format = Eigen::Matrix3d::Identity();  // R: a_B = R a_I
  std::vector<std::string> not_held;
};

// Errors: the tag is missing, a model_rejected sensor (except an import's, below), a matrix
// with det <= 0, SiForm's.
// px4 / ardupilot: the text is ExportAutopilotParameters's (unchanged); values and covariance
// are its offsets and scales.
Result<InterchangeExport> ExportInterchange(const Calibration& calibration,
                                            const InterchangeExportOptions& options);

// The sidecar's name for an exported file: FILE.covariance.json.
std::string InterchangeSidecarPath(const std::string& exported_path);
// The sidecar's text ("metro.interchange_covariance/1", docs/calibration-interchange.md).
std::string InterchangeSidecarJson(const InterchangeExport& exported, const std::string& file,
                                   const std::string& calibration_file, int sensor);

// ---- Import -------------------------------------------------------------------------------

// A format's file as read: its numbers in layout order (the same names as the export's).
struct InterchangeFile {
  InterchangeFormat format = InterchangeFormat::kKalibr;
  std::string file;
  std::string sha256;  // Of the text read.
  std::vector<InterchangeValue> values;
  std::vector<bool> present;  // Per value: in the file (false: a default, e.g. Kalibr's A).
  std::vector<std::pair<int64_t, int64_t>> positions;  // Per value: line, column (1-based).
  std::string model;               // kalibr: model; openvins: model ("kalibr", "rpng").
  std::vector<std::string> notes;  // What the file held that metro does not read (noise, ...).
};

struct InterchangeReadOptions {
  InterchangeFormat format = InterchangeFormat::kKalibr;
  int instance = 0;  // imuN (kalibr, openvins, realsense imus[N]); px4 / ardupilot IMU index.
};

// Reads a format's file. Errors (input) at file:line:column: not YAML / JSON, an unknown key
// (with the keys expected), a missing key (at its parent), a value that is not a number, a
// matrix that is not 3 x 3, a rotation that is not a rotation (|R^T R - I| > 1e-6 or det < 0).
Result<InterchangeFile> ReadInterchangeFile(std::string_view text,
                                            const InterchangeReadOptions& options,
                                            const std::string& file);

struct InterchangeImportOptions {
  int sensor = 1;            // The tag number calibration.json gets.
  std::string sidecar_text;  // The covariance sidecar's text; empty: none.
  std::string sidecar_file;  // Its name, for errors.
  std::string date_utc;      // The calibration.json's date_utc (the import's time).
  std::string tool_version;
};

struct InterchangeImport {
  Calibration calibration;
  Eigen::Matrix3d body_from_format = Eigen::Matrix3d::Identity();
  std::vector<std::string> not_carried;  // Constants the format did not carry.
  std::vector<std::string> flags;        // Implausible constants (warnings), named with value.
  bool uncertainty_known = false;        // From a sidecar.
};

// The file's constants as calibration.json (input units m/s^2 and rad/s, output g and deg/s,
// model full / scale / bias as the file carries). Constants the format did not carry are 0
// (bias) and named; without a sidecar the uncertainties are unknown: the covariance is written
// as zeros and each sensor is marked model_rejected with that reason, so blob, push and the
// certificate refuse it unless --accept-rejected-model. Errors (input): a value outside
// physical sense: a matrix that is singular (condition number above 1e6) or reverses
// orientation (det <= 0), a gain <= 0; a sidecar that does not belong to the file (names or
// values differ), at the sidecar's file:line:column.
Result<InterchangeImport> ImportInterchange(const InterchangeFile& file,
                                            const InterchangeImportOptions& options);

}  // namespace metro
