// calibration.json ("metro.calibration/1", specified in docs/calibration-format.md), the
// readable report of a calibration, and applying a calibration to a session.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "metro/calibration/calibrate.hpp"
#include "metro/core/status.hpp"
#include "metro/io/session.hpp"

namespace metro {

inline constexpr const char* kCalibrationSchema = "metro.calibration/1";

nlohmann::json CalibrationToJson(const Calibration& calibration);
// Errors name `file` and the JSON key that is missing or malformed.
Result<Calibration> CalibrationFromJson(const nlohmann::json& json, const std::string& file = "");
// Pretty-printed JSON text (2-space indent, trailing newline).
std::string FormatCalibrationJson(const Calibration& calibration);
Result<Calibration> LoadCalibration(const std::string& path);

// A readable summary: per tag and sensor the constants with their standard uncertainties, the
// residuals and the segments.
std::string FormatCalibrationReport(const Calibration& calibration);

struct ApplySummary {
  int tags_calibrated = 0;
  int64_t rows = 0;
  std::vector<std::string> warnings;
};

// Adds (or overwrites) ax_g ay_g az_g and gx_dps gy_dps gz_dps in every tag of `session` with
// the calibrated values of the tag's calibration (matched by sensor number); every other
// column and every row is kept. Errors: a tag without a calibration, a tag without the
// calibration's input columns (e.g. ax_lsb for input_unit "LSB"), or a temperature model and
// no temp_c column.
Result<ApplySummary> ApplyCalibration(const Calibration& calibration, Session* session);

}  // namespace metro
