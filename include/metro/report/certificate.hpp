// Calibration certificate: the HTML view of a calibration ("metro.calibration/1") with the
// content ISO/IEC 17025:2017 7.8.2 and 7.8.4 ask of a calibration report: identification
// of the item(s) from the data and the tags file (format, sensor, name, device ID, declared
// profile), of every input session (SHA-256) and the dates of measurement from the records,
// method and model, the gravity value with its source, results with expanded uncertainties
// U = k u and the coverage factor k = t_0.975(dof) with its dof (JCGM 100:2008 6.2, 6.3,
// G.3, 7.2.6 rounding), the conditions (temperature range of the records), the residuals
// before and after calibration (log scale), the metrological traceability (7.8.4.1 c) and the
// validity of the results. Print CSS keeps tables on one page and numbers the pages.
#pragma once

#include <string>
#include <vector>

#include "metro/calibration/calibrate.hpp"
#include "metro/core/status.hpp"
#include "metro/io/session.hpp"

namespace metro {

struct CertificateOptions {
  // Coverage probability p of the stated expanded uncertainties U = k u: each sensor's k is
  // Student's t_{(1+p)/2}(nu) at its fit's degrees of freedom nu (JCGM 100:2008 6.3.3, G.3.2;
  // CoverageFactor, uncertainty/gum.hpp); nu is infinite for an accelerometer u that rests on
  // the poses' noise alone (calibration.json's coverage_factor_95 = 1.96, G.6.6).
  double coverage_probability = 0.95;
  // Full-scale settings used for the "before calibration" residuals of raw (LSB) input when
  // calibration.json does not record them (SensorCalibration::full_scale, files written
  // before issue #25): the nominal MPU6050 sensitivity at these ranges (NominalScale).
  double accel_fs_g = 2.0;
  double gyro_fs_dps = 250.0;
  // The certificate id shown in section 1; empty: CalibrationCertificateId(calibration), the
  // hash of the JSON as `fit` writes it. A certificate rendered from a file passes the file's
  // own hash, so it carries the id the registry records (docs/registry.md).
  std::string certificate_id;

  bool IsValid(std::string* why) const;
};

// The certificate page. `sessions` are the calibration's inputs in the order of
// calibration.inputs (as fitted), or empty when they are not available: the conditions
// then come from the file alone and the residual plots are omitted; `sessions_note` says
// which. Errors: invalid options, `sessions` not matching calibration.inputs.
Result<std::string> RenderCalibrationCertificate(const Calibration& calibration,
                                                 const std::vector<const Session*>& sessions,
                                                 const std::string& sessions_note,
                                                 const CertificateOptions& options = {});

// Residuals of every static segment a sensor's fit used, before calibration (the raw
// segment mean at the nominal sensitivity, NominalScale) and after (SensorModel::Apply at
// the segment's mean temperature): accelerometer |a| - gravity_mps2/g_n [g], gyroscope |w|
// [deg/s]. Errors: no nominal scale for the input unit, no static segment found in
// `sessions` (the inputs in calibration.inputs order).
struct StaticResiduals {
  std::vector<double> before;
  std::vector<double> after;
  std::string unit;  // "g" or "deg/s".
};
Result<StaticResiduals> ComputeStaticResiduals(const SensorCalibration& calibration, int sensor,
                                               const std::vector<const Session*>& sessions,
                                               double gravity_mps2,
                                               const CertificateOptions& options = {});

// The inputs of a calibration reloaded from disk (paths as recorded, then relative to the
// directory of `calibration_path`), each only when its SHA-256 matches the recorded one.
struct ReloadedInputs {
  std::vector<Session> sessions;  // In calibration.inputs order when `complete`.
  bool complete = false;          // Every input was found and matched.
  std::string note;               // What was reloaded, or why not.
};
ReloadedInputs ReloadCalibrationInputs(const Calibration& calibration,
                                       const std::string& calibration_path);

}  // namespace metro
