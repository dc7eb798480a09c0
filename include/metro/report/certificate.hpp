// Calibration certificate: the HTML view of a calibration ("metro.calibration/1") with the
// content ISO/IEC 17025:2017 7.8.2 and 7.8.4 ask of a calibration report: identification
// of the item(s) from the data and the tags file (format, sensor, name, device ID, declared
// profile), of every input session (SHA-256) and the dates of measurement from the records,
// method and model, the gravity value with its source, results with expanded uncertainties
// U = k u and the coverage factor k = t_0.975(dof) with its dof (JCGM 100:2008 6.2, 6.3,
// G.3, 7.2.6 rounding), the conditions (temperature range of the records), the residuals
// before and after calibration (log scale), the metrological traceability (7.8.4.1 c) and the
// validity of the results; everything from calibration.json, which records what the
// certificate needs of the records at fit time (no input is reloaded). Print CSS keeps tables on
// one page and numbers the pages.
#pragma once

#include <string>

#include "metro/calibration/calibrate.hpp"
#include "metro/core/status.hpp"

namespace metro {

struct CertificateOptions {
  // Coverage probability p of the stated expanded uncertainties U = k u: each sensor's k is
  // Student's t_{(1+p)/2}(nu) at its fit's degrees of freedom nu (JCGM 100:2008 6.3.3, G.3.2;
  // CoverageFactor, uncertainty/gum.hpp); nu is infinite for an accelerometer u that rests on
  // the poses' noise alone (calibration.json's coverage_factor_95 = 1.96, G.6.6).
  double coverage_probability = 0.95;
  // The certificate id shown in section 1; empty: CalibrationCertificateId(calibration), the
  // hash of the JSON as `fit` writes it. A certificate rendered from a file passes the file's
  // own hash, so it carries the id the registry records (docs/registry.md).
  std::string certificate_id;
  // Constants calibration.json marks model_rejected (ModelCheck, issue #36) are refused (an
  // input error naming them) unless this is set (`--accept-rejected-model`); then stated with
  // a notice in their section and in the validity section.
  bool accept_rejected_model = false;
  // A view of calibration.json, not a certificate (`characterize report`, issue #36): constants
  // marked model_rejected do not stop the page; it is then titled "Calibration report (not a
  // certificate)", opens with a banner naming each rejected sensor and the reason, and says in
  // the sensor's section and under validity that they are not certified. Without rejected
  // constants the view is the certificate.
  bool view = false;

  bool IsValid(std::string* why) const;
};

// The certificate page, from the calibration alone: the conditions of the records and the
// residual plots are what the fit recorded (TagCalibration::record_conditions,
// SensorCalibration::static_residuals); a calibration read from a file written before metro
// recorded them gets a page that says so and how to get them (re-run `calibrate fit`).
// Errors: invalid options.
Result<std::string> RenderCalibrationCertificate(const Calibration& calibration,
                                                 const CertificateOptions& options = {});

}  // namespace metro
