// The IEEE 952 noise terms of an IMU's rate quantities written as the noise parameters other
// tools read (issue #40 step 1; docs/noise.md "Export to estimators"), each value with its
// convention beside it.
//
// The physics (IEEE Std 952-1997 Annex C; Kalibr wiki "IMU Noise Model"):
//   white rate noise     metro N = random_walk [q]*sqrt(s): the continuous white sigma with
//                        two-sided PSD N^2, i.e. Kalibr's *_noise_density [q]/sqrt(Hz).
//                        metro's density_one_sided = sqrt(2) N is NOT that value.
//   bias random walk     metro K = rate_random_walk [q]/sqrt(s): the continuous sigma of the
//                        bias's driving white noise, Kalibr's *_random_walk [q]/s/sqrt(Hz).
//   discrete at rate f   (Kalibr's rule) white sigma_d = N * sqrt(f), bias walk
//                        sigma_bd = K / sqrt(f); per-sample variance of the white noise N^2 f.
// Gyroscope values go out in rad/s, accelerometer values in m/s^2 (converted from the report's
// deg/s, g); a quantity in LSB or any unit without an SI scale is refused.
//
// Over the three axes a scalar format takes one value per instrument, reduced by
// AxisReduction (kMax: the largest axis value and that axis's u; kRms: sqrt(mean(v_i^2)) with
// u by JCGM 100:2008 5.1.2, the axes uncorrelated). Formats that hold a vector (basalt's
// *_std[3], ROS's covariance diagonals) take each axis and need all three.
//
// A term the record did not resolve (value null, supported false, the IEEE 952 model
// rejected over the fit range, the Allan analysis failed) is refused by name: ExportNoise
// returns an input error naming the quantity, the term and the reason; nothing is filled in.
#pragma once

#include <cmath>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "metro/core/status.hpp"
#include "metro/io/columns.hpp"
#include "metro/noise/allan_report.hpp"
#include "metro/noise/noise_model.hpp"

namespace metro {

enum class NoiseExportFormat {
  kKalibr,    // imu.yaml (Kalibr, OpenVINS, ORB-SLAM3 users exchange it): continuous.
  kOpenVins,  // kalibr_imu_chain.yaml, %YAML:1.0 with the values under imu0: continuous.
  kBasalt,    // calibration.json's value0.{accel,gyro}_{noise,bias}_std[3]: continuous.
  kVins,      // VINS-Mono/Fusion config: acc_n, gyr_n, acc_w, gyr_w (continuous, see the file).
  kOrbSlam3,  // ORB-SLAM3 settings: IMU.NoiseGyro, NoiseAcc, GyroWalk, AccWalk, Frequency.
  kGtsam,     // PreintegrationParams sigmas (continuous), as flat key: value.
  kPx4Ekf2,   // EKF2_GYR_NOISE, EKF2_ACC_NOISE, EKF2_GYR_B_NOISE, EKF2_ACC_B_NOISE.
  kRos,       // sensor_msgs/Imu covariance diagonals (per-sample variance at the rate).
};
inline constexpr NoiseExportFormat kAllNoiseExportFormats[] = {
    NoiseExportFormat::kKalibr,  NoiseExportFormat::kOpenVins, NoiseExportFormat::kBasalt,
    NoiseExportFormat::kVins,    NoiseExportFormat::kOrbSlam3, NoiseExportFormat::kGtsam,
    NoiseExportFormat::kPx4Ekf2, NoiseExportFormat::kRos};

// "kalibr", "openvins", "basalt", "vins", "orbslam3", "gtsam", "px4-ekf2", "ros".
const char* NoiseExportFormatName(NoiseExportFormat format);
// The format named so; an input error listing the names otherwise.
Result<NoiseExportFormat> ParseNoiseExportFormat(std::string_view name);

enum class AxisReduction { kMax, kRms };
const char* AxisReductionName(AxisReduction reduction);  // "max", "rms".
Result<AxisReduction> ParseAxisReduction(std::string_view name);

// One rate quantity of the record: its name (a column name such as "gx_dps": ClassifyColumn
// gives the sensor and axis), its unit as the report states it, and its Allan report.
struct NoiseExportAxis {
  std::string quantity;
  std::string unit;
  AllanReport allan;
};

// The record the values come from: what the file names as its source (e.g. "session.csv
// (sha256 ...), sensor 3") and the rate quantities of one tag (accelerometer and gyroscope
// axes; other quantities are ignored).
struct NoiseExportInput {
  std::string source;
  std::vector<NoiseExportAxis> axes;
};

struct NoiseExportOptions {
  NoiseExportFormat format = NoiseExportFormat::kKalibr;
  AxisReduction reduction = AxisReduction::kMax;
  std::string rostopic = "/imu0";  // kalibr, openvins: the topic the file names (a ROS name).
  // px4-ekf2: the EKF2 prediction rate the parameters are discretized at (PX4 scales both its
  // white and bias parameters by its filter step dt: value = continuous / sqrt(dt)).
  double px4_predict_rate_hz = 100.0;

  bool IsValid(std::string* why) const;
};

// One value of an exported file, in the file's units.
struct ExportedNoiseValue {
  std::string key;  // As the reader flattens it: "accelerometer_noise_density",
                    // "imu0.gyroscope_random_walk", "value0.accel_noise_std[1]", ...
  SensorKind sensor = SensorKind::kNone;    // kAccelerometer or kGyroscope.
  NoiseTerm term = NoiseTerm::kRandomWalk;  // N (white) or K (bias random walk).
  double value = std::nan("");
  double u = std::nan("");  // Standard uncertainty (k = 1) propagated from the report's u.
  // 95 % interval value -/+ 1.96 u (normal approximation to the term's distribution).
  double low95 = std::nan("");
  double high95 = std::nan("");
  std::string unit;        // e.g. "rad/s/sqrt(Hz)", "(rad/s)^2".
  std::string convention;  // e.g. "continuous white sigma = N (two-sided PSD N^2)".
  std::string from;        // e.g. "max over gx_dps gy_dps gz_dps: gy_dps N".
};

// An exported file: its values and its text.
struct NoiseExport {
  NoiseExportFormat format = NoiseExportFormat::kKalibr;
  double rate_hz = std::nan("");  // The record's sample rate (allan.sample_period.rate_hz).
  std::vector<ExportedNoiseValue> values;
  std::string text;  // The file, with its convention comment block (basalt: a JSON member).
};

// The field's names and SI form of a report's N or K (issue #40 step 2), written beside the
// term as "allan.noise.<key>.standard" (docs/noise.md "Names"): name "angle_random_walk" /
// "velocity_random_walk" (N of a gyroscope / accelerometer), "rate_random_walk" /
// "acceleration_random_walk" (K); kalibr_key the Kalibr imu.yaml key holding the same value;
// value/u in rad/s, m/s^2 based units ("rad/s/sqrt(Hz)", "m/s^3/sqrt(Hz)"); for N also the
// one-sided density sqrt(2) N in the same unit. NaN where the term is not supported.
struct StandardNoiseName {
  std::string name;
  std::string kalibr_key;
  double value = std::nan("");
  double u = std::nan("");
  std::string unit;
  double density_one_sided = std::nan("");  // N only.
  double u_density_one_sided = std::nan("");
};
// nullopt for the other terms and for a quantity unit that is not an angular rate or an
// acceleration with an SI scale (read from the term's unit, e.g. "deg/s*sqrt(s)").
std::optional<StandardNoiseName> StandardNoiseNameOf(NoiseTerm term,
                                                     const AllanNoiseTermReport& report);

// Kalibr's discretization of a continuous white sigma (density [q]/sqrt(Hz)) at rate_hz:
// sigma_d = density * sqrt(rate_hz).
double DiscreteWhiteSigma(double density, double rate_hz);
// Kalibr's discretization of a bias random walk [q]/s/sqrt(Hz): sigma_bd = walk / sqrt(rate).
double DiscreteBiasWalkSigma(double walk, double rate_hz);

// The values `options.format` holds for `input`, without the text (what noise-compare
// compares a file against). Errors (input): no accelerometer or gyroscope axis, a unit
// without an SI scale, a term not resolved (by name, with the reason), a vector format
// without the three axes, invalid options.
Result<NoiseExport> ExportedNoiseValues(const NoiseExportInput& input,
                                        const NoiseExportOptions& options);

// The values and the file's text.
Result<NoiseExport> ExportNoise(const NoiseExportInput& input, const NoiseExportOptions& options);

}  // namespace metro
