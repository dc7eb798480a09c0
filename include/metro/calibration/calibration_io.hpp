// calibration.json ("metro.calibration/1", specified in docs/calibration-format.md), the
// readable report of a calibration, and applying a calibration to a session.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "metro/calibration/calibrate.hpp"
#include "metro/core/status.hpp"
#include "metro/io/session.hpp"
#include "metro/io/tag_registry.hpp"

namespace metro {

inline constexpr const char* kCalibrationSchema = "metro.calibration/1";

// Relative tolerance of the redundant fields on read: `matrix` against T K from `scale` and
// `misalignment`, `sensitivity` against 1 / `scale`. Each element of T K is one product t_ij k_j
// (t_ii = 1, t_ij = +-a misalignment term, imu_model.hpp) and 1 / k one quotient: the writer
// rounds it once to binary64 (at most 2^-53 relative) and writes it exactly (shortest
// round-trip or 17 significant digits, as metro's JSON writer does); the reader rounds its own
// product once more. An honest file is therefore within 2 * 2^-53; the tolerance is twice that,
// 2^-51 = 4.4e-16, relative to the larger of the two values (so a zero must be written as 0).
inline constexpr double kRedundantRelTolerance = 0x1p-51;

// calibration.json's text (2-space indent, object keys sorted, no trailing newline): every key
// and number text as metro has written it; keys added later sit beside the older ones
// (docs/calibration-format.md).
std::string ToJson(const Calibration& calibration);
// Reads calibration.json's text. Errors at `file:line:column` of the offending value with its
// path and what was expected (`c.json:41:17: tags[0].accel.bias[2]: expected a number, found
// the string "x"`): not JSON, a missing or malformed key, another schema, redundant fields
// that disagree beyond kRedundantRelTolerance (`matrix` against T K from `scale` and
// `misalignment`, `sensitivity` against 1 / `scale`) and standard uncertainties that are not
// the square roots of their covariance's diagonal. Keys added after the first files (the
// identification, record_conditions, static_residuals, ...) are optional.
Result<Calibration> CalibrationFromJson(std::string_view text, const std::string& file);
// ToJson with a trailing newline: the bytes `calibrate fit` writes.
std::string FormatCalibrationJson(const Calibration& calibration);
Result<Calibration> LoadCalibration(const std::string& path);

// ---- Positions in calibration.json, for checks made after reading ------------------------
//
// A path to a value of calibration.json: member names and array indices, e.g.
// {"tags", size_t{0}, "accel", "temperature", "bias_per_c", size_t{1}}.
using CalibrationPath = std::vector<std::variant<std::string, size_t>>;

// An input error (ErrorKind::kInput) with `message` at `file:line:column` of the value at `path`
// in the calibration.json `calibration` was read from (Calibration::source_file), or of its
// nearest ancestor present there (the tag object for a key the tag lacks, the top object for a
// missing top-level key). A calibration not read from a file (a fit's, one built in memory):
// the message alone, without file, line or column.
Error CalibrationErrorAt(const Calibration& calibration, const CalibrationPath& path,
                         std::string message);
// "calibration has no sensor 7 (it has: 2, 3); expected --sensor 2 or another of its sensors",
// at calibration.json's `tags` (CalibrationErrorAt): a command asked for a tag the file lacks.
Error NoSensorError(const Calibration& calibration, int sensor);
// The path of the tag calibration of `sensor` ({"tags", i}: tags are kept in file order), or
// {"tags"} when the calibration has none.
CalibrationPath CalibrationTagPath(const Calibration& calibration, int sensor);
// The path of the tag's accel or gyro object ({"tags", i, "accel"}).
CalibrationPath CalibrationSensorPath(const Calibration& calibration, int sensor, ImuSensor imu);
// The certificate id: the first 16 hex digits of the SHA-256 of FormatCalibrationJson (the
// certificate's section 1 and the registry's `certificate_id`).
std::string CalibrationCertificateId(const Calibration& calibration);

// A readable summary: per tag and sensor the constants with their standard uncertainties, the
// residuals and the segments.
std::string FormatCalibrationReport(const Calibration& calibration);

// A sensor's model check (issue #36) as the report prints it, each line starting with
// `indent`: status, chi-square, each comparison's test, statistic, dof, p-value and decision,
// the Type B term and the reason.
std::string FormatModelCheck(const ModelCheck& check, const std::string& indent);

// "sensor N accel: <reason>" for every sensor calibration.json marks model_rejected
// (ModelCheck): what `calibrate blob`, `push` and the certificate refuse without
// --accept-rejected-model. Empty when none is.
std::vector<std::string> ModelRejectedConstants(const Calibration& calibration);

// ---- Temperature validity range ----------------------------------------------------------
//
// The tag clamps the die temperature to [t_valid_min_c, t_valid_max_c] before it evaluates the
// temperature term b1 (T - t_ref_c) (docs/calibration-blob.md section 3); `calibrate blob`
// writes the range into the blob and `calibrate apply` clamps to the same range, so the PC and
// the tag agree at every temperature (docs/calibration-format.md, "Temperature validity
// range"). Default, per sensor calibration:
//
//   [max(-40, min_c - 5), min(85, max_c + 5)] degC
//
// where min_c .. max_c is its `static_pose_temperature` (the static poses' temperatures: the
// span a temperature term was fitted on) and 5 degC is kValidityMarginC. Without a recorded span
// (no temp_c in the data, or a file written before metro recorded it) the default is the MPU6050
// operating range -40 .. 85 degC, with a warning saying why. Explicit ends replace either end
// of the default; a range that reaches beyond the default is accepted with a warning that names
// the span and the temperature term the tag then applies at the ends (mg or deg/s).

inline constexpr double kOperatingMinC = -40.0;  // MPU6050 operating range, degC
inline constexpr double kOperatingMaxC = 85.0;   // (PS-MPU-6000A rev 3.4)
inline constexpr double kValidityMarginC = 5.0;  // beyond the fitted span, each side
// The narrowest range the tag accepts: twice the +-1 degC linearity of the MPU6050
// temperature sensor (METRO_FW_T_VALID_MIN_SPAN_C, docs/calibration-blob.md section 3.1).
inline constexpr double kMinValiditySpanC = 2.0;

struct ValidityOptions {
  std::optional<double> t_valid_min_c;  // degC; unset: the default's end
  std::optional<double> t_valid_max_c;

  // Each end that is set finite within -40 .. 85; both set: min < max and max - min >= 2.
  bool IsValid(std::string* why) const;
};

struct TemperatureValidity {
  double min_c = kOperatingMinC;  // The range the tag clamps to.
  double max_c = kOperatingMaxC;
  double default_min_c = kOperatingMinC;  // The default above (the data's).
  double default_max_c = kOperatingMaxC;
  std::optional<PoseTemperatureRange> span;  // static_pose_temperature, when recorded
  bool explicit_min = false;                 // min_c / max_c came from the options
  bool explicit_max = false;
  std::vector<std::string> warnings;  // Each starts with the sensor's name: "accel: ...".

  // The temperature the tag evaluates the temperature term at: a NaN temperature counts as
  // t_ref_c (the firmware's metro_fw_apply), then clamped to [min_c, max_c].
  double Clamp(double temp_c, double t_ref_c) const;
  // "from the static poses' span 22.4 .. 33.8 degC + 5 degC", "as given", ...
  std::string Describe() const;
};

// The validity range of one sensor calibration (rule above). Errors: invalid options, or a
// resulting range that is not within -40 .. 85 degC, has min >= max or is narrower than
// 2 degC (e.g. an explicit minimum above the default maximum, or poses recorded above 85 degC).
Result<TemperatureValidity> TemperatureValidityRange(const SensorCalibration& calibration,
                                                     const ValidityOptions& options = {});

struct ApplyCalibrationOptions {
  ValidityOptions validity;  // The same ends as given to `calibrate blob`.

  bool IsValid(std::string* why) const { return validity.IsValid(why); }
};

// How a session's temperatures met one sensor calibration's validity range.
struct SensorTemperatureCount {
  int sensor = 0;  // Tag number.
  ImuSensor imu = ImuSensor::kAccel;
  bool temperature_term = false;  // Only then does the clamp change the result.
  double t_ref_c = 0.0;
  TemperatureValidity validity;
  int64_t samples = 0;  // Rows of the tag (all have temp_c).
  int64_t below = 0;    // temp_c < min_c: clamped up
  int64_t above = 0;    // temp_c > max_c: clamped down
  int64_t missing = 0;  // temp_c NaN: t_ref_c applied

  int64_t outside() const { return below + above; }
  // One line for stderr: "sensor 2 accel: 120 of 13100 samples outside the validity range
  // 17.36 .. 38.84 degC (100 below, 20 above; from ...): clamped to the range, as the tag does".
  std::string Describe() const;
};

struct ApplySummary {
  int tags_calibrated = 0;
  int64_t rows = 0;
  std::vector<std::string> warnings;  // "sensor 2 accel: ...": the validity ranges' warnings
  // Per tag and sensor calibration, for tags whose session has a temp_c column.
  std::vector<SensorTemperatureCount> temperature;
};

// Adds (or overwrites) ax_g ay_g az_g and gx_dps gy_dps gz_dps in every tag of `session` with
// the calibrated values of the tag's calibration (matched by sensor number); every other
// column and every row is kept. A temperature term follows the tag's rule: temp_c is clamped
// to the sensor's validity range (TemperatureValidityRange with options.validity) and a NaN
// temp_c counts as t_ref_c; summary.temperature counts the samples outside the range. Errors:
// invalid options or validity range, a tag without a calibration, a tag without the
// calibration's input columns (e.g. ax_lsb for input_unit "LSB"), or a temperature model and no
// temp_c column.
Result<ApplySummary> ApplyCalibration(const Calibration& calibration, Session* session,
                                      const ApplyCalibrationOptions& options = {});

// The format a calibration's tags are named for (IsThesisTagFormat): a thesis tags' format
// when any record is one or does not say (files written before metro recorded it), otherwise
// the first record's (a calibration fitted only from other tools' files: imu_tk, EuRoC, ...).
SessionFormat CalibrationRecordsFormat(const Calibration& cal);

// A fit's tags named from the tags file (`calibrate fit --tags FILE`): each tag the file has an
// entry for gets the entry's device ID and profile, and its name where the name applies (a
// default body-part name only for the thesis tags' own records, CalibrationRecordsFormat).
void NameFittedTags(const TagRegistry& tags, Calibration* cal);

}  // namespace metro
