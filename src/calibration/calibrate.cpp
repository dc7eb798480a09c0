#include "metro/calibration/calibrate.hpp"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <ctime>
#include <exception>
#include <limits>
#include <map>
#include <optional>

#include "calibration/calibrate_stages.hpp"
#include "calibration/model_selection.hpp"
#include "calibration/parameter_blocks.hpp"
#include "metro/calibration/gyro_bias.hpp"
#include "metro/core/utc_time.hpp"
#include "metro/core/version.hpp"

namespace metro {

namespace ci = calibration_internal;

const char* LossKindName(LossKind kind) {
  switch (kind) {
    case LossKind::kTrivial:
      return "none";
    case LossKind::kHuber:
      return "huber";
    case LossKind::kCauchy:
      return "cauchy";
  }
  return "none";
}

std::optional<LossKind> ParseLossKind(std::string_view name) {
  if (name == "none") return LossKind::kTrivial;
  if (name == "huber") return LossKind::kHuber;
  if (name == "cauchy") return LossKind::kCauchy;
  return std::nullopt;
}

bool CalibrationOptions::IsValid(std::string* why) const {
  auto fail = [why](const std::string& message) {
    if (why != nullptr) *why = message;
    return false;
  };
  if (!(gravity_mps2 > 9.7 && gravity_mps2 < 9.9)) {
    return fail(fmt::format("gravity_mps2 = {} is not a gravity on Earth (9.7 .. 9.9 m/s^2)",
                            gravity_mps2));
  }
  if (gravity_u_mps2 && !(*gravity_u_mps2 >= 0 && *gravity_u_mps2 < 0.5)) {
    return fail(
        fmt::format("gravity_u_mps2 = {} is not a standard uncertainty of gravity "
                    "(0 .. 0.5 m/s^2)",
                    *gravity_u_mps2));
  }
  if (!(accel_fs_g > 0)) return fail("accel_fs_g must be > 0 (2, 4, 8 or 16 for an MPU6050)");
  if (!(gyro_fs_dps > 0)) {
    return fail("gyro_fs_dps must be > 0 (250, 500, 1000 or 2000 for an MPU6050)");
  }
  if (!(min_temp_span_c > 0)) return fail("min_temp_span_c must be > 0");
  if (!(loss_scale > 0)) return fail("loss_scale must be > 0");
  if (sensor < 0) return fail("sensor must be >= 0 (0 = every tag)");
  if (max_iterations < 1) return fail("max_iterations must be >= 1");
  if (!(max_rotation_s > 0)) return fail("max_rotation_s must be > 0");
  if (!fit_accel && (!fit_gyro || gyro_model != ModelKind::kBias || gyro_auto)) {
    return fail(
        "without the accelerometer (accel model none) only the gyroscope's bias at rest is "
        "evaluated: give the gyroscope model bias");
  }
  if (!fit_accel && temperature == TemperatureMode::kOn) {
    return fail(
        "a temperature term needs poses at several temperatures: not with accel model "
        "none (a bias at rest is one pose)");
  }
  std::string seg_why;
  if (!segmentation.IsValid(&seg_why)) return fail("segmentation: " + seg_why);
  return true;
}

Eigen::MatrixXd SensorCalibration::Correlation() const {
  Eigen::MatrixXd r = covariance;
  for (Eigen::Index i = 0; i < r.rows(); ++i) {
    for (Eigen::Index j = 0; j < r.cols(); ++j) {
      const double d = std::sqrt(covariance(i, i) * covariance(j, j));
      r(i, j) = d > 0 ? covariance(i, j) / d : (i == j ? 1.0 : 0.0);
    }
  }
  return r;
}

const TagCalibration* Calibration::FindTag(int sensor) const {
  for (const TagCalibration& t : tags) {
    if (t.sensor == sensor) return &t;
  }
  return nullptr;
}

namespace {

// One model of a sensor's ladder (issue #36), fitted in its own parameter blocks.
struct Trial {
  bool tried = false;
  Status status;
  ci::ParameterBlocks x;
  ci::Fit fit;
  ci::SensorSolution solution;
  Eigen::Vector3d ref = Eigen::Vector3d::Ones();  // accel_ref or gyro_ref of the trial.
  std::vector<std::string> warnings;
  // Gyroscope: the rotations as the trial left them (exclusions) and its segments.
  std::vector<ci::RotationData> rotations;
  std::vector<const Segment*> rotation_segments;
  std::vector<Segment> segments;
};

constexpr ModelKind kLadder[] = {ModelKind::kBias, ModelKind::kScale, ModelKind::kFull};

// The blocks `blocks` (into `from`) as the same blocks of `to`.
std::vector<double*> Rebase(const std::vector<double*>& blocks, const ci::ParameterBlocks& from,
                            ci::ParameterBlocks* to) {
  std::vector<double*> out;
  const double* base = from[ci::ParameterBlocks::kAccelBias];
  for (double* b : blocks) {
    out.push_back((*to)[ci::ParameterBlocks::kAccelBias] + (static_cast<const double*>(b) - base));
  }
  return out;
}

// A trial's model as determined: the covariance in input units passes CheckDetermined.
Status CheckTrialDetermined(ImuSensor imu, ModelKind kind, const ci::TagProblemData& d,
                            const Trial& t, const std::string& unit, int sensor) {
  ci::ParameterBlocks x = t.x;
  Eigen::MatrixXd cov = t.solution.covariance;
  ci::Unscale(t.ref, imu, kind, d.temperature, &x, &cov);
  return ci::CheckDetermined(
      ci::MakeSensorCalibration(imu, kind, d.temperature, d.t_ref_c, unit, x, cov), sensor);
}

Status RunAccelTrial(ModelKind kind, const CalibrationOptions& o, const std::string& unit,
                     const std::string& hint, int sensor, ci::TagProblemData* d, Trial* t) {
  CalibrationOptions ok = o;
  ok.accel_model = kind;
  t->tried = true;
  Result<ci::SensorStart> start = ci::StartAccel(d->statics, d->target_norm, unit, d->temperature,
                                                 ok, sensor, &t->warnings, hint);
  if (!start.ok()) return start.error();
  t->ref = start.value().scale;
  d->accel_ref = t->ref;
  ci::SetScaledStart(ImuSensor::kAccel, start.value(), &t->x);
  Result<ci::SensorSolution> solved = ci::SolveAccel(*d, ok, sensor, &t->x, &t->fit);
  if (!solved.ok()) return solved.error();
  t->solution = std::move(solved).value();
  return CheckTrialDetermined(ImuSensor::kAccel, kind, *d, *t, unit, sensor);
}

// `scaled_start` keeps StartGyro's result for the scale and full models, which is the same for
// both (the isotropic scale search on the rotations, a tenth of the whole fit on imu_tk's
// Xsens record): computed by the first of them, reused by the other.
Status RunGyroTrial(ModelKind kind, const CalibrationOptions& o, const ci::SensorSolution& accel,
                    double gyro_nominal, const std::string& unit, int sensor, ci::TagProblemData* d,
                    std::optional<Result<ci::GyroStart>>* scaled_start, Trial* t) {
  CalibrationOptions og = o;
  og.gyro_model = kind;
  t->tried = true;
  Status motion =
      ci::CheckGyroMotion(d->tables.size(), d->rotations.size(), kind, d->temperature, sensor);
  if (!motion.ok()) return motion;
  std::optional<Result<ci::GyroStart>> own;
  std::optional<Result<ci::GyroStart>>* cache = kind == ModelKind::kBias ? &own : scaled_start;
  if (!cache->has_value()) {
    *cache = ci::StartGyro(d->statics, d->tables, d->rotations, t->x, gyro_nominal, kind, sensor);
  }
  const Result<ci::GyroStart>& start = **cache;
  if (!start.ok()) return start.error();
  ci::ApplyGyroStart(start.value(), d, &t->x, &t->fit);
  t->ref = d->gyro_ref;
  Result<ci::SensorSolution> solved = ci::SolveGyro(*d, og, sensor, accel, &t->x, &t->fit);
  if (!solved.ok()) return solved.error();
  // Rotations that contradict the rest are excluded one at a time (the worst first) and the
  // gyroscope solved again, while the rest still determine the model.
  for (int round = 0; round < 5 && o.loss == LossKind::kTrivial; ++round) {
    const std::optional<size_t> bad = ci::ContradictingRotation(t->fit, d->rotations.size());
    if (!bad) break;
    if (!ci::CheckGyroMotion(d->tables.size(), d->rotations.size() - 1, kind, d->temperature,
                             sensor)
             .ok()) {
      break;
    }
    t->warnings.push_back(ci::ExcludeRotation(*bad, t->fit, d, &t->segments, sensor));
    solved = ci::SolveGyro(*d, og, sensor, accel, &t->x, &t->fit);
    if (!solved.ok()) return solved.error();
  }
  t->solution = std::move(solved).value();
  return CheckTrialDetermined(ImuSensor::kGyro, kind, *d, *t, unit, sensor);
}

ci::LadderFit LadderFitOf(ImuSensor imu, ModelKind kind, const Trial& t, bool temperature) {
  ci::LadderFit f;
  f.kind = kind;
  f.fitted = t.tried && t.status.ok();
  if (t.tried && !t.status.ok()) f.why = t.status.error().message;
  f.parameters = ci::ParameterBlocks::FreeCount(imu, kind, temperature);
  if (f.fitted) {
    f.chi2 = t.solution.chi2;
    f.chi2_dof = t.solution.chi2_dof;
    f.orientations = t.solution.orientations;
  }
  return f;
}

// The ladder's comparisons, the chosen model (auto) and its standing; `given` when not auto.
// Returns the chosen model, or the error of the given one (or, auto, of the smallest) when it
// could not be fitted.
Result<ModelKind> SelectModel(ImuSensor imu, const std::array<Trial, 3>& trials, bool automatic,
                              bool compare, ModelKind given, bool temperature, bool robust,
                              ModelCheck* check) {
  std::vector<ci::LadderFit> fits;
  for (ModelKind k : kLadder) {
    const Trial& t = trials[static_cast<size_t>(k)];
    if (t.tried) fits.push_back(LadderFitOf(imu, k, t, temperature));
  }
  ModelKind chosen = given;
  if (automatic) {
    const bool any = std::any_of(fits.begin(), fits.end(), [](const auto& f) { return f.fitted; });
    if (!any) return trials[static_cast<size_t>(fits.front().kind)].status.error();
  }
  const std::vector<ModelComparison> comparisons =
      compare ? ci::CompareLadder(fits) : std::vector<ModelComparison>{};
  if (automatic) chosen = ci::ChooseModel(fits, comparisons);
  const Trial& t = trials[static_cast<size_t>(chosen)];
  if (!t.status.ok()) return t.status.error();
  *check = ci::CheckChosenModel(imu, LadderFitOf(imu, chosen, t, temperature), automatic,
                                comparisons, robust);
  if (automatic && check->model_rejected) {
    // Auto found no model the data accept: a larger model that could not be fitted says
    // what the record lacks (as --model full did before auto), rather than constants to refuse.
    for (auto k = std::rbegin(kLadder); k != std::rend(kLadder) && *k != chosen; ++k) {
      const Trial& larger = trials[static_cast<size_t>(*k)];
      if (larger.tried && !larger.status.ok()) return larger.status.error();
    }
  }
  return chosen;
}

std::vector<std::string> CrossAxisTerms(ImuSensor imu, bool accel_terms, bool gyro_terms) {
  std::vector<std::string> out;
  const std::vector<std::string> a =
      ci::ParameterBlocks::FreeNames(ImuSensor::kAccel, ModelKind::kFull, false);
  const std::vector<std::string> g =
      ci::ParameterBlocks::FreeNames(ImuSensor::kGyro, ModelKind::kFull, false);
  if (accel_terms) {
    for (size_t i = 6; i < a.size(); ++i) out.push_back("accel." + a[i]);
  }
  if (gyro_terms && imu == ImuSensor::kGyro) {
    for (size_t i = 6; i < g.size(); ++i) out.push_back("gyro." + g[i]);
  }
  return out;
}

// cov += S_active u^2 S_active^T (the columns of S for the active terms; JCGM 100:2008 5.1.2
// with independent rectangular inputs).
void AddCrossAxisTypeB(const Eigen::MatrixXd& sensitivity, const std::vector<int>& columns,
                       double u, Eigen::MatrixXd* cov) {
  if (sensitivity.rows() != cov->rows()) return;
  for (int c : columns) {
    if (c >= sensitivity.cols()) continue;
    const Eigen::VectorXd s = sensitivity.col(c);
    *cov += u * u * s * s.transpose();
  }
}

// ---- CalibrateTagImpl's stages (calibrate_stages.hpp has the library stages they call) ------

// What the stages of one tag's calibration share, in the order they fill it. It stays where
// the driver made it: d.rotation_segments point into out.segments, the solutions' free blocks
// into x.
struct TagRun {
  explicit TagRun(const CalibrationOptions& options) : o(options), oc(options) {}
  const CalibrationOptions& o;
  TagCalibration out;
  ci::RecordSet records;  // Units and has_gyro; the records themselves move into d.
  ci::TagProblemData d;
  ci::TemperatureDecision temperature;
  // Which models are fitted (issue #36): the whole ladder when comparing or choosing.
  bool robust = false, accel_auto = false, gyro_auto = false, compare = false;
  CalibrationOptions oc;  // o with the chosen models.
  ci::ParameterBlocks x;
  ci::Fit fit;
  ci::SensorSolution accel, gyro;
  ModelCheck accel_check, gyro_check;
};

// Records and poses, and the temperature term.
Status ReadPoses(const std::vector<const Tag*>& tags, TagRun* run) {
  const CalibrationOptions& o = run->o;
  TagCalibration& out = run->out;
  ci::TagProblemData& d = run->d;
  // Records and poses.
  Result<ci::RecordSet> read = ci::ReadRecords(tags, o, out.sensor);
  if (!read.ok()) return read.error();
  run->records = std::move(read).value();
  ci::RecordSet& records = run->records;
  ci::SummarizeRecords(records, o, &out);
  d.target_norm = o.gravity_mps2 / kStandardGravityMps2;
  d.has_gyro = records.has_gyro;
  d.records = std::move(records.records);
  ci::PoseMeans poses = ci::MeanPoses(d.records, d.has_gyro);
  d.statics = std::move(poses.statics);
  d.tables = std::move(poses.tables);

  // Temperature term.
  Result<ci::TemperatureDecision> decided =
      ci::DecideTemperature(ci::EveryRecordHasTemperature(d.records), d.statics, o, out.sensor);
  if (!decided.ok()) return decided.error();
  run->temperature = decided.value();
  const ci::TemperatureDecision& temperature = run->temperature;
  d.temperature = temperature.fit;
  d.t_ref_c = temperature.t_ref_c;
  return Status::Ok();
}

// Which models are fitted (issue #36): the whole ladder when comparing or choosing; a
// robust loss fits the models as given.
void ChooseLadder(TagRun* run) {
  const CalibrationOptions& o = run->o;
  const bool robust = o.loss != LossKind::kTrivial;
  run->robust = robust;
  run->accel_auto = o.accel_auto && !robust;
  run->gyro_auto = o.gyro_auto && !robust;
  run->compare = (o.compare_models || o.accel_auto || o.gyro_auto) && !robust;
  if (robust && (o.accel_auto || o.gyro_auto)) {
    run->out.warnings.push_back(fmt::format(
        "sensor {}: --model auto compares the models on their chi-square against the noise, "
        "which a robust loss does not give: the '{}' accelerometer and '{}' gyroscope models "
        "are fitted as given",
        run->out.sensor, ModelKindName(o.accel_model), ModelKindName(o.gyro_model)));
  }
}

// Accelerometer: start and fit of each model, then the chosen one.
Status FitAccel(TagRun* run) {
  const CalibrationOptions& o = run->o;
  TagCalibration& out = run->out;
  const ci::RecordSet& records = run->records;
  ci::TagProblemData& d = run->d;
  CalibrationOptions& oc = run->oc;
  ci::ParameterBlocks& x = run->x;
  ci::Fit& fit = run->fit;
  ci::SensorSolution& accel = run->accel;
  ModelCheck& accel_check = run->accel_check;
  const bool compare = run->compare;
  const bool robust = run->robust;
  const bool accel_auto = run->accel_auto;
  const std::string hint = ci::PoseShortfallHint(d.records);
  std::array<Trial, 3> accel_trials;
  for (ModelKind k : kLadder) {
    if (!compare && k != o.accel_model) continue;
    Trial& t = accel_trials[static_cast<size_t>(k)];
    t.status = RunAccelTrial(k, o, records.accel_unit, hint, out.sensor, &d, &t);
  }
  Result<ModelKind> accel_kind = SelectModel(ImuSensor::kAccel, accel_trials, accel_auto, compare,
                                             o.accel_model, d.temperature, robust, &accel_check);
  if (!accel_kind.ok()) return accel_kind.error();
  oc.accel_model = accel_kind.value();
  Trial& at = accel_trials[static_cast<size_t>(oc.accel_model)];
  // What only the chosen model's report needs (its cross-axis sensitivity), on its own blocks.
  ci::CompleteAccelUncertainty(oc.accel_model, &at.x, &at.solution);
  x = at.x;
  fit = at.fit;
  accel = at.solution;
  accel.free_blocks = Rebase(at.solution.free_blocks, at.x, &x);
  d.accel_ref = at.ref;
  for (const std::string& w : at.warnings) out.warnings.push_back(w);
  for (const std::string& w : accel.warnings) out.warnings.push_back(w);
  return Status::Ok();
}

// Gyroscope: rotations, then start and fit of each model with the accelerometer held.
Status FitGyro(TagRun* run) {
  const CalibrationOptions& o = run->o;
  TagCalibration& out = run->out;
  const ci::RecordSet& records = run->records;
  ci::TagProblemData& d = run->d;
  const ci::TemperatureDecision& temperature = run->temperature;
  CalibrationOptions& oc = run->oc;
  ci::ParameterBlocks& x = run->x;
  ci::Fit& fit = run->fit;
  ci::SensorSolution& accel = run->accel;
  ci::SensorSolution& gyro = run->gyro;
  ModelCheck& gyro_check = run->gyro_check;
  const bool compare = run->compare;
  const bool robust = run->robust;
  const bool gyro_auto = run->gyro_auto;
  ci::RotationSet rotations = ci::BuildRotations(d.records, d.statics, temperature, d.accel_ref,
                                                 o.max_rotation_s, &out.segments);
  const double gyro_nominal =
      NominalScale(ImuSensor::kGyro, records.gyro_unit, o.gyro_fs_dps).value();
  std::array<Trial, 3> gyro_trials;
  std::optional<Result<ci::GyroStart>> scaled_start;
  for (ModelKind k : kLadder) {
    if (!compare && k != o.gyro_model) continue;
    Trial& t = gyro_trials[static_cast<size_t>(k)];
    d.rotations = rotations.data;
    d.rotation_segments = rotations.segments;
    t.x = x;
    t.fit = fit;
    t.segments = out.segments;
    ci::SensorSolution held = accel;
    held.free_blocks = Rebase(accel.free_blocks, x, &t.x);
    t.status = RunGyroTrial(k, oc, held, gyro_nominal, records.gyro_unit, out.sensor, &d,
                            &scaled_start, &t);
    t.rotations = d.rotations;
    t.rotation_segments = d.rotation_segments;
  }
  Result<ModelKind> gyro_kind = SelectModel(ImuSensor::kGyro, gyro_trials, gyro_auto, compare,
                                            o.gyro_model, d.temperature, robust, &gyro_check);
  if (!gyro_kind.ok()) return gyro_kind.error();
  oc.gyro_model = gyro_kind.value();
  Trial& gt = gyro_trials[static_cast<size_t>(oc.gyro_model)];
  {
    // The chosen model's stated covariance and cross-axis sensitivity, on its own blocks (the
    // ladder's fits carry only what the comparison and CheckDetermined need).
    ci::SensorSolution held = accel;
    held.free_blocks = Rebase(accel.free_blocks, x, &gt.x);
    Status done = ci::CompleteGyroUncertainty(oc, out.sensor, held, &gt.x, &gt.solution);
    if (!done.ok()) return done.error();
  }
  x = gt.x;
  fit = gt.fit;
  gyro = gt.solution;
  d.rotations = gt.rotations;
  d.rotation_segments = gt.rotation_segments;
  d.gyro_ref = gt.ref;
  // Element by element: d.rotation_segments point into out.segments.
  for (size_t i = 0; i < out.segments.size() && i < gt.segments.size(); ++i) {
    out.segments[i] = gt.segments[i];
  }
  for (const std::string& w : gt.warnings) out.warnings.push_back(w);
  for (const std::string& w : gyro.warnings) out.warnings.push_back(w);
  return Status::Ok();
}

// The Type B for the cross-axis terms a rejected or exact scale model leaves out (issue #36),
// added to the covariances after the gyroscope took the accelerometer's (noise) covariance;
// the models' standing said.
void AddLeftOutCrossAxisTypeB(TagRun* run) {
  TagCalibration& out = run->out;
  ci::TagProblemData& d = run->d;
  CalibrationOptions& oc = run->oc;
  ci::SensorSolution& accel = run->accel;
  ci::SensorSolution& gyro = run->gyro;
  ModelCheck& accel_check = run->accel_check;
  ModelCheck& gyro_check = run->gyro_check;
  const bool accel_type_b = accel_check.type_b.has_value();
  if (accel_type_b) {
    accel_check.type_b->terms = CrossAxisTerms(ImuSensor::kAccel, true, false);
    AddCrossAxisTypeB(accel.cross_axis_sensitivity, {0, 1, 2}, accel_check.type_b->u,
                      &accel.covariance);
  }
  if (d.has_gyro) {
    const bool gyro_own = gyro_check.type_b.has_value();
    std::vector<int> columns;
    if (accel_type_b) columns = {0, 1, 2};
    if (gyro_own) {
      for (int c = 3; c < 9; ++c) columns.push_back(c);
    }
    if (!columns.empty() && gyro.cross_axis_sensitivity.cols() == 9) {
      if (!gyro_check.type_b) {
        gyro_check.type_b = ci::DatasheetCrossAxis();
        gyro_check.reason += fmt::format(
            "{}u includes the Type B term of the accelerometer's cross-axis terms, which its "
            "'{}' model leaves out, carried through the rotations",
            gyro_check.reason.empty() ? "" : "; ", ModelKindName(oc.accel_model));
      }
      gyro_check.type_b->terms = CrossAxisTerms(ImuSensor::kGyro, accel_type_b, gyro_own);
      AddCrossAxisTypeB(gyro.cross_axis_sensitivity, columns, gyro_check.type_b->u,
                        &gyro.covariance);
    }
  }
  for (const ModelCheck* c : {&accel_check, &gyro_check}) {
    if (!c->reason.empty() && c->status != "accepted") {
      out.warnings.push_back(fmt::format("sensor {}: {}", out.sensor, c->reason));
    }
  }
}

// Back to input units, and the results.
Status AssembleResults(TagRun* run) {
  const CalibrationOptions& o = run->o;
  TagCalibration& out = run->out;
  const ci::RecordSet& records = run->records;
  ci::TagProblemData& d = run->d;
  const ci::TemperatureDecision& temperature = run->temperature;
  CalibrationOptions& oc = run->oc;
  ci::ParameterBlocks& x = run->x;
  ci::Fit& fit = run->fit;
  ci::SensorSolution& accel = run->accel;
  ci::SensorSolution& gyro = run->gyro;
  ModelCheck& accel_check = run->accel_check;
  ModelCheck& gyro_check = run->gyro_check;
  const bool compare = run->compare;
  out.iterations = fit.iterations;
  if (d.has_gyro) {
    ci::Unscale(d.gyro_ref, ImuSensor::kGyro, oc.gyro_model, d.temperature, &x, &gyro.covariance);
  }
  ci::Unscale(d.accel_ref, ImuSensor::kAccel, oc.accel_model, d.temperature, &x, &accel.covariance);
  Result<SensorCalibration> accel_cal =
      ci::AssembleAccel(d, x, accel, fit, temperature, records.accel_unit, oc, out.sensor);
  if (!accel_cal.ok()) return accel_cal.error();
  out.accel = std::move(accel_cal).value();
  if (compare || accel_check.status != "accepted") out.accel->model_check = accel_check;
  if (d.has_gyro) {
    Result<SensorCalibration> gyro_cal =
        ci::AssembleGyro(d, x, gyro, fit, temperature, records.gyro_unit, oc, out.sensor);
    if (!gyro_cal.ok()) return gyro_cal.error();
    out.gyro = std::move(gyro_cal).value();
    if (compare || gyro_check.status != "accepted") out.gyro->model_check = gyro_check;
  }
  if (!fit.converged) {
    out.warnings.push_back(fmt::format(
        "sensor {}: the solver stopped before convergence (no-convergence after {} iterations)",
        out.sensor, o.max_iterations));
  }
  return Status::Ok();
}

// The stages of calibrate_stages.hpp, in order.
Result<TagCalibration> CalibrateTagImpl(const std::vector<const Tag*>& tags,
                                        const CalibrationOptions& o) {
  std::string why;
  if (!o.IsValid(&why)) return MakeError("invalid calibration options: " + why);
  if (tags.empty()) return MakeError("no records to calibrate");
  TagRun run(o);
  run.out.sensor = tags.front()->sensor;
  if (Status s = ReadPoses(tags, &run); !s.ok()) return s.error();
  ChooseLadder(&run);
  if (Status s = FitAccel(&run); !s.ok()) return s.error();
  if (run.d.has_gyro) {
    if (Status s = FitGyro(&run); !s.ok()) return s.error();
  }
  AddLeftOutCrossAxisTypeB(&run);
  if (Status s = AssembleResults(&run); !s.ok()) return s.error();
  return std::move(run.out);
}

}  // namespace

void DeriveUncertainties(SensorCalibration* c) {
  const SensorModel& mo = c->model;
  const Eigen::MatrixXd& cov = c->covariance;
  const int nm = MisalignmentCount(mo.sensor);
  c->bias_u.setZero();
  c->scale_u.setZero();
  c->bias_per_c_u.setZero();
  c->misalignment_u.assign(static_cast<size_t>(nm), 0.0);
  // The free parameters in FreeNames order: b(3), then k(3), m(nm), b1(3) as the model has them.
  Eigen::VectorXd free(cov.rows());
  Eigen::Index i = 0;
  auto take = [&](double value, double* u) {
    METRO_CHECK(i < cov.rows());
    free[i] = value;
    *u = std::sqrt(std::max(0.0, cov(i, i)));
    ++i;
  };
  for (int a = 0; a < 3; ++a) take(mo.bias[a], &c->bias_u[a]);
  if (mo.kind != ModelKind::kBias) {
    for (int a = 0; a < 3; ++a) take(mo.scale[a], &c->scale_u[a]);
  }
  if (mo.kind == ModelKind::kFull) {
    for (int a = 0; a < nm; ++a) {
      take(mo.misalignment[static_cast<size_t>(a)], &c->misalignment_u[static_cast<size_t>(a)]);
    }
  }
  if (mo.has_temperature) {
    for (int a = 0; a < 3; ++a) take(mo.bias_per_c[a], &c->bias_per_c_u[a]);
  }
  METRO_CHECK(i == cov.rows());
  // u(M): law of propagation of uncertainty, JCGM 100:2008 5.1.2, with the sensitivity
  // coefficients by central differences (M is bilinear in k and the misalignment terms).
  const double k[3] = {mo.scale[0], mo.scale[1], mo.scale[2]};
  Eigen::MatrixXd jm(9, cov.rows());
  for (Eigen::Index p = 0; p < cov.rows(); ++p) {
    const double h = 1e-6 * std::max(1e-6, std::abs(free[p]));
    Eigen::VectorXd xp = free, xm = free;
    xp[p] += h;
    xm[p] -= h;
    const Eigen::Matrix3d d = (ci::MatrixFromFree(mo.sensor, mo.kind, k, xp) -
                               ci::MatrixFromFree(mo.sensor, mo.kind, k, xm)) /
                              (2 * h);
    for (int e = 0; e < 9; ++e) jm(e, p) = d(e / 3, e % 3);
  }
  const Eigen::MatrixXd cm = jm * cov * jm.transpose();
  for (int e = 0; e < 9; ++e) c->matrix_u(e / 3, e % 3) = std::sqrt(std::max(0.0, cm(e, e)));
  for (int a = 0; a < 3; ++a) {
    c->sensitivity[a] = 1.0 / k[a];
    c->sensitivity_u[a] = c->scale_u[a] / (k[a] * k[a]);
  }
}

Result<TagCalibration> CalibrateTag(const std::vector<const Tag*>& records,
                                    const CalibrationOptions& options) {
  try {
    return CalibrateTagImpl(records, options);
  } catch (const std::exception& e) {
    return MakeFailedError(std::string("calibration failed: ") + e.what());
  }
}

Status CheckCalibrationColumns(const std::vector<const Session*>& sessions,
                               const CalibrationOptions& options) {
  if (!options.fit_accel) return CheckGyroRestRecords(sessions, options);
  // Sensors with a gyroscope family in some session.
  std::map<int, std::string> gyro_seen;  // sensor -> a session that has it
  for (const Session* s : sessions) {
    for (const Tag& t : s->tags) {
      if (options.sensor != 0 && t.sensor != options.sensor) continue;
      const ci::FamilyMatch accel = ci::FindFamily(t, ImuSensor::kAccel);
      if (accel.unit == nullptr) {
        return MakeError(s->path, 0,
                         accel.family.empty()
                             ? fmt::format("sensor {}: no accelerometer columns: the calibrator "
                                           "needs {} in static poses",
                                           t.sensor, ci::FamilyChoices(ImuSensor::kAccel))
                             : ci::IncompleteFamilyMessage(t.sensor, ImuSensor::kAccel, accel));
      }
      const ci::FamilyMatch gyro = ci::FindFamily(t, ImuSensor::kGyro);
      if (gyro.unit == nullptr && !gyro.family.empty() && options.fit_gyro) {
        return MakeError(
            s->path, 0,
            ci::IncompleteFamilyMessage(t.sensor, ImuSensor::kGyro, gyro) + " (or --accel-only)");
      }
      if (gyro.unit != nullptr && gyro_seen.count(t.sensor) == 0) gyro_seen[t.sensor] = s->path;
    }
  }
  if (!options.fit_gyro) return Status::Ok();
  for (const Session* s : sessions) {
    for (const Tag& t : s->tags) {
      if (options.sensor != 0 && t.sensor != options.sensor) continue;
      if (gyro_seen.count(t.sensor) != 0 && ci::FindFamily(t, ImuSensor::kGyro).unit == nullptr) {
        return MakeError(
            s->path, 0,
            fmt::format("sensor {}: no gyroscope columns while {} has them: records of one tag "
                        "are fitted together; log {} in every record or give --accel-only",
                        t.sensor, gyro_seen[t.sensor], ci::FamilyChoices(ImuSensor::kGyro)));
      }
    }
  }
  return Status::Ok();
}

InputFile RecordTimeSpan(const Session& session) {
  InputFile out;
  out.format = SessionFormatName(session.format);
  double first_s = std::numeric_limits<double>::infinity();
  double last_s = -first_s;
  for (const Tag& t : session.tags) {
    if (t.t_s.empty()) continue;
    first_s = std::min(first_s, t.t_s.front());
    last_s = std::max(last_s, t.t_s.back());
  }
  if (!(first_s <= last_s)) return out;
  out.duration_s = last_s - first_s;
  // Unix time 2000-01-01T00:00:00Z .. 2100-01-01T00:00:00Z: a date, not a clock since start.
  constexpr double kFrom = 946684800.0, kTo = 4102444800.0;
  const double origin_s =
      session.input.time_integer ? static_cast<double>(session.input.time_origin_ns) * 1e-9 : 0.0;
  const double start = origin_s + first_s, end = origin_s + last_s;
  if (start >= kFrom && end < kTo) {
    out.start_utc = UtcIso8601(static_cast<std::time_t>(std::floor(start)));
    out.end_utc = UtcIso8601(static_cast<std::time_t>(std::floor(end)));
  }
  return out;
}

Result<StaticResiduals> ComputeStaticResiduals(const SensorCalibration& c,
                                               const std::vector<const Tag*>& records,
                                               double gravity_mps2) {
  const SensorModel& m = c.model;
  const bool accel = m.sensor == ImuSensor::kAccel;
  if (m.input_unit == "LSB" && !c.full_scale) {
    return MakeError("static residuals: the full-scale setting of the raw (LSB) input is not set");
  }
  const std::optional<double> nominal =
      NominalScale(m.sensor, m.input_unit, c.full_scale.value_or(1.0));
  const std::vector<std::string> columns = InputColumns(m.sensor, m.input_unit);
  if (!nominal || columns.size() != 3) {
    return MakeError(fmt::format("static residuals: input unit {} is not a unit of the {}",
                                 m.input_unit, ImuSensorLongName(m.sensor)));
  }
  const double target = accel ? gravity_mps2 / kStandardGravityMps2 : 0.0;
  StaticResiduals out;
  out.unit = std::string(OutputUnit(m.sensor).symbol);
  for (const Segment& seg : c.segments) {
    if (seg.kind != SegmentKind::kStatic || !seg.used) continue;
    if (seg.piece < 0 || static_cast<size_t>(seg.piece) >= records.size()) continue;
    const Tag& tag = *records[static_cast<size_t>(seg.piece)];
    const Quantity* col[3] = {tag.Find(columns[0]), tag.Find(columns[1]), tag.Find(columns[2])};
    if (col[0] == nullptr || col[1] == nullptr || col[2] == nullptr) continue;
    if (seg.end > tag.size() || seg.begin >= seg.end) continue;
    const Quantity* temp = tag.Find("temp_c");
    Eigen::Vector3d raw = Eigen::Vector3d::Zero();
    double temp_c = 0.0;
    for (size_t i = seg.begin; i < seg.end; ++i) {
      for (int a = 0; a < 3; ++a) raw[a] += col[a]->values[i];
      if (temp != nullptr) temp_c += temp->values[i];
    }
    const double n = static_cast<double>(seg.end - seg.begin);
    raw /= n;
    temp_c /= n;
    out.before.push_back((*nominal * raw).norm() - target);
    out.after.push_back(m.Apply(raw, temp_c).norm() - target);
  }
  return out;
}

namespace {

RecordConditions ConditionsOf(const Tag& tag, int input) {
  RecordConditions r;
  r.input = input;
  r.samples = static_cast<int64_t>(tag.size());
  if (!tag.t_s.empty()) r.duration_s = tag.t_s.back() - tag.t_s.front();
  if (const Quantity* temp = tag.Find("temp_c")) {
    for (double t : temp->values) {
      if (!std::isfinite(t)) continue;
      r.temp_min_c = std::min(r.temp_min_c.value_or(t), t);
      r.temp_max_c = std::max(r.temp_max_c.value_or(t), t);
    }
  }
  return r;
}

}  // namespace

Result<Calibration> CalibrateSessions(const std::vector<const Session*>& sessions,
                                      const CalibrationOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) return MakeError("invalid calibration options: " + why);
  if (sessions.empty()) return MakeError("no sessions to calibrate");
  Calibration cal;
  cal.gravity_mps2 = options.gravity_mps2;
  cal.gravity_source =
      options.gravity_given || options.gravity_mps2 != kStandardGravityMps2 ? "given" : "standard";
  cal.gravity_u_mps2 = options.gravity_u_mps2;
  cal.tool_version = std::string(kToolName) + " " + kVersion;
  cal.date_utc = UtcIso8601Now();
  std::map<int, std::vector<const Tag*>> by_sensor;
  std::map<int, std::vector<RecordConditions>> conditions;
  for (const Session* s : sessions) {
    const int input = static_cast<int>(cal.inputs.size());
    InputFile in = RecordTimeSpan(*s);
    in.path = s->path;
    in.sha256 = s->sha256;
    cal.inputs.push_back(std::move(in));
    for (const Tag& t : s->tags) {
      if (options.sensor == 0 || t.sensor == options.sensor) {
        by_sensor[t.sensor].push_back(&t);
        conditions[t.sensor].push_back(ConditionsOf(t, input));
      }
    }
  }
  if (by_sensor.empty()) {
    return MakeError(options.sensor != 0
                         ? fmt::format("no tag with sensor number {} in the input", options.sensor)
                         : std::string("the input has no tags"));
  }
  for (const auto& [sensor, tags] : by_sensor) {
    Result<TagCalibration> t =
        options.fit_accel ? CalibrateTag(tags, options) : CalibrateGyroBiasAtRest(tags, options);
    if (!t.ok()) {
      Error e = t.error();
      if (e.file.empty() && sessions.size() == 1) e.file = sessions.front()->path;
      return e;
    }
    for (std::optional<SensorCalibration>* c : {&t.value().accel, &t.value().gyro}) {
      if (c->has_value() && (*c)->model.input_unit == "LSB") {
        (*c)->full_scale =
            (*c)->model.sensor == ImuSensor::kAccel ? options.accel_fs_g : options.gyro_fs_dps;
      }
      if (c->has_value()) {
        Result<StaticResiduals> residuals = ComputeStaticResiduals(**c, tags, options.gravity_mps2);
        if (!residuals.ok()) return residuals.error();
        (*c)->static_residuals = std::move(residuals).value();
      }
    }
    t.value().record_conditions = std::move(conditions[sensor]);
    cal.tags.push_back(std::move(t).value());
  }
  return cal;
}

Result<CalibrationOptions> ResolveFitOptions(CalibrationOptions o,
                                             const std::string& segments_path) {
  const bool accel_none = !o.fit_accel;
  if (accel_none && !o.fit_gyro) {
    return MakeError("--accel-model none and --accel-only leave nothing to calibrate");
  }
  if (accel_none && (o.gyro_model != ModelKind::kBias || o.gyro_auto)) {
    return MakeError(
        "--accel-model none evaluates the gyroscope's bias at rest from one static record: give "
        "--gyro-model bias (a scale or misalignment needs poses, rotations and the "
        "accelerometer)");
  }
  if (accel_none && !segments_path.empty()) {
    return MakeError(
        "--segments does not apply to --accel-model none (the whole record is "
        "the static pose)");
  }
  if (!segments_path.empty()) {
    Result<std::vector<AnnotatedSegment>> given = ReadSegmentsFile(segments_path);
    if (!given.ok()) return given.error();
    o.annotated_segments = std::move(given).value();
    o.segments_path = segments_path;
  }
  std::string why;
  if (!o.IsValid(&why)) return MakeError(why);
  return o;
}

}  // namespace metro
