// Accelerometer and gyroscope calibration with the standard uncertainty of every constant.
//
// Model: see imu_model.hpp (calibrated = T * K * (raw - b), bias removed before scaling).
// Method (docs/calibration-model.md):
//  1. Segment each record (segments.hpp) into static poses, table runs and hand rotations.
//  2. Accelerometer: one residual per static pose, |M_a (r_mean - b)| - g_local/g_n = 0
//     (gravity-norm method of Tedaldi et al., ICRA 2014), started from a closed-form
//     axis-aligned ellipsoid fit of the pose means (or the nominal scale for fewer than 6
//     poses).
//  3. Gyroscope: static residuals r_mean - b = 0 (the bias is estimated, not frozen), table
//     residuals |M_g (r_mean - b)| - |table_rate| = 0, and for each hand rotation between two
//     static poses the gravity direction of the first pose rotated by the integrated gyroscope
//     minus the gravity direction of the second (imu_tk's method), started from the static
//     means and a one-dimensional search for an isotropic scale.
//  4. A joint Ceres fit of all residual groups, each whitened by its own residual standard
//     deviation from the separate fits; the covariance of the free parameters comes from
//     Ceres's Covariance API and is scaled by the residual variance of the joint fit (Type A,
//     JCGM 100:2008 4.2 and G.4), then propagated to M (JCGM 100:2008 5.1.2).
// A problem whose Jacobian is rank deficient is an error, never a set of numbers.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "metro/calibration/conformity.hpp"
#include "metro/calibration/imu_model.hpp"
#include "metro/calibration/segment_file.hpp"
#include "metro/calibration/segments.hpp"
#include "metro/core/status.hpp"
#include "metro/io/session.hpp"

namespace metro {

enum class TemperatureMode { kAuto, kOn, kOff };
enum class LossKind { kTrivial, kHuber, kCauchy };
const char* LossKindName(LossKind kind);  // "none", "huber", "cauchy"
std::optional<LossKind> ParseLossKind(std::string_view name);

struct CalibrationOptions {
  ModelKind accel_model = ModelKind::kFull;
  ModelKind gyro_model = ModelKind::kFull;
  // `--model auto` (issue #36; docs/calibration-model.md "Model selection"): fit the smallest
  // model of the ladder bias < scale < full that the data accept (accel_model / gyro_model
  // are then ignored). With the least-squares loss only: a robust loss has no chi-square on
  // the noise, so auto keeps accel_model / gyro_model with a warning.
  bool accel_auto = false;
  bool gyro_auto = false;
  // Fit every model of the ladder and compare each with the next larger one
  // (SensorCalibration::model_check.comparisons); implied by accel_auto / gyro_auto.
  // `calibrate fit` always compares; false keeps a library fit to the one model given.
  bool compare_models = false;
  double gravity_mps2 = kStandardGravityMps2;  // Local gravity; the accel target norm is
                                               // gravity_mps2 / 9.80665 g.
  // True when the user gave gravity_mps2 (`--gravity-mps2`), even as 9.80665: the calibration
  // records gravity_source "given"; false and 9.80665: "standard" (any other value: "given").
  bool gravity_given = false;
  // Standard uncertainty of gravity_mps2 [m/s^2] (`--gravity-u-mps2`), recorded in
  // calibration.json for the certificate's accelerometer budget; unset: not stated.
  std::optional<double> gravity_u_mps2;
  double accel_fs_g = 2.0;     // Full-scale setting of raw (LSB) accelerometer data.
  double gyro_fs_dps = 250.0;  // Full-scale setting of raw (LSB) gyroscope data.
  TemperatureMode temperature = TemperatureMode::kAuto;
  double min_temp_span_c = 2.0;  // kAuto fits b1 when the static poses span at least this.
  LossKind loss = LossKind::kTrivial;
  double loss_scale = 3.0;  // Of the robust loss, in units of the whitened residual.
  int sensor = 0;           // Calibrate only this tag; 0 = every tag.
  bool fit_gyro = true;     // False: accelerometer only.
  // False (`--accel-model none`): no accelerometer calibration; with gyro_model kBias the
  // gyroscope's bias at rest from one static record (gyro_bias.hpp).
  bool fit_accel = true;
  int max_iterations = 200;
  double max_rotation_s = 60.0;  // Longer hand rotations are not integrated (drift).
  SegmentationOptions segmentation;
  // Annotated segments (--segments FILE, segment_file.hpp) used instead of the detector when
  // not empty; segments_path names the file in errors.
  std::vector<AnnotatedSegment> annotated_segments;
  std::string segments_path;

  bool IsValid(std::string* why) const;
};

// One residual group of a fit.
struct ResidualGroup {
  std::string kind;  // "static_pose_norm", "static_rate", "table_rate", "rotation_gravity".
  int count = 0;     // Residual blocks (poses, intervals, runs, rotations).
  double rms = 0;    // Root mean square of the unwhitened residuals, in `unit`.
  std::string unit;  // e.g. "g", "LSB", "deg/s", "rad".
};

// Temperature of the static poses a fit used (each pose's mean temp_c): the conditions
// of the calibration (ISO/IEC 17025 7.8.4.1) and where a temperature term is supported.
struct PoseTemperatureRange {
  double min_c = 0;
  double mean_c = 0;
  double max_c = 0;
  int poses = 0;
};

// The residual of every static segment a sensor's fit used, before calibration (the segment's
// raw mean at the nominal sensitivity, NominalScale at the fit's full-scale setting) and after
// (SensorModel::Apply at the segment's mean temp_c, 0 degC without one): accelerometer
// |a| - gravity_mps2/g_n [g] (the gravity-norm residual of Tedaldi et al., ICRA 2014),
// gyroscope |w| [deg/s] (the rate at rest). Computed by the fit from its records, so the
// certificate's before/after plot needs no input file; calibration.json's `static_residuals`.
struct StaticResiduals {
  std::string unit;            // "g" or "deg/s" (OutputUnit).
  std::vector<double> before;  // One per used static segment, in segment order.
  std::vector<double> after;
};

// One nested-model comparison (issue #36): `smaller` against `larger` on the same residuals,
// measured against the noise of the data. When the larger model describes the data to its
// noise (its chi-square below the 99 % point of its law), the chi-square difference
// chi2_smaller - chi2_larger ~ chi2(p_larger - p_smaller) (test "chi2_difference", dof2 0);
// otherwise the F-test F = (delta chi2 / delta p) / (chi2_larger / dof_larger)
// ~ F(delta p, dof_larger) (test "F"), which scales by the larger model's own misfit.
// `rejected`: the smaller model is rejected at the 5 % level (p_value < 0.05).
struct ModelComparison {
  ModelKind smaller = ModelKind::kScale;
  ModelKind larger = ModelKind::kFull;
  std::string test;  // "chi2_difference" or "F"; empty when not computed (`note` says why).
  double statistic = 0;
  double dof1 = 0;  // Added parameters (the chi-square's dof, or F's numerator).
  double dof2 = 0;  // F's denominator (the larger model's residual dof); 0 for chi2_difference.
  double p_value = 1;
  bool rejected = false;
  std::string note;
};

// The Type B term for the cross-axis sensitivity a model leaves out (issue #36), from a stated
// spec: every omitted misalignment term m is uniform in +-half_width (u = half_width /
// sqrt(3), JCGM 100:2008 4.3.7), propagated to every constant through the fit's Jacobian
// (d theta / d m = -(J^T J)^-1 J^T J_m; JCGM 100:2008 5.1.2) and added to the covariance.
struct CrossAxisTypeB {
  std::string source;     // The spec, e.g. "MPU-6000/6050 datasheet PS-MPU-6000A-00 rev 3.4 ...".
  double half_width = 0;  // Of each term [rad, = fraction of the sensitivity].
  std::string distribution;        // "rectangular".
  double u = 0;                    // half_width / sqrt(3).
  std::vector<std::string> terms;  // The omitted terms, e.g. "accel.a_yz", "gyro.g_xz".
};

// How far a sensor's fitted model is supported by the data (issue #36), calibration.json's
// `model_check`. status: "accepted" (the model describes the data to its noise and no larger
// model is needed), "rejected" (its chi-square above the 99 % point of its law, or a
// comparison rejects it against a larger model), "exact_fit" (as many parameters as distinct
// orientations: nothing tests it). A rejected or exact scale model carries `type_b`; a
// rejected full model carries the misfit in u (between-orientation component, residual
// scatter); a rejected or exact bias model, and an exact full model, are `model_rejected`:
// `calibrate blob`, `push` and the certificate refuse them without --accept-rejected-model.
struct ModelCheck {
  std::string selection;  // "auto" (--model auto), "given", or "imported" (kImportedSelection).
  std::vector<ModelComparison> comparisons;
  std::string status;
  double chi2 = -1;     // Of the fitted model against the noise; -1 when not measured.
  double chi2_dof = 0;  // Its degrees of freedom (m - p; the gyroscope's sum of E_g).
  double p_value = -1;  // P(chi2(dof) >= chi2); -1 when not measured.
  std::optional<CrossAxisTypeB> type_b;
  bool model_rejected = false;
  std::string reason;  // Why (status other than "accepted"), and what to do.
};

struct SensorCalibration {
  SensorModel model;
  // Standard uncertainties (k = 1) of the constants, in the units of the constants;
  // 0 for a constant the model holds fixed.
  Eigen::Vector3d bias_u = Eigen::Vector3d::Zero();
  Eigen::Vector3d scale_u = Eigen::Vector3d::Zero();
  std::vector<double> misalignment_u;
  Eigen::Vector3d bias_per_c_u = Eigen::Vector3d::Zero();
  Eigen::Matrix3d matrix_u = Eigen::Matrix3d::Zero();  // Of each element of M.
  // Derived: sensitivity s = 1/k [input unit / output unit] and its uncertainty u_k / k^2.
  Eigen::Vector3d sensitivity = Eigen::Vector3d::Zero();
  Eigen::Vector3d sensitivity_u = Eigen::Vector3d::Zero();
  // Covariance of the free parameters, in the layout of imu_model.hpp restricted to the names.
  std::vector<std::string> parameter_names;
  Eigen::MatrixXd covariance;
  Eigen::MatrixXd Correlation() const;
  double residual_rms = 0;    // Main residual (accel: gravity norm per pose; gyro:
  std::string residual_unit;  // rotation gravity angle, else table rate), in this unit.
  std::vector<ResidualGroup> groups;
  std::vector<Segment> segments;  // The segments this sensor's fit used.
  int dof = 0;                    // Residual degrees of freedom minus free parameters.
  double reduced_chi2 = 0;        // Of the whitened fit (about 1 when consistent).
  double coverage_factor_95 = 0;  // Student t_0.975(dof) (JCGM 100:2008 G.3.2).
  // When every input has a temp_c column.
  std::optional<PoseTemperatureRange> static_pose_temperature;
  // Raw (LSB) input only: the full-scale setting the fit took the nominal sensitivity from
  // (CalibrationOptions::accel_fs_g [g] or gyro_fs_dps [deg/s]); calibration.json's
  // `full_scale` (absent in older files and for input in physical units).
  std::optional<double> full_scale;
  // M as calibration.json's `matrix` holds it (set by the reader, which checked it against
  // model.Matrix() to double rounding); unset after a fit, where M is model.Matrix().
  std::optional<Eigen::Matrix3d> matrix;
  // Set by CalibrateSessions (empty lists when no static segment was used); absent in files
  // written before metro recorded it.
  std::optional<StaticResiduals> static_residuals;

  // The model comparisons and the chosen model's standing (issue #36); absent in files written
  // before metro made them, and for the gyroscope's bias at rest.
  std::optional<ModelCheck> model_check;

  // The M that apply, the report and the blob use: `matrix` when read from a file.
  Eigen::Matrix3d M() const { return matrix ? *matrix : model.Matrix(); }
};

// ModelCheck::selection of a sensor read by `calibrate import` (interchange.hpp).
inline constexpr const char* kImportedSelection = "imported";

// An import whose standard uncertainties are unknown (no covariance sidecar, or a format that
// does not carry the biases): its u and covariance hold zeros that stand for nothing, and it is
// model_rejected, so blobs, pushes and certificates refuse it. Readers print "u unknown".
inline bool UncertaintyUnknown(const SensorCalibration& c) {
  return c.model_check && c.model_check->selection == kImportedSelection &&
         c.model_check->model_rejected;
}

// Fills every value derived from c->model and c->covariance (rows in FreeNames order, as
// c->parameter_names): bias_u, scale_u, misalignment_u, bias_per_c_u (square roots of the
// diagonal), matrix_u (JCGM 100:2008 5.1.2, u of each element of M = T K propagated from the
// covariance), sensitivity and sensitivity_u. The fit calls it, and the loader of
// calibration.json checks the file's values against it.
// Precondition: covariance is square with as many rows as the model has free parameters.
void DeriveUncertainties(SensorCalibration* c);

// The conditions of one record of a tag (ISO/IEC 17025:2017 7.8.4.1 a: the environmental
// conditions of the calibration), from the data at fit time: calibration.json's
// `record_conditions`.
struct RecordConditions {
  int input = 0;          // Index of the record in Calibration::inputs.
  int64_t samples = 0;    // Rows of the tag in the record.
  double duration_s = 0;  // Last minus first observation time of the tag.
  // Lowest and highest finite temp_c of the tag; absent without a temp_c column (or with NaN
  // only).
  std::optional<double> temp_min_c;
  std::optional<double> temp_max_c;
};

struct TagCalibration {
  int sensor = 1;
  // The tag's FICR device ID when known (`calibrate fit --tags FILE`), (DEVICEID[1] << 32) |
  // DEVICEID[0]; calibration.json's `device_id`.
  std::optional<uint64_t> device_id;
  // The tag's name and declared IMU profile ("mpu6050", "generic") from the tags file
  // (`calibrate fit --tags FILE`); empty when not given. calibration.json's `name`, `profile`.
  std::string name;
  std::string profile;
  std::optional<SensorCalibration> accel;
  std::optional<SensorCalibration> gyro;
  std::vector<Segment> segments;  // Every segment found, in every input.
  double threshold_factor = 0;    // Static detector factor chosen (first input).
  int saturated_samples = 0;      // Excluded samples (either sensor).
  int iterations = 0;
  std::vector<std::string> warnings;
  // One per input record that holds the tag, in input order; set by CalibrateSessions, absent
  // in files written before metro recorded it.
  std::optional<std::vector<RecordConditions>> record_conditions;
};

struct InputFile {
  InputFile() = default;
  InputFile(std::string path_in, std::string sha256_in)
      : path(std::move(path_in)), sha256(std::move(sha256_in)) {}

  std::string path;
  std::string sha256;
  // What the record is and when it was measured (ISO/IEC 17025:2017 7.8.2.1 e, f); absent in
  // files written before metro recorded them. `format`: SessionFormatName ("csv", "receiver",
  // "imutk", ...). `duration_s`: last minus first observation time over every tag.
  // `start_utc`, `end_utc` (ISO 8601): the first and last observation when the record's time
  // column reads as a Unix clock between 2000-01-01 and 2100-01-01 (RecordTimeSpan); empty
  // when its times are relative (a tag's or receiver's clock since start).
  std::string format;
  std::optional<double> duration_s;
  std::string start_utc;
  std::string end_utc;
};

// The time span of a record (the InputFile fields above), from its tags' observation times.
// The times are a date when the time column read as Unix time falls within 2000 .. 2100:
// integer times (t_ms, t_us, t_ns) from InputDialect::time_origin_ns plus t_s, otherwise t_s
// itself (a column of epoch seconds).
InputFile RecordTimeSpan(const Session& session);

// The content of calibration.json ("metro.calibration/1", docs/calibration-format.md).
struct Calibration {
  double gravity_mps2 = kStandardGravityMps2;
  // Where gravity_mps2 came from: "standard" (g_n = 9.80665 m/s^2, the conventional value of
  // the 3rd CGPM, 1901), "given" (`calibrate fit --gravity-mps2`, the user's local value), or
  // empty (a file written before metro recorded it). calibration.json's `gravity_source`.
  std::string gravity_source;
  // The standard uncertainty of gravity_mps2 when the user stated it (`calibrate fit
  // --gravity-u-mps2`); calibration.json's `gravity_u_mps2`, absent otherwise (the certificate
  // then states the u it assumes, docs/calibration-model.md "Gravity").
  std::optional<double> gravity_u_mps2;
  std::vector<InputFile> inputs;
  std::string tool_version;
  std::string date_utc;  // ISO 8601, e.g. "2024-05-01T12:00:00Z".
  std::vector<TagCalibration> tags;
  // Statements of conformity with a spec (`calibrate fit --spec`, docs/conformity.md); absent
  // when no spec was given.
  std::optional<ConformityStatement> conformity;
  // The calibration.json this was read from (CalibrationFromJson, LoadCalibration in
  // calibration_io.hpp): its name and its text as read, so that a check made after reading
  // (`calibrate blob`, `push`, `apply`) can name the file:line:column of the value it is about
  // (CalibrationErrorAt). Empty for a calibration made by a fit or built in memory. Not part
  // of the calibration: ToJson ignores it.
  std::string source_file;
  std::shared_ptr<const std::string> source_text;

  const TagCalibration* FindTag(int sensor) const;
};

// The columns the fit needs, checked before fitting so that a session without them is an
// input error (`calibrate fit` exits 2): for every tag to be calibrated (options.sensor) in
// every session, a complete accelerometer family (AxisUnits/FamilyColumns in
// metro/io/columns.hpp: ax ay az with _lsb, _g or _mps2); no incomplete gyroscope family;
// and, with fit_gyro, gyroscope columns in every session when any session of that tag has
// them (a tag's records are fitted together). A tag without any gyroscope column anywhere
// stays an accelerometer-only fit with a warning. The error's file is the session; its
// message names the sensor and, for a partial family, the family and its missing columns:
// "sensor 1: the gyroscope calibration needs gx_dps, gy_dps, gz_dps; missing gx_dps, gy_dps".
Status CheckCalibrationColumns(const std::vector<const Session*>& sessions,
                               const CalibrationOptions& options);

// The options of a `calibrate fit` (and metro.calibrate.fit) made whole and checked: with
// fit_accel false (`--accel-model none`) only gyro_model kBias without auto and no segments
// file (the whole record is the static pose); the annotated segments read from
// `segments_path` when not empty (ReadSegmentsFile); then IsValid. Errors are input errors
// (`calibrate fit` exits 2); the model and segments messages name the flags.
Result<CalibrationOptions> ResolveFitOptions(CalibrationOptions options,
                                             const std::string& segments_path);

// Calibrates one tag from one or more records of it (e.g. a static multi-pose session and a
// rotation-table session). Errors say what to collect.
Result<TagCalibration> CalibrateTag(const std::vector<const Tag*>& records,
                                    const CalibrationOptions& options);

// The static residuals of `calibration` (StaticResiduals above) from the records it was
// fitted on (`records[segment.piece]`, the tag's records in the order given to CalibrateTag).
// Precondition: full_scale is set for LSB input. Errors: no nominal scale for the input unit.
Result<StaticResiduals> ComputeStaticResiduals(const SensorCalibration& calibration,
                                               const std::vector<const Tag*>& records,
                                               double gravity_mps2);

// Calibrates every tag (or options.sensor) found in the sessions; a tag's records from several
// sessions are fitted together (with fit_accel false: CalibrateGyroBiasAtRest, one record per
// tag). Fills inputs, tool version and date, and what the certificate shows of the records
// (each sensor's static_residuals, each tag's record_conditions), so that no view reloads
// an input.
Result<Calibration> CalibrateSessions(const std::vector<const Session*>& sessions,
                                      const CalibrationOptions& options);

}  // namespace metro
