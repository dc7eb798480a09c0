// Private: the stages of one tag's calibration (CalibrateTag, calibrate.hpp), in the order
// CalibrateTag runs them (method: docs/calibration-model.md):
//
//   records      ReadRecords, SummarizeRecords    inputs, units, saturation, segments
//   poses        MeanPoses                        static and table means
//   temperature  DecideTemperature                whether b1 is fitted, t_ref, pose span
//   start        StartAccel, StartGyro,           ellipsoid/nominal start, sphere span check;
//                SetScaledStart, ApplyGyroStart   gyroscope bias and isotropic scale
//   rotations    BuildRotations, CheckGyroMotion  hand rotations between static poses
//   solves       SolveAccel, SolveGyro            Ceres stages, rank, covariance,
//                                                 PropagateAccelUncertainty
//   assembly     Unscale, AssembleAccel,          input units, SensorCalibration,
//                AssembleGyro                     groups, segments, CheckDetermined
//
// Every fit works on scaled parameters (TagProblemData::accel_ref, gyro_ref) held in one
// ParameterBlocks (parameter_blocks.hpp). Errors are messages for the user, starting with
// "sensor N: " where they name the tag.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "calibration/parameter_blocks.hpp"
#include "calibration/residuals.hpp"
#include "metro/calibration/calibrate.hpp"

namespace ceres {
class Problem;
}

namespace metro::calibration_internal {

// ---- Records ----------------------------------------------------------------------------

// One tag of one input, with the columns the calibrator needs.
struct Record {
  int piece = 0;
  std::vector<double> t_s;
  std::vector<Eigen::Vector3d> accel, gyro;
  std::string accel_unit, gyro_unit;
  std::vector<double> temp_c, table_rate_dps;
  bool has_table_column = false;
  std::vector<unsigned char> accel_sat, gyro_sat, saturated;
  int accel_sat_count = 0, gyro_sat_count = 0;
  SegmentationSummary seg;
};

// Which axis family of the sensor a tag holds (columns.hpp): the first complete one in
// AxisUnits order (raw counts preferred), or, when none is complete, the first the tag holds
// part of (`unit` is nullptr then) or none at all (`family` empty).
struct FamilyMatch {
  const Unit* unit = nullptr;        // The complete family's unit; nullptr if none.
  std::vector<std::string> family;   // Its columns (or the partial family's).
  std::vector<std::string> missing;  // Of a partial family, the absent columns.
};
FamilyMatch FindFamily(const Tag& tag, ImuSensor sensor);

// "sensor 1: the gyroscope calibration needs gx_dps, gy_dps, gz_dps; missing gx_dps, gy_dps"
std::string IncompleteFamilyMessage(int sensor, ImuSensor imu, const FamilyMatch& match);

// The families the calibrator accepts: "ax_lsb ay_lsb az_lsb (or ax_g ay_g az_g, or ax_mps2
// ay_mps2 az_mps2)".
std::string FamilyChoices(ImuSensor imu);

// Reads one input's columns, flags saturated raw counts and segments it (piece = input index).
Result<Record> ReadRecord(const Tag& tag, int piece, const CalibrationOptions& options);

struct RecordSet {
  std::vector<Record> records;  // One per input, in input order.
  std::string accel_unit;       // Of every record.
  std::string gyro_unit;        // Of every record; empty without gyroscope columns.
  bool has_gyro = false;        // fit_gyro and gyroscope columns.
};

// Reads every input of tag `sensor` and checks that they agree on units.
Result<RecordSet> ReadRecords(const std::vector<const Tag*>& tags, const CalibrationOptions& o,
                              int sensor);

// What the detector left out that the user recorded: shorter still periods (how many, how
// long, the --min-static-s that accepts them) and steady rotations; "" when nothing. Appended
// to a refusal for too few poses.
std::string PoseShortfallHint(const std::vector<Record>& records);

// The record-level results of `out`: warnings (no gyroscope, saturated samples, a table column
// without runs), saturated_samples, every segment, threshold_factor.
void SummarizeRecords(const RecordSet& set, const CalibrationOptions& o, TagCalibration* out);

// ---- Poses ------------------------------------------------------------------------------

// Means over a segment (saturated samples left out).
struct Pose {
  const Segment* segment = nullptr;  // Into the record's segments.
  int record = 0;
  Eigen::Vector3d accel = Eigen::Vector3d::Zero();
  Eigen::Vector3d gyro = Eigen::Vector3d::Zero();
  Eigen::Vector3d gyro_sd = Eigen::Vector3d::Zero();  // Per-sample standard deviation.
  double temp_c = 0;
  size_t n = 0;
};
Pose MeanOver(const Record& r, int record_index, const Segment& s);

struct PoseMeans {
  std::vector<Pose> statics;  // Static poses, all records, in record then time order.
  std::vector<Pose> tables;   // Table runs (only with_tables).
};
// The records must outlive the result (Pose::segment points into them).
PoseMeans MeanPoses(const std::vector<Record>& records, bool with_tables);

// ---- Temperature decision ---------------------------------------------------------------

struct TemperatureDecision {
  bool fit = false;    // Whether b1 is fitted.
  double t_ref_c = 0;  // Mean of the static poses' temperatures when fitted, else 0.
  // The static poses' temperature span when every input has temp_c (and there are poses).
  std::optional<PoseTemperatureRange> pose_range;
};

bool EveryRecordHasTemperature(const std::vector<Record>& records);

// kOff: never; kAuto: when every input has temp_c and the static poses span at least
// o.min_temp_span_c; kOn: always, an error without temp_c or without any span.
Result<TemperatureDecision> DecideTemperature(bool every_input_has_temp,
                                              const std::vector<Pose>& statics,
                                              const CalibrationOptions& o, int sensor);

// ---- Problem data and start values ------------------------------------------------------

// Everything one tag's fit needs, built once.
struct TagProblemData {
  std::vector<Record> records;
  std::vector<Pose> statics;            // Static poses, all records.
  std::vector<Pose> tables;             // Table runs.
  std::vector<RotationData> rotations;  // Hand rotations (weight 1).
  std::vector<const Segment*> rotation_segments;
  bool has_gyro = false;
  bool temperature = false;
  double t_ref_c = 0;
  double target_norm = 1;
  // The fit runs on data multiplied by a reference scale (the start value of K), so that every
  // parameter is O(1) in output units: b' = k_ref b, k' = k / k_ref, b1' = k_ref b1. Without
  // it, biases in counts next to scales of 1e-4 make J^T J too ill-conditioned for Ceres's
  // covariance. Rotation data are stored already scaled.
  Eigen::Vector3d accel_ref = Eigen::Vector3d::Ones();
  Eigen::Vector3d gyro_ref = Eigen::Vector3d::Ones();
};

// The state of the fit across stages: group standard deviations that whiten the next stage,
// the last stage's residuals, the solver's iterations and convergence.
struct Fit {
  double s_accel = 1, s_static = 1, s_table = 1, s_rotation = 1;
  std::vector<double> r_accel, r_static, r_table, r_rotation;  // Unwhitened residuals.
  int iterations = 0;
  bool converged = false;
  std::string message;
};

// Closed-form start: axis-aligned ellipsoid A x^2 + B y^2 + C z^2 + D x + E y + F z = 1 through
// the pose means (linear least squares on centred, scaled data). Returns false when the fit is
// not an ellipsoid.
bool EllipsoidStart(const std::vector<Eigen::Vector3d>& points, double target_norm,
                    Eigen::Vector3d* bias, Eigen::Vector3d* scale);

// Start values of one sensor in input units (scale: output units per input unit).
struct SensorStart {
  Eigen::Vector3d bias = Eigen::Vector3d::Zero();
  Eigen::Vector3d scale = Eigen::Vector3d::Ones();
};

// Checks the pose count for the accelerometer model, starts from the ellipsoid (else the
// nominal scale, with a warning), and checks that the poses span the sphere (an error for
// the scale and full models, a warning for bias). `accel_unit` gives the nominal scale.
// `hint` (PoseShortfallHint) ends the too-few-poses error.
Result<SensorStart> StartAccel(const std::vector<Pose>& statics, double target_norm,
                               const std::string& accel_unit, bool temperature,
                               const CalibrationOptions& o, int sensor,
                               std::vector<std::string>* warnings, const std::string& hint = "");

// Sets a sensor's blocks to the scaled start: b' = ref b, k' = 1 (ref = start.scale).
void SetScaledStart(ImuSensor sensor, const SensorStart& start, ParameterBlocks* x);

// Group standard deviations that weight the gyroscope's first fit.
struct GyroWeights {
  double s_static = 1;    // Input units (unscaled).
  double s_table = 1;     // deg/s.
  double s_rotation = 1;  // Unit-vector difference.
};
struct GyroStart {
  SensorStart start;  // Bias: mean of the static means; scale: isotropic.
  GyroWeights weights;
};

// Bias from the static means; for the scale and full models an isotropic scale from the table
// runs (median |rate| / |r_mean - b|), else from a log-grid and golden-section search on the
// hand rotations (`rotations` unscaled in the gyroscope, `x` holding the accelerometer's
// solution), which fails when no scale matches the accelerometer's gravity directions.
Result<GyroStart> StartGyro(const std::vector<Pose>& statics, const std::vector<Pose>& tables,
                            const std::vector<RotationData>& rotations, const ParameterBlocks& x,
                            double gyro_nominal, ModelKind gyro_model, int sensor);

// From here on the gyroscope works in scaled units: d->gyro_ref = start scale, the gyroscope's
// blocks of x at the scaled start (SetScaledStart), fit's first weights (s_static scaled), and
// d->rotations' samples multiplied by gyro_ref.
void ApplyGyroStart(const GyroStart& start, TagProblemData* d, ParameterBlocks* x, Fit* fit);

// ---- Rotations --------------------------------------------------------------------------

struct RotationSet {
  std::vector<RotationData> data;        // Accelerometer means scaled by accel_ref.
  std::vector<const Segment*> segments;  // The rotation segment of each, into `segments`.
};

// The hand rotations between consecutive static poses of one record: samples from the end of
// pose i to the start of pose j. A rotation with a saturated gyroscope sample or longer than
// max_rotation_s is not used (its segment in `segments` says why). `segments` holds every
// segment of every record (TagCalibration::segments); `statics` are MeanPoses' static poses.
RotationSet BuildRotations(const std::vector<Record>& records, const std::vector<Pose>& statics,
                           const TemperatureDecision& temperature, const Eigen::Vector3d& accel_ref,
                           double max_rotation_s, std::vector<Segment>* segments);

// Enough table runs and hand rotations for the gyroscope model.
Status CheckGyroMotion(size_t table_runs, size_t rotations, ModelKind gyro_model, bool temperature,
                       int sensor);

// ---- Solves -----------------------------------------------------------------------------

// The (whitened, robustified) Jacobian of `problem` over `blocks`, dense; rows in the order the
// residual blocks were added.
std::optional<Eigen::MatrixXd> DenseJacobian(ceres::Problem* problem,
                                             const std::vector<double*>& blocks);

// The implicit-function sensitivity of the free parameters to blocks the fit holds:
// -(J_f^T J_f)^-1 J_f^T J_h, J_f the whitened Jacobian of `problem` over `free_blocks` (p
// columns) and J_h over `held` (made variable only to evaluate it, constant again after);
// columns in the order of `held`'s parameters. nullopt when the Jacobian cannot be formed.
std::optional<Eigen::MatrixXd> HeldTermSensitivity(ceres::Problem* problem,
                                                   const std::vector<double*>& free_blocks, int p,
                                                   const std::vector<double*>& held);

// kAccel/kGyro: unweighted start fits; kAccelFinal/kGyroFinal: whitened by the group standard
// deviations of the start fits, with the robust loss when one is chosen. The accelerometer is
// held in the gyroscope stages (the gravity norm alone determines it, as in imu_tk); its
// uncertainty reaches the gyroscope through PropagateAccelUncertainty.
enum class Stage { kAccel, kAccelFinal, kGyro, kGyroFinal };

// Builds and solves one stage; residuals of every group are evaluated at the solution.
// keep_problem: the problem to build (kept for the covariance), else a local one.
Status SolveStage(Stage stage, const TagProblemData& d, const CalibrationOptions& o,
                  ParameterBlocks* x, Fit* fit, ceres::Problem* keep_problem,
                  std::vector<double*>* free_blocks, int* residual_count);

// One sensor's solution in scaled parameters.
struct SensorSolution {
  std::vector<double*> free_blocks;  // Into the ParameterBlocks solved.
  Eigen::MatrixXd covariance;        // Of the free parameters, FreeNames order.
  double reduced_chi2 = 0;
  int residuals = 0;          // m
  int parameters = 0;         // p
  int dof = -1;               // Residual degrees of freedom when not m - p (distinct orientations).
  bool u_from_noise = false;  // The covariance rests on the poses' noise alone (k = 1.96).
  std::vector<std::string> warnings;
  // The residuals against the noise of the data (HonestAccelCovariance: sum r_i^2 / sigma_i^2
  // with m - p dof; GyroNoiseChiSquare: sum chi2_g with sum E_g dof); chi2 -1 when not
  // measured (a robust loss, poses without noise). The model comparisons use them.
  double chi2 = -1;
  double chi2_dof = 0;
  int orientations = 0;  // Accelerometer: distinct orientations (0 when not counted).
  // d theta / d m (rows: the free parameters, FreeNames order, scaled; columns: the omitted
  // misalignment terms, accelerometer a_yz a_zy a_zx then, for the gyroscope, g_yz .. g_yx):
  // how the solution moves with cross-axis terms the model holds at 0 (-(J^T J)^-1 J^T J_m
  // of the whitened fit; for the gyroscope the accelerometer's terms also act through the
  // accelerometer's constants). Columns of terms the model frees are 0; empty for the full
  // model. CrossAxisTypeB (calibrate.hpp) multiplies it by the spec's u.
  Eigen::MatrixXd cross_axis_sensitivity;

  // What the chosen model's uncertainty still needs after the model comparison (gyroscope;
  // CompleteGyroUncertainty): the final stage's problem over the solved blocks, the residual
  // variance s^2 that scales Ceres's covariance, and the whitened Jacobians of that problem
  // over the free blocks (`jacobian_free`) and over the held accelerometer's free blocks
  // (`jacobian_accel`, empty when the problem does not hold every one of them).
  std::shared_ptr<ceres::Problem> problem;
  double s2 = 0;
  Eigen::MatrixXd jacobian_free, jacobian_accel;
  // False after SolveGyro: `covariance` is the one the model comparison and CheckDetermined
  // need, s^2 (J^T J)^-1 from the Jacobian above plus the accelerometer's share, and
  // cross_axis_sensitivity is not formed; CompleteGyroUncertainty makes both the stated ones.
  bool complete = true;
};

// The accelerometer's covariance from the noise of each pose and the number of distinct
// orientations (issue #23; docs/calibration-model.md "Uncertainty"), replacing the covariance
// scaled by the residuals' own scatter. Each pose residual r_i (gravity norm, g) has the noise
// sigma_i of its mean along gravity (the samples' variance with the AR(1) factor
// (1 + rho) / (1 - rho) of their lag-1 autocorrelation). Poses whose gravity directions lie
// within kSameOrientationDeg (and, with a temperature term, 1 degC) are one orientation
// cluster: repeated stops there share any error the model leaves, so
//   V = f diag(sigma_i^2) + tau^2 B   (B_ij = 1 within a cluster)
// with f = max(1, within-cluster chi-square / (m - C)) and tau^2 the between-orientation
// variance by the method of moments on the cluster means (0 when the model fits to the
// noise). The fit is least squares with equal weights (J the Jacobian of the residuals), so
//   cov = (J^T J)^-1 J^T V J (J^T J)^-1            (sandwich; JCGM 100:2008 5.2, C.3.4)
// reduced_chi2 = sum r_i^2 / sigma_i^2 / (m - p): about 1 when the model describes the data to
// its noise, larger when it does not (a warning names it). Fewer clusters than p + 1 is an
// error: repeated stops at one orientation do not determine more constants.
// Only for the trivial loss (a robust loss keeps the scaled covariance).
constexpr double kSameOrientationDeg = 10.0;
Status HonestAccelCovariance(const TagProblemData& d, const ParameterBlocks& x,
                             const CalibrationOptions& o, int sensor, const Fit& fit,
                             ceres::Problem* problem, SensorSolution* solution);

// The gyroscope's residuals against the noise of the data (issue #23; docs/calibration-model.md
// "Uncertainty"), so that a model that does not fit shows. The residuals, each rotation's
// projected on the plane normal to gravity at its end pose (2 of its 3 components carry
// information), have the noise covariance S:
//   static pose, per axis: the variance of the pose's mean rate (AR(1) factor as above);
//   table run: that variance along the rate direction;
//   rotation i -> j: R^T du_i - du_j + [v]x dphi, du the noise of a pose's gravity direction
//     (its mean's noise normal to gravity / |a|), shared by the two rotations that meet at a
//     pose, and dphi the integrated rate noise, variance s_w^2 sum dt_k^2 (s_w^2 the rate
//     samples' long-run variance at the static poses); plus G_a cov_a G_a^T, the
//     accelerometer's parameter error (G_a the rotations' Jacobian over its parameters).
// The fit is weighted least squares (W: 1 / each group's scatter); the chi-square is that of
// the generalized least-squares step from its solution in S's metric (A = J^T S^-1 J,
// r_G = r - J A^-1 J^T S^-1 r, chi2 = r_G^T S^-1 r_G): chi-squared with m - p dof for
// Gaussian noise and a model linear near the solution, and the difference of nested models'
// chi-squares chi-squared with their difference in p (the model comparisons). Group g's share
// r_G,g^T S_gg^-1 r_G,g has the expectation E_g = n_g - tr(S_gg^-1 J_g A^-1 J_g^T), the E_g
// adding up to m - p. reduced_chi2 = chi2 / (m - p): about 1 when the model describes the data
// to its noise; above the 99 % point of the chi-square law with m - p degrees of freedom a
// warning names each group's ratio. The covariance stays the one scaled by each group's own
// scatter (JCGM 100:2008 4.2.3), which holds any excess over the noise: u grows with it.
// Only for the trivial loss; a pose without measurable noise leaves reduced_chi2 as the
// scaled fit's, with a warning.
// `solution` holds the whitened Jacobians of the final stage (SensorSolution::jacobian_free,
// jacobian_accel).
Status GyroNoiseChiSquare(const TagProblemData& d, const ParameterBlocks& x,
                          const CalibrationOptions& o, int sensor, const Fit& fit,
                          const SensorSolution& accel, SensorSolution* solution);

// The accelerometer: unweighted fit, whitened final fit, rank, covariance; the cross-axis
// sensitivity of a model other than full follows in CompleteAccelUncertainty (the chosen
// model's alone).
Result<SensorSolution> SolveAccel(const TagProblemData& d, const CalibrationOptions& o, int sensor,
                                  ParameterBlocks* x, Fit* fit);

// The cross_axis_sensitivity of the accelerometer's solution `s` (x: the blocks it solved), for
// a model other than full; the problem it was solved on is released.
void CompleteAccelUncertainty(ModelKind accel_model, ParameterBlocks* x, SensorSolution* s);

// The gyroscope with the accelerometer held: two re-weighted passes, whitened final fit, rank,
// the chi-square against the noise, and the covariance the model comparison and CheckDetermined
// need (SensorSolution::complete false; one evaluation of the Jacobian). The ladder fits every
// model this way and completes the chosen one's uncertainty alone (issue #36: three Ceres
// covariances made `calibrate fit` slower).
Result<SensorSolution> SolveGyro(const TagProblemData& d, const CalibrationOptions& o, int sensor,
                                 const SensorSolution& accel, ParameterBlocks* x, Fit* fit);

// The gyroscope's stated uncertainty (s->complete): Ceres's covariance of the kept problem times
// s^2 (DENSE_SVD, no pseudo-inverse), the cross_axis_sensitivity of models other than full,
// plus the accelerometer's uncertainty (PropagateAccelUncertainty); releases the problem.
// `o` gives both sensors' models, x the blocks the solution was solved on.
Status CompleteGyroUncertainty(const CalibrationOptions& o, int sensor, const SensorSolution& accel,
                               ParameterBlocks* x, SensorSolution* s);

// Rotations that contradict the rest (issue #23): an orientation change the gyroscope did not
// see (the tag re-seated between poses), a knock, a burst. Their gravity-direction residual
// angle is far outside the others': the angles of consistent rotations follow a Rayleigh law
// (a two-dimensional residual), whose median is 1.1774 sigma; the worst rotation above
// max(6 sigma, 1 deg) is returned (index into d.rotations), none with fewer than 6 rotations.
std::optional<size_t> ContradictingRotation(const Fit& fit, size_t rotations);

// Marks rotation `index` of d unused in `segments` (note: its residual angle and why) and
// removes it from d; returns the warning that names it.
std::string ExcludeRotation(size_t index, const Fit& fit, TagProblemData* d,
                            std::vector<Segment>* segments, int sensor);

// cov_g += S cov_a S^T, S = -(G_g^T G_g)^-1 G_g^T G_a (JCGM 100:2008 5.2), from the whitened
// Jacobian of the gyroscope problem over its free blocks (G_g) and the accelerometer's free
// blocks (G_a); nothing when the gyroscope problem does not hold every accelerometer block.
Status PropagateAccelUncertainty(ceres::Problem* gyro_problem,
                                 const std::vector<double*>& gyro_free, int pg,
                                 const SensorSolution& accel, Eigen::MatrixXd* cov_g);

// ---- Assembly ---------------------------------------------------------------------------

// Back to input units: b = b' / k_ref, k = k' k_ref, b1 = b1' / k_ref; the covariance
// transforms with the diagonal Jacobian D of that map (JCGM 100:2008 5.1.2).
void Unscale(const Eigen::Vector3d& ref, ImuSensor sensor, ModelKind kind, bool temperature,
             ParameterBlocks* x, Eigen::MatrixXd* cov);

// The SensorCalibration of one sensor's blocks of `x` (input units) and covariance.
SensorCalibration MakeSensorCalibration(ImuSensor sensor, ModelKind kind, bool temperature,
                                        double t_ref_c, const std::string& input_unit,
                                        const ParameterBlocks& x, const Eigen::MatrixXd& cov);

// A fit can be full rank and still not determine a constant: an uncertainty as large as the
// datasheet tolerance (accel: 20 mg, 2 % scale, 0.02 rad; gyro: 1 deg/s, 2 %, 0.02 rad) is
// refused.
Status CheckDetermined(const SensorCalibration& c, int sensor_number);

// The accelerometer's and gyroscope's results (x unscaled, covariances in input units).
Result<SensorCalibration> AssembleAccel(const TagProblemData& d, const ParameterBlocks& x,
                                        const SensorSolution& solution, const Fit& fit,
                                        const TemperatureDecision& temperature,
                                        const std::string& accel_unit, const CalibrationOptions& o,
                                        int sensor);
Result<SensorCalibration> AssembleGyro(const TagProblemData& d, const ParameterBlocks& x,
                                       const SensorSolution& solution, const Fit& fit,
                                       const TemperatureDecision& temperature,
                                       const std::string& gyro_unit, const CalibrationOptions& o,
                                       int sensor);

// M's elements as a function of the sensor's free parameters (FreeNames order); held scales
// are k_fixed.
Eigen::Matrix3d MatrixFromFree(ImuSensor sensor, ModelKind kind, const double* k_fixed,
                               const Eigen::VectorXd& free);

double StudentT975(int dof);

}  // namespace metro::calibration_internal
