// Gyroscope bias at rest from one static record (`calibrate fit SESSION --gyro-model bias
// --accel-model none`; docs/calibration-model.md "Gyroscope bias at rest").
//
// Model: the gyroscope's `bias` model of imu_model.hpp,
//
//   calibrated = K_nom * (raw - b0),   K_nom the nominal scale (held), T = I,
//
// with b0 per axis the mean of the record,  b0_a = (1/n) sum_k r_a,k  (JCGM 100:2008 4.2.1),
// and u(b0_a) the autocorrelation-aware standard uncertainty of that mean (metro's Type A,
// stats/type_a.hpp: the AR spectral density at frequency zero, with the batch-means check
// for drift; JCGM 100:2008 4.2.7), so a bias-unstable or filtered record does not get the
// i.i.d. s/sqrt(n). The dof is the smallest of the three axes' (JCGM 100:2008 G.4.2); the
// covariance is diagonal (the axes' noise is independent), and the coverage factor is
// Student t_0.975(dof) (JCGM 100:2008 G.3.2). No accelerometer calibration is made: the record
// has one orientation, which gives no scale or axes.
#pragma once

#include <vector>

#include "metro/calibration/calibrate.hpp"
#include "metro/core/status.hpp"
#include "metro/io/session.hpp"

namespace metro {

// The shortest record evaluated: the Type A needs n >= 2; 10 s of a 10 Hz tag is far more.
inline constexpr size_t kMinRestSamples = 10;
// A record is not at rest when a 1 s moving mean of a gyroscope axis leaves the record's mean
// by more than this (deg/s, through the nominal scale): ten times the MPU6050's rate noise in a
// 1 s mean at full bandwidth, and far below a hand's turn.
inline constexpr double kRestLimitDps = 1.0;

// Checks the records before a bias-at-rest fit, as input errors (`calibrate fit` exits 2):
// per tag to be calibrated, exactly one record with a complete gyroscope family, at least
// kMinRestSamples finite samples, and at rest (kRestLimitDps). Errors name the session and say
// what was expected.
Status CheckGyroRestRecords(const std::vector<const Session*>& sessions,
                            const CalibrationOptions& options);

// The bias of one tag from its one static record (above). Options: fit_accel false,
// gyro_model kBias (CalibrationOptions::IsValid), gyro_fs_dps for the nominal scale of raw
// counts. static_pose_temperature is the record's temp_c (one pose) when it has one.
Result<TagCalibration> CalibrateGyroBiasAtRest(const std::vector<const Tag*>& records,
                                               const CalibrationOptions& options);

}  // namespace metro
