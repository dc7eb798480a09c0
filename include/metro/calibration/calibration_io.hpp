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

// Relative tolerance of the redundant fields on read: `matrix` against T K from `scale` and
// `misalignment`, `sensitivity` against 1 / `scale`. Each element of T K is one product t_ij k_j
// (t_ii = 1, t_ij = +-a misalignment term, imu_model.hpp) and 1 / k one quotient: the writer
// rounds it once to binary64 (at most 2^-53 relative) and writes it exactly (shortest
// round-trip or 17 significant digits, as nlohmann_json does); the reader rounds its own
// product once more. An honest file is therefore within 2 * 2^-53; the tolerance is twice that,
// 2^-51 = 4.4e-16, relative to the larger of the two values (so a zero must be written as 0).
inline constexpr double kRedundantRelTolerance = 0x1p-51;

nlohmann::json CalibrationToJson(const Calibration& calibration);
// Errors name `file` and the JSON key that is missing or malformed, and refuse redundant fields
// that disagree beyond kRedundantRelTolerance, naming both (`matrix` and `scale` and
// `misalignment`, or `sensitivity` and `scale`).
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
