#include "metro/calibration/calibrate.hpp"

#include <ceres/ceres.h>
#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <boost/math/distributions/students_t.hpp>
#include <chrono>
#include <cmath>
#include <ctime>
#include <exception>
#include <map>
#include <memory>
#include <numeric>

#include "calibration/residuals.hpp"
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
  if (!(accel_fs_g > 0)) return fail("accel_fs_g must be > 0 (2, 4, 8 or 16 for an MPU6050)");
  if (!(gyro_fs_dps > 0)) {
    return fail("gyro_fs_dps must be > 0 (250, 500, 1000 or 2000 for an MPU6050)");
  }
  if (!(min_temp_span_c > 0)) return fail("min_temp_span_c must be > 0");
  if (!(loss_scale > 0)) return fail("loss_scale must be > 0");
  if (sensor < 0) return fail("sensor must be >= 0 (0 = every tag)");
  if (max_iterations < 1) return fail("max_iterations must be >= 1");
  if (!(max_rotation_s > 0)) return fail("max_rotation_s must be > 0");
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

constexpr double kPi = 3.14159265358979323846;

const Quantity* FindQuantity(const Tag& tag, std::string_view name) {
  for (const Quantity& q : tag.quantities) {
    if (q.name == name) return &q;
  }
  return nullptr;
}

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

std::string JoinNames(const std::vector<std::string>& names, const char* separator) {
  std::string out;
  for (const std::string& n : names) out += (out.empty() ? "" : separator) + n;
  return out;
}

// Which axis family of the sensor a tag holds (columns.hpp): the first complete one in
// AxisUnits order (raw counts preferred), or, when none is complete, the first the tag holds
// part of (`unit` is nullptr then) or none at all (`family` empty).
struct FamilyMatch {
  const Unit* unit = nullptr;        // The complete family's unit; nullptr if none.
  std::vector<std::string> family;   // Its columns (or the partial family's).
  std::vector<std::string> missing;  // Of a partial family, the absent columns.
};

FamilyMatch FindFamily(const Tag& tag, ImuSensor sensor) {
  std::vector<std::string> present;
  for (const Quantity& q : tag.quantities) present.push_back(q.name);
  FamilyMatch partial;
  for (const Unit* unit : AxisUnits(ColumnSensorKind(sensor))) {
    std::vector<std::string> family = FamilyColumns(ColumnSensorKind(sensor), unit);
    std::vector<std::string> missing = MissingColumns(family, present);
    if (missing.empty()) return {unit, std::move(family), {}};
    if (missing.size() < family.size() && partial.family.empty()) {
      partial.family = std::move(family);
      partial.missing = std::move(missing);
    }
  }
  return partial;
}

// "sensor 1: the gyroscope calibration needs gx_dps, gy_dps, gz_dps; missing gx_dps, gy_dps"
std::string IncompleteFamilyMessage(int sensor, ImuSensor imu, const FamilyMatch& match) {
  return fmt::format("sensor {}: the {} calibration needs {}; missing {}", sensor,
                     ImuSensorLongName(imu), JoinNames(match.family, ", "),
                     JoinNames(match.missing, ", "));
}

// The families the calibrator accepts: "ax_lsb ay_lsb az_lsb (or ax_g ay_g az_g, or ax_mps2
// ay_mps2 az_mps2)".
std::string FamilyChoices(ImuSensor imu) {
  std::string out;
  const std::vector<const Unit*> units = AxisUnits(ColumnSensorKind(imu));
  for (size_t i = 0; i < units.size(); ++i) {
    out += i == 0 ? "" : (i == 1 ? " (or " : ", or ");
    out += JoinNames(FamilyColumns(ColumnSensorKind(imu), units[i]), " ");
  }
  return units.size() > 1 ? out + ")" : out;
}

// Reads the family FindFamily picks. Returns false when the tag holds none of its columns;
// an error names the missing columns of a partial family.
Result<bool> ReadAxes(const Tag& tag, ImuSensor imu, std::vector<Eigen::Vector3d>* out,
                      std::string* unit) {
  const FamilyMatch match = FindFamily(tag, imu);
  if (match.unit == nullptr) {
    if (match.family.empty()) return false;
    return MakeError(IncompleteFamilyMessage(tag.sensor, imu, match));
  }
  const Quantity* q[3];
  for (int a = 0; a < 3; ++a) q[a] = FindQuantity(tag, match.family[static_cast<size_t>(a)]);
  out->resize(tag.size());
  for (size_t i = 0; i < tag.size(); ++i) {
    for (int a = 0; a < 3; ++a) {
      const double v = q[a]->values[i];
      if (!std::isfinite(v)) {
        return MakeError(
            "", tag.line.size() > i ? tag.line[i] : 0,
            fmt::format("sensor {}: {} is not a finite number", tag.sensor, q[a]->name));
      }
      (*out)[i][a] = v;
    }
  }
  *unit = std::string(match.unit->symbol);
  return true;
}

bool IsRawCount(const std::string& unit_symbol) {
  const Unit* unit = UnitBySymbol(unit_symbol);
  return unit != nullptr && unit->dimension == Dimension::kRawCount;
}

// Saturation of raw counts: int16 limits, or uint16 limits for unsigned data (imu_tk's Xsens).
int FlagSaturation(const std::vector<Eigen::Vector3d>& x, std::vector<unsigned char>* flags) {
  flags->assign(x.size(), 0);
  double lo = 0, hi = 0;
  for (const Eigen::Vector3d& v : x) {
    lo = std::min(lo, v.minCoeff());
    hi = std::max(hi, v.maxCoeff());
  }
  const bool unsigned_counts = lo >= 0 && hi > 32767;
  const double min_count = unsigned_counts ? 0.0 : -32768.0;
  const double max_count = unsigned_counts ? 65535.0 : 32767.0;
  int count = 0;
  for (size_t i = 0; i < x.size(); ++i) {
    if (x[i].minCoeff() <= min_count || x[i].maxCoeff() >= max_count) {
      (*flags)[i] = 1;
      ++count;
    }
  }
  return count;
}

Result<Record> ReadRecord(const Tag& tag, int piece, const CalibrationOptions& options) {
  Record r;
  r.piece = piece;
  r.t_s = tag.t_s;
  Result<bool> has_accel = ReadAxes(tag, ImuSensor::kAccel, &r.accel, &r.accel_unit);
  if (!has_accel.ok()) return has_accel.error();
  if (!has_accel.value()) {
    return MakeError(
        fmt::format("sensor {}: no accelerometer columns: the calibrator needs {} in static "
                    "poses: log it together with the gyroscope",
                    tag.sensor, FamilyChoices(ImuSensor::kAccel)));
  }
  if (options.fit_gyro) {
    Result<bool> has_gyro = ReadAxes(tag, ImuSensor::kGyro, &r.gyro, &r.gyro_unit);
    if (!has_gyro.ok()) return has_gyro.error();
  }
  if (const Quantity* q = FindQuantity(tag, "temp_c")) r.temp_c = q->values;
  if (const Quantity* q = FindQuantity(tag, "table_rate_dps")) {
    r.table_rate_dps = q->values;
    r.has_table_column = true;
  }
  r.accel_sat.assign(r.accel.size(), 0);
  r.gyro_sat.assign(r.accel.size(), 0);
  if (IsRawCount(r.accel_unit)) r.accel_sat_count = FlagSaturation(r.accel, &r.accel_sat);
  if (IsRawCount(r.gyro_unit)) r.gyro_sat_count = FlagSaturation(r.gyro, &r.gyro_sat);
  r.saturated.resize(r.accel.size());
  for (size_t i = 0; i < r.accel.size(); ++i) r.saturated[i] = r.accel_sat[i] | r.gyro_sat[i];

  SegmentationInput in;
  in.t_s = &r.t_s;
  in.accel = &r.accel;
  in.gyro = r.gyro.empty() ? nullptr : &r.gyro;
  in.table_rate_dps = r.table_rate_dps.empty() ? nullptr : &r.table_rate_dps;
  in.saturated = &r.saturated;
  in.piece = piece;
  r.seg = DetectSegments(in, options.segmentation);
  return r;
}

// Means over a segment.
struct Pose {
  const Segment* segment = nullptr;
  int record = 0;
  Eigen::Vector3d accel = Eigen::Vector3d::Zero();
  Eigen::Vector3d gyro = Eigen::Vector3d::Zero();
  Eigen::Vector3d gyro_sd = Eigen::Vector3d::Zero();  // Per-sample standard deviation.
  double temp_c = 0;
  size_t n = 0;
};

Pose MeanOver(const Record& r, int record_index, const Segment& s) {
  Pose p;
  p.segment = &s;
  p.record = record_index;
  Eigen::Vector3d g2 = Eigen::Vector3d::Zero();
  for (size_t i = s.begin; i < s.end; ++i) {
    if (r.saturated[i]) continue;
    p.accel += r.accel[i];
    if (!r.gyro.empty()) {
      p.gyro += r.gyro[i];
      g2 += r.gyro[i].cwiseProduct(r.gyro[i]);
    }
    if (!r.temp_c.empty()) p.temp_c += r.temp_c[i];
    ++p.n;
  }
  const double n = static_cast<double>(std::max<size_t>(p.n, 1));
  p.accel /= n;
  p.gyro /= n;
  p.temp_c /= n;
  if (p.n > 1) {
    p.gyro_sd = ((g2 / n - p.gyro.cwiseProduct(p.gyro)) * n / (n - 1)).cwiseMax(0.0).cwiseSqrt();
  }
  return p;
}

// Closed-form start: axis-aligned ellipsoid A x^2 + B y^2 + C z^2 + D x + E y + F z = 1 through
// the pose means (linear least squares on centred, scaled data). Returns false when the fit is
// not an ellipsoid.
bool EllipsoidStart(const std::vector<Eigen::Vector3d>& points, double target_norm,
                    Eigen::Vector3d* bias, Eigen::Vector3d* scale) {
  const size_t n = points.size();
  if (n < 6) return false;
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (const auto& p : points) c += p;
  c /= static_cast<double>(n);
  double s2 = 0;
  for (const auto& p : points) s2 += (p - c).squaredNorm();
  const double s = std::sqrt(s2 / static_cast<double>(n));
  if (!(s > 0)) return false;
  Eigen::MatrixXd a(n, 6);
  Eigen::VectorXd ones = Eigen::VectorXd::Ones(static_cast<Eigen::Index>(n));
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d x = (points[i] - c) / s;
    a.row(static_cast<Eigen::Index>(i)) << x[0] * x[0], x[1] * x[1], x[2] * x[2], x[0], x[1], x[2];
  }
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(a, Eigen::ComputeThinU | Eigen::ComputeThinV);
  const auto& sv = svd.singularValues();
  if (sv(5) < 1e-9 * sv(0)) return false;
  const Eigen::VectorXd th = svd.solve(ones);
  if (!(th[0] > 0 && th[1] > 0 && th[2] > 0)) return false;
  Eigen::Vector3d centre;
  double g = 1.0;
  for (int i = 0; i < 3; ++i) {
    centre[i] = -th[3 + i] / (2 * th[i]);
    g += th[3 + i] * th[3 + i] / (4 * th[i]);
  }
  if (!(g > 0)) return false;
  for (int i = 0; i < 3; ++i) {
    const double radius = std::sqrt(g / th[i]) * s;  // In input units.
    (*scale)[i] = target_norm / radius;
  }
  *bias = c + s * centre;
  return bias->allFinite() && scale->allFinite();
}

// All parameter blocks of the problem (imu_model.hpp layout).
struct Params {
  double ab[3] = {0, 0, 0}, ak[3] = {1, 1, 1}, am[3] = {0, 0, 0}, ab1[3] = {0, 0, 0};
  double gb[3] = {0, 0, 0}, gk[3] = {1, 1, 1}, gm[6] = {0, 0, 0, 0, 0, 0}, gb1[3] = {0, 0, 0};
  std::vector<double*> AccelBlocks() { return {ab, ak, am, ab1}; }
  std::vector<double*> GyroBlocks() { return {gb, gk, gm, gb1}; }
  std::vector<double*> All() { return {ab, ak, am, ab1, gb, gk, gm, gb1}; }
};

const char* const kAccelNames[] = {"b_x",  "b_y",  "b_z",  "k_x",  "k_y",  "k_z",
                                   "a_yz", "a_zy", "a_zx", "b1_x", "b1_y", "b1_z"};
const char* const kGyroNames[] = {"b_x",  "b_y",  "b_z",  "k_x",  "k_y",  "k_z",  "g_yz", "g_zy",
                                  "g_xz", "g_zx", "g_xy", "g_yx", "b1_x", "b1_y", "b1_z"};

// Which blocks of a sensor are free for a model.
std::vector<bool> FreeBlocks(ModelKind kind, bool temperature) {
  return {true, kind != ModelKind::kBias, kind == ModelKind::kFull, temperature};
}
int FreeCount(ImuSensor sensor, ModelKind kind, bool temperature) {
  int n = 3;
  if (kind != ModelKind::kBias) n += 3;
  if (kind == ModelKind::kFull) n += MisalignmentCount(sensor);
  if (temperature) n += 3;
  return n;
}

ceres::LossFunction* MakeLoss(const CalibrationOptions& o) {
  switch (o.loss) {
    case LossKind::kHuber:
      return new ceres::HuberLoss(o.loss_scale);
    case LossKind::kCauchy:
      return new ceres::CauchyLoss(o.loss_scale);
    case LossKind::kTrivial:
      return nullptr;
  }
  return nullptr;
}

// Group standard deviation: RMS with a degrees-of-freedom share, or 1.4826 MAD when robust.
double GroupSigma(const std::vector<double>& r, double dof_ratio, bool robust) {
  if (r.empty()) return 1.0;
  double s;
  if (robust) {
    std::vector<double> a(r.size());
    std::transform(r.begin(), r.end(), a.begin(), [](double x) { return std::abs(x); });
    std::nth_element(a.begin(), a.begin() + static_cast<std::ptrdiff_t>(a.size() / 2), a.end());
    s = 1.4826 * a[a.size() / 2];
  } else {
    double ss = 0;
    for (double x : r) ss += x * x;
    s = std::sqrt(ss / (static_cast<double>(r.size()) * std::max(dof_ratio, 1e-3)));
  }
  return s > 0 && std::isfinite(s) ? s : 1e-12;
}

double Rms(const std::vector<double>& r) {
  if (r.empty()) return 0;
  double ss = 0;
  for (double x : r) ss += x * x;
  return std::sqrt(ss / static_cast<double>(r.size()));
}

// Everything one tag's fit needs, built once.
struct TagProblemData {
  std::vector<Record> records;
  std::vector<Pose> statics;                // Static poses, all records.
  std::vector<Pose> tables;                 // Table runs.
  std::vector<ci::RotationData> rotations;  // Hand rotations (weight 1).
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

struct Fit {
  double s_accel = 1, s_static = 1, s_table = 1, s_rotation = 1;
  std::vector<double> r_accel, r_static, r_table, r_rotation;  // Unwhitened residuals.
  int iterations = 0;
  bool converged = false;
  std::string message;
};

// kAccel/kGyro: unweighted start fits; kAccelFinal/kGyroFinal: whitened by the group standard
// deviations of the start fits, with the robust loss when one is chosen. The accelerometer is
// held in the gyroscope stages (the gravity norm alone determines it, as in imu_tk); its
// uncertainty reaches the gyroscope through PropagateAccel.
enum class Stage { kAccel, kAccelFinal, kGyro, kGyroFinal };

// Builds and solves one stage; residuals of every group are evaluated at the solution.
Status SolveStage(Stage stage, const TagProblemData& d, const CalibrationOptions& o, Params* x,
                  Fit* fit, ceres::Problem* keep_problem, std::vector<double*>* free_blocks,
                  int* residual_count) {
  ceres::Problem local;
  ceres::Problem& problem = keep_problem != nullptr ? *keep_problem : local;
  const bool accel_free = stage == Stage::kAccel || stage == Stage::kAccelFinal;
  const bool gyro_used = !accel_free && d.has_gyro;
  const bool whiten = stage == Stage::kAccelFinal || stage == Stage::kGyroFinal;
  int m = 0;
  if (accel_free) {
    for (const Pose& p : d.statics) {
      const double w = whiten ? 1.0 / fit->s_accel : 1.0;
      problem.AddResidualBlock(ci::NewAccelNormCost(d.accel_ref.cwiseProduct(p.accel),
                                                    p.temp_c - d.t_ref_c, d.target_norm, w),
                               whiten ? MakeLoss(o) : nullptr, x->ab, x->ak, x->am, x->ab1);
      m += 1;
    }
  }
  if (gyro_used) {
    for (const Pose& p : d.statics) {
      const double w = 1.0 / fit->s_static;
      problem.AddResidualBlock(
          ci::NewGyroStaticCost(d.gyro_ref.cwiseProduct(p.gyro), p.temp_c - d.t_ref_c, w),
          whiten ? MakeLoss(o) : nullptr, x->gb, x->gb1);
      m += 3;
    }
    for (const Pose& p : d.tables) {
      const double w = 1.0 / fit->s_table;
      problem.AddResidualBlock(
          ci::NewGyroTableCost(d.gyro_ref.cwiseProduct(p.gyro), p.temp_c - d.t_ref_c,
                               std::abs(p.segment->table_rate_dps), w),
          whiten ? MakeLoss(o) : nullptr, x->gb, x->gk, x->gm, x->gb1);
      m += 1;
    }
    for (const ci::RotationData& rd : d.rotations) {
      ci::RotationData w = rd;
      w.weight = 1.0 / fit->s_rotation;
      problem.AddResidualBlock(ci::NewRotationCost(std::move(w)), whiten ? MakeLoss(o) : nullptr,
                               {x->ab, x->ak, x->am, x->ab1, x->gb, x->gk, x->gm, x->gb1});
      // R^T u_i - u_j is a difference of unit vectors: it lies in the plane normal to
      // R^T u_i + u_j, so each rotation carries 2 degrees of freedom, not 3.
      m += 2;
    }
  }
  // Free and constant blocks.
  free_blocks->clear();
  const bool temp = d.temperature;
  auto set = [&](std::vector<double*> blocks, std::vector<bool> free, bool active) {
    for (size_t i = 0; i < blocks.size(); ++i) {
      if (!problem.HasParameterBlock(blocks[i])) continue;
      if (active && free[i]) {
        free_blocks->push_back(blocks[i]);
      } else {
        problem.SetParameterBlockConstant(blocks[i]);
      }
    }
  };
  set(x->AccelBlocks(), FreeBlocks(o.accel_model, temp), accel_free);
  set(x->GyroBlocks(), FreeBlocks(o.gyro_model, temp), gyro_used);
  *residual_count = m;

  ceres::Solver::Options so;
  so.linear_solver_type = ceres::DENSE_QR;
  so.max_num_iterations = o.max_iterations;
  so.function_tolerance = 1e-12;
  so.gradient_tolerance = 1e-14;
  so.parameter_tolerance = 1e-12;
  so.num_threads = 1;
  so.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(so, &problem, &summary);
  fit->iterations += static_cast<int>(summary.iterations.size());
  fit->converged = summary.termination_type == ceres::CONVERGENCE;
  if (!summary.IsSolutionUsable()) {
    return MakeError(fmt::format("the {} fit failed: {}",
                                 accel_free ? "accelerometer" : "gyroscope", summary.message));
  }
  // Unwhitened residuals of every group at the solution.
  fit->r_accel.clear();
  fit->r_static.clear();
  fit->r_table.clear();
  fit->r_rotation.clear();
  const double* ap[4] = {x->ab, x->ak, x->am, x->ab1};
  for (const Pose& p : d.statics) {
    std::unique_ptr<ceres::CostFunction> c(ci::NewAccelNormCost(
        d.accel_ref.cwiseProduct(p.accel), p.temp_c - d.t_ref_c, d.target_norm, 1.0));
    double r;
    c->Evaluate(ap, &r, nullptr);
    fit->r_accel.push_back(r);
  }
  if (gyro_used) {
    const double* sp[2] = {x->gb, x->gb1};
    for (const Pose& p : d.statics) {
      std::unique_ptr<ceres::CostFunction> c(
          ci::NewGyroStaticCost(d.gyro_ref.cwiseProduct(p.gyro), p.temp_c - d.t_ref_c, 1.0));
      double r[3];
      c->Evaluate(sp, r, nullptr);
      fit->r_static.insert(fit->r_static.end(), r, r + 3);
    }
    const double* tp[4] = {x->gb, x->gk, x->gm, x->gb1};
    for (const Pose& p : d.tables) {
      std::unique_ptr<ceres::CostFunction> c(
          ci::NewGyroTableCost(d.gyro_ref.cwiseProduct(p.gyro), p.temp_c - d.t_ref_c,
                               std::abs(p.segment->table_rate_dps), 1.0));
      double r;
      c->Evaluate(tp, &r, nullptr);
      fit->r_table.push_back(r);
    }
    const double* all[8] = {x->ab, x->ak, x->am, x->ab1, x->gb, x->gk, x->gm, x->gb1};
    for (const ci::RotationData& rd : d.rotations) {
      const Eigen::Vector3d r = ci::RotationResidual(rd, all);
      fit->r_rotation.insert(fit->r_rotation.end(), r.data(), r.data() + 3);
    }
  }
  return Status::Ok();
}

// The (whitened, robustified) Jacobian over `blocks`, dense.
std::optional<Eigen::MatrixXd> DenseJacobian(ceres::Problem* problem,
                                             const std::vector<double*>& blocks) {
  ceres::Problem::EvaluateOptions eo;
  eo.parameter_blocks = blocks;
  ceres::CRSMatrix crs;
  double cost = 0;
  if (!problem->Evaluate(eo, &cost, nullptr, nullptr, &crs)) return std::nullopt;
  Eigen::MatrixXd j = Eigen::MatrixXd::Zero(crs.num_rows, crs.num_cols);
  for (int r = 0; r < crs.num_rows; ++r) {
    for (int k = crs.rows[static_cast<size_t>(r)]; k < crs.rows[static_cast<size_t>(r) + 1]; ++k) {
      j(r, crs.cols[static_cast<size_t>(k)]) = crs.values[static_cast<size_t>(k)];
    }
  }
  return j;
}

// Rank of the whitened Jacobian over the free blocks; names the null direction on failure.
Status CheckRank(ceres::Problem* problem, const std::vector<double*>& free_blocks,
                 const std::vector<std::string>& names) {
  std::optional<Eigen::MatrixXd> jac = DenseJacobian(problem, free_blocks);
  if (!jac) return MakeError("could not evaluate the Jacobian at the solution");
  Eigen::MatrixXd& j = *jac;
  for (Eigen::Index c = 0; c < j.cols(); ++c) {
    const double n = j.col(c).norm();
    if (n > 0) j.col(c) /= n;
  }
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(j, Eigen::ComputeThinV);
  const Eigen::VectorXd& sv = svd.singularValues();
  const Eigen::Index last = sv.size() - 1;
  if (sv.size() > 0 && sv(last) > 1e-8 * sv(0)) return Status::Ok();
  // The free parameters that make up the null direction.
  const Eigen::VectorXd v = svd.matrixV().col(last);
  std::vector<std::string> involved;
  for (Eigen::Index i = 0; i < v.size(); ++i) {
    if (std::abs(v(i)) > 0.3 && static_cast<size_t>(i) < names.size()) {
      involved.push_back(names[static_cast<size_t>(i)]);
    }
  }
  std::string list;
  for (const std::string& s : involved) list += (list.empty() ? "" : ", ") + s;
  return MakeError(fmt::format(
      "degenerate calibration: the Jacobian is rank deficient (smallest/largest singular value "
      "{:.2e}); the data do not determine {}. Collect poses and rotations that exercise these "
      "parameters (every axis up and down, rotations about every axis)",
      sv.size() > 0 && sv(0) > 0 ? sv(last) / sv(0) : 0.0, list));
}

// Covariance of the free parameters from Ceres's Covariance API, scaled by the residual
// variance s^2 = 2 cost / (m - p) (Type A, JCGM 100:2008 4.2.3 and G.4; the groups are
// whitened, so s^2 is the reduced chi-square).
Result<Eigen::MatrixXd> ScaledCovariance(ceres::Problem* problem,
                                         const std::vector<double*>& free_blocks, int p, int m,
                                         double* reduced_chi2) {
  double cost = 0;
  problem->Evaluate(ceres::Problem::EvaluateOptions(), &cost, nullptr, nullptr, nullptr);
  const int dof = m - p;
  const double s2 = dof > 0 ? 2.0 * cost / static_cast<double>(dof) : 0.0;
  *reduced_chi2 = s2;
  ceres::Covariance::Options co;
  co.algorithm_type = ceres::DENSE_SVD;
  co.null_space_rank = 0;
  co.num_threads = 1;
  ceres::Covariance covariance(co);
  std::vector<const double*> cblocks(free_blocks.begin(), free_blocks.end());
  if (!covariance.Compute(cblocks, problem)) {
    return MakeError(
        "degenerate calibration: Ceres could not compute the parameter covariance (the "
        "Jacobian is rank deficient); the data do not determine every constant: collect more "
        "varied poses and rotations");
  }
  int block_total = 0;
  for (const double* b : cblocks) block_total += problem->ParameterBlockSize(b);
  METRO_CHECK(block_total == p);
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> cov(p, p);
  covariance.GetCovarianceMatrix(cblocks, cov.data());
  return Eigen::MatrixXd(cov * s2);
}

std::vector<std::string> FreeNames(ImuSensor sensor, ModelKind kind, bool temperature) {
  const char* const* names = sensor == ImuSensor::kAccel ? kAccelNames : kGyroNames;
  const int nm = MisalignmentCount(sensor);
  std::vector<std::string> out;
  for (int i = 0; i < 3; ++i) out.push_back(names[i]);
  if (kind != ModelKind::kBias) {
    for (int i = 3; i < 6; ++i) out.push_back(names[i]);
  }
  if (kind == ModelKind::kFull) {
    for (int i = 6; i < 6 + nm; ++i) out.push_back(names[i]);
  }
  if (temperature) {
    for (int i = 6 + nm; i < 9 + nm; ++i) out.push_back(names[i]);
  }
  return out;
}

// M's elements as a function of the sensor's free parameters (for propagation).
Eigen::Matrix3d MatrixFromFree(ImuSensor sensor, ModelKind kind, const double* k_fixed,
                               const Eigen::VectorXd& free) {
  double k[3] = {k_fixed[0], k_fixed[1], k_fixed[2]};
  double m[6] = {0, 0, 0, 0, 0, 0};
  const int nm = MisalignmentCount(sensor);
  if (kind != ModelKind::kBias) {
    for (int i = 0; i < 3; ++i) k[i] = free[3 + i];
  }
  if (kind == ModelKind::kFull) {
    for (int i = 0; i < nm; ++i) m[i] = free[6 + i];
  }
  return MisalignmentMatrix(sensor, m) * Eigen::Vector3d(k[0], k[1], k[2]).asDiagonal();
}

SensorCalibration MakeSensorCalibration(ImuSensor sensor, ModelKind kind, bool temperature,
                                        double t_ref_c, const std::string& input_unit,
                                        const double* b, const double* k, const double* m,
                                        const double* b1, const Eigen::MatrixXd& cov) {
  SensorCalibration c;
  SensorModel& mo = c.model;
  mo.sensor = sensor;
  mo.kind = kind;
  mo.input_unit = input_unit;
  mo.output_unit = std::string(OutputUnit(sensor).symbol);
  const int nm = MisalignmentCount(sensor);
  mo.bias = Eigen::Vector3d(b[0], b[1], b[2]);
  mo.scale = Eigen::Vector3d(k[0], k[1], k[2]);
  mo.misalignment.assign(m, m + nm);
  mo.has_temperature = temperature;
  if (temperature) {
    mo.bias_per_c = Eigen::Vector3d(b1[0], b1[1], b1[2]);
    mo.t_ref_c = t_ref_c;
  }
  c.parameter_names = FreeNames(sensor, kind, temperature);
  c.covariance = cov;
  DeriveUncertainties(&c);
  return c;
}

std::string AxisWord(int axis, bool positive) {
  return fmt::format("{}{}", positive ? '+' : '-', "XYZ"[axis]);
}

// A fit can be full rank and still not determine a constant: with noisy data a near
// degeneracy shows as an uncertainty as large as the datasheet tolerance itself (accel:
// 20 mg, 2 % scale, 0.02 rad; gyro: 1 deg/s, 2 %, 0.02 rad). Such a result is refused.
Status CheckDetermined(const SensorCalibration& c, int sensor_number) {
  const SensorModel& m = c.model;
  const bool accel = m.sensor == ImuSensor::kAccel;
  const double bias_limit = accel ? 0.02 : 1.0;  // Output units.
  std::vector<std::string> bad;
  const char* axes = "xyz";
  for (int a = 0; a < 3; ++a) {
    if (c.bias_u[a] * std::abs(m.scale[a]) > bias_limit) {
      bad.push_back(fmt::format("{}.b_{} (u = {:.3g} {})", ImuSensorName(m.sensor), axes[a],
                                c.bias_u[a] * std::abs(m.scale[a]), m.output_unit));
    }
    if (c.scale_u[a] > 0.02 * std::abs(m.scale[a])) {
      bad.push_back(fmt::format("{}.k_{} (u = {:.3g} %)", ImuSensorName(m.sensor), axes[a],
                                100.0 * c.scale_u[a] / std::abs(m.scale[a])));
    }
  }
  for (size_t i = 0; i < c.misalignment_u.size(); ++i) {
    if (c.misalignment_u[i] > 0.02) {
      bad.push_back(fmt::format("{}.{} (u = {:.3g} rad)", ImuSensorName(m.sensor),
                                c.parameter_names.size() > 6 + i ? c.parameter_names[6 + i] : "",
                                c.misalignment_u[i]));
    }
  }
  if (bad.empty()) return Status::Ok();
  std::string list;
  for (const std::string& b : bad) list += (list.empty() ? "" : ", ") + b;
  return MakeError(fmt::format(
      "sensor {}: degenerate calibration: the data do not determine {}; the uncertainty is as "
      "large as the datasheet tolerance. Collect more distinct poses (every axis up and down, "
      "the corners and edges of a cube) and rotations about every axis, or use a simpler --model",
      sensor_number, list));
}

double StudentT975(int dof) {
  if (dof < 1) return 0;
  boost::math::students_t dist(static_cast<double>(dof));
  return boost::math::quantile(dist, 0.975);
}

Result<TagCalibration> CalibrateTagImpl(const std::vector<const Tag*>& tags,
                                        const CalibrationOptions& o) {
  std::string why;
  if (!o.IsValid(&why)) return MakeError("invalid calibration options: " + why);
  if (tags.empty()) return MakeError("no records to calibrate");
  TagCalibration out;
  out.sensor = tags.front()->sensor;
  TagProblemData d;
  d.target_norm = o.gravity_mps2 / kStandardGravityMps2;
  for (size_t i = 0; i < tags.size(); ++i) {
    if (tags[i]->size() < 10) {
      return MakeError(
          fmt::format("sensor {}: input {} has {} samples; a calibration record needs "
                      "static poses of at least {} s each",
                      out.sensor, i + 1, tags[i]->size(), o.segmentation.min_static_s));
    }
    Result<Record> r = ReadRecord(*tags[i], static_cast<int>(i), o);
    if (!r.ok()) return r.error();
    d.records.push_back(std::move(r).value());
  }
  const std::string accel_unit = d.records.front().accel_unit;
  const std::string gyro_unit = d.records.front().gyro_unit;
  for (const Record& r : d.records) {
    if (r.accel_unit != accel_unit || r.gyro_unit != gyro_unit) {
      return MakeError(fmt::format(
          "sensor {}: the inputs disagree on units (accelerometer {} vs {}, gyroscope '{}' vs "
          "'{}'); calibrate records of one kind together",
          out.sensor, accel_unit, r.accel_unit, gyro_unit, r.gyro_unit));
    }
  }
  d.has_gyro = o.fit_gyro && !gyro_unit.empty();
  if (o.fit_gyro && gyro_unit.empty()) {
    out.warnings.push_back(fmt::format(
        "sensor {}: no gyroscope columns, accelerometer only: the gyroscope calibration needs {}",
        out.sensor, FamilyChoices(ImuSensor::kGyro)));
  }
  // Segments, saturation, table column.
  for (Record& r : d.records) {
    out.saturated_samples += static_cast<int>(
        std::count(r.saturated.begin(), r.saturated.end(), static_cast<unsigned char>(1)));
    if (r.accel_sat_count > 0) {
      out.warnings.push_back(fmt::format(
          "sensor {}: {} accelerometer samples at the count limits (saturated) were excluded; "
          "if they fall in static poses, use a larger --accel-fs-g range",
          out.sensor, r.accel_sat_count));
    }
    if (r.gyro_sat_count > 0) {
      out.warnings.push_back(fmt::format(
          "sensor {}: {} gyroscope samples at the count limits (saturated) were excluded; the "
          "rotations containing them are not used: rotate more slowly or use a larger "
          "--gyro-fs-dps range",
          out.sensor, r.gyro_sat_count));
    }
    if (r.has_table_column && r.seg.table_count == 0) {
      out.warnings.push_back(fmt::format(
          "sensor {}: table_rate_dps is present but has no runs (every value empty or 0, or "
          "runs shorter than {} s): the gyroscope scale must come from hand rotations; record "
          "runs at a known constant rate",
          out.sensor, o.segmentation.min_table_s + 2 * o.segmentation.table_settle_s));
    }
    for (Segment s : r.seg.segments) out.segments.push_back(s);
  }
  out.threshold_factor = d.records.front().seg.threshold_factor;

  // Static poses (and table runs, rotations) with their means.
  for (size_t ri = 0; ri < d.records.size(); ++ri) {
    const Record& r = d.records[ri];
    for (const Segment& s : r.seg.segments) {
      if (s.kind == SegmentKind::kStatic) d.statics.push_back(MeanOver(r, static_cast<int>(ri), s));
      if (s.kind == SegmentKind::kTable && d.has_gyro) {
        d.tables.push_back(MeanOver(r, static_cast<int>(ri), s));
      }
    }
  }
  // Temperature term.
  bool all_temp = true;
  for (const Record& r : d.records) all_temp = all_temp && !r.temp_c.empty();
  double tmin = 1e300, tmax = -1e300, tsum = 0;
  for (const Pose& p : d.statics) {
    tmin = std::min(tmin, p.temp_c);
    tmax = std::max(tmax, p.temp_c);
    tsum += p.temp_c;
  }
  if (o.temperature == TemperatureMode::kOn && !all_temp) {
    return MakeError(fmt::format(
        "sensor {}: a temperature term was requested but not every input has a temp_c column",
        out.sensor));
  }
  if (all_temp && !d.statics.empty()) {
    const double span = tmax - tmin;
    if (o.temperature == TemperatureMode::kOn) {
      if (!(span > 0)) {
        return MakeError(fmt::format(
            "sensor {}: a temperature term was requested but the static poses all have the same "
            "temperature; record poses over a temperature range (e.g. warm-up)",
            out.sensor));
      }
      d.temperature = true;
    } else if (o.temperature == TemperatureMode::kAuto && span >= o.min_temp_span_c) {
      d.temperature = true;
    }
    if (d.temperature) d.t_ref_c = tsum / static_cast<double>(d.statics.size());
  }
  std::optional<PoseTemperatureRange> pose_temperature;
  if (all_temp && !d.statics.empty()) {
    pose_temperature = PoseTemperatureRange{tmin, tsum / static_cast<double>(d.statics.size()),
                                            tmax, static_cast<int>(d.statics.size())};
  }

  // Too few poses for the accelerometer model.
  const int pa = FreeCount(ImuSensor::kAccel, o.accel_model, d.temperature);
  const int need = pa + 3;
  if (static_cast<int>(d.statics.size()) < need) {
    return MakeError(fmt::format(
        "sensor {}: {} static poses found; the accelerometer '{}' model{} has {} parameters and "
        "needs at least {} poses for a fit with an uncertainty. Collect more static poses (hold "
        "each still for at least {} s), e.g. the 6 faces, 8 corners and 12 edges of a cube",
        out.sensor, d.statics.size(), ModelKindName(o.accel_model),
        d.temperature ? " with temperature term" : "", pa, need,
        o.segmentation.min_static_s + o.segmentation.window_s));
  }

  // Accelerometer start: ellipsoid fit, else nominal.
  Params x;
  const double accel_nominal = NominalScale(ImuSensor::kAccel, accel_unit, o.accel_fs_g).value();
  std::vector<Eigen::Vector3d> pose_means;
  for (const Pose& p : d.statics) pose_means.push_back(p.accel);
  Eigen::Vector3d b0 = Eigen::Vector3d::Zero(), k0 = Eigen::Vector3d::Constant(accel_nominal);
  Eigen::Vector3d be, ke;
  if (EllipsoidStart(pose_means, d.target_norm, &be, &ke)) {
    b0 = be;
    if (o.accel_model != ModelKind::kBias) k0 = ke;
  } else if (o.accel_model != ModelKind::kBias) {
    out.warnings.push_back(fmt::format(
        "sensor {}: the pose means do not fit an ellipsoid; starting from the nominal scale",
        out.sensor));
  }
  d.accel_ref = k0;
  for (int a = 0; a < 3; ++a) {
    x.ab[a] = k0[a] * b0[a];  // Scaled parameters (TagProblemData::accel_ref).
    x.ak[a] = 1.0;
  }
  // Do the poses span the sphere? Each axis should point up and down at least once.
  {
    std::vector<std::string> missing;
    for (int a = 0; a < 3; ++a) {
      double hi = -1, lo = 1;
      for (const Pose& p : d.statics) {
        const Eigen::Vector3d u = (k0.asDiagonal() * (p.accel - b0)).normalized();
        hi = std::max(hi, u[a]);
        lo = std::min(lo, u[a]);
      }
      if (hi < 0.5) missing.push_back(AxisWord(a, true));
      if (lo > -0.5) missing.push_back(AxisWord(a, false));
    }
    if (!missing.empty()) {
      std::string list;
      for (const std::string& s : missing) list += (list.empty() ? "" : ", ") + s;
      const std::string msg = fmt::format(
          "sensor {}: the static poses do not span the sphere: no pose had the {} axis within 60 "
          "deg of up; add poses with {} pointing up",
          out.sensor, list, list);
      if (o.accel_model == ModelKind::kBias) {
        out.warnings.push_back(msg);
      } else {
        return MakeError(msg + " (the scale and misalignment need every axis up and down)");
      }
    }
  }

  // Stage 1: accelerometer alone.
  Fit fit;
  std::vector<double*> free_blocks;
  int m_accel = 0;
  {
    Status s = SolveStage(Stage::kAccel, d, o, &x, &fit, nullptr, &free_blocks, &m_accel);
    if (!s.ok()) return s.error();
    fit.s_accel =
        GroupSigma(fit.r_accel, static_cast<double>(m_accel - pa) / static_cast<double>(m_accel),
                   o.loss != LossKind::kTrivial);
  }
  // Accelerometer final: whitened (robust loss if chosen), rank, covariance.
  ceres::Problem accel_problem;
  std::vector<double*> accel_free;
  Eigen::MatrixXd cov_a;
  double chi2_accel = 0;
  {
    Status s =
        SolveStage(Stage::kAccelFinal, d, o, &x, &fit, &accel_problem, &accel_free, &m_accel);
    if (!s.ok()) return s.error();
    std::vector<std::string> names;
    for (const std::string& n : FreeNames(ImuSensor::kAccel, o.accel_model, d.temperature)) {
      names.push_back("accel." + n);
    }
    Status rank = CheckRank(&accel_problem, accel_free, names);
    if (!rank.ok())
      return MakeError(fmt::format("sensor {}: {}", out.sensor, rank.error().message));
    Result<Eigen::MatrixXd> c =
        ScaledCovariance(&accel_problem, accel_free, pa, m_accel, &chi2_accel);
    if (!c.ok()) return MakeError(fmt::format("sensor {}: {}", out.sensor, c.error().message));
    cov_a = c.value();
  }

  // Gyroscope.
  int pg = 0;
  int m_gyro_final = 0;
  double chi2_gyro = 0;
  Eigen::MatrixXd cov_g;
  ceres::Problem gyro_problem;
  if (d.has_gyro) {
    pg = FreeCount(ImuSensor::kGyro, o.gyro_model, d.temperature);
    // Rotations between consecutive static poses of one record.
    for (size_t ri = 0; ri < d.records.size(); ++ri) {
      const Record& r = d.records[ri];
      const Pose* prev = nullptr;
      Segment* pending = nullptr;
      size_t pose_index = 0;
      for (size_t si = 0; si < d.statics.size(); ++si) {
        if (d.statics[si].record == static_cast<int>(ri)) {
          pose_index = si;
          break;
        }
      }
      for (Segment& s : out.segments) {
        if (s.piece != static_cast<int>(ri)) continue;
        if (s.kind == SegmentKind::kStatic) {
          const Pose* cur = &d.statics[pose_index++];
          if (prev != nullptr && pending != nullptr && pending->used) {
            const size_t b = prev->segment->end, e = cur->segment->begin;
            bool ok = true;
            for (size_t k = b; k <= e; ++k) ok = ok && !r.gyro_sat[k];
            Segment* ps = pending;
            if (!ok) {
              ps->used = false;
              ps->note = "saturated gyroscope samples";
            } else if (r.t_s[e] - r.t_s[b - 1] > o.max_rotation_s) {
              ps->used = false;
              ps->note = fmt::format("longer than {} s", o.max_rotation_s);
            } else {
              ci::RotationData rd;
              rd.accel_start = d.accel_ref.cwiseProduct(prev->accel);
              rd.accel_end = d.accel_ref.cwiseProduct(cur->accel);
              rd.dtemp_start_c = d.temperature ? prev->temp_c - d.t_ref_c : 0.0;
              rd.dtemp_end_c = d.temperature ? cur->temp_c - d.t_ref_c : 0.0;
              for (size_t k = b; k <= e; ++k) {
                rd.gyro.push_back(r.gyro[k]);
                rd.dt_s.push_back(r.t_s[k] - r.t_s[k - 1]);
                rd.dtemp_c.push_back(d.temperature ? r.temp_c[k] - d.t_ref_c : 0.0);
              }
              d.rotations.push_back(std::move(rd));
              d.rotation_segments.push_back(pending);
            }
          }
          prev = cur;
          pending = nullptr;
        } else if (s.kind == SegmentKind::kRotation) {
          pending = &s;
        }
      }
    }
    const int dynamic = static_cast<int>(d.tables.size() + 2 * d.rotations.size());
    const int dyn_params = pg - 3 - (d.temperature ? 3 : 0);
    if (dyn_params > 0 && dynamic < dyn_params + 3) {
      return MakeError(fmt::format(
          "sensor {}: {} hand rotations between static poses and {} table runs found; the "
          "gyroscope '{}' model needs at least {} rotations (or {} table runs at a known rate "
          "in different orientations). Turn the tag by hand between the static poses, or record "
          "table runs, or use --model bias",
          out.sensor, d.rotations.size(), d.tables.size(), ModelKindName(o.gyro_model),
          (dyn_params + 4) / 2, dyn_params + 3));
    }
    // Bias start: the static means (per-axis regression on temperature when fitted).
    const double gyro_nominal = NominalScale(ImuSensor::kGyro, gyro_unit, o.gyro_fs_dps).value();
    {
      Eigen::Vector3d mean = Eigen::Vector3d::Zero();
      for (const Pose& p : d.statics) mean += p.gyro;
      mean /= static_cast<double>(d.statics.size());
      for (int a = 0; a < 3; ++a) {
        x.gb[a] = mean[a];
        x.gk[a] = gyro_nominal;
      }
      // Initial weights: static means' standard error, 0.5 deg of direction, 0.1 % of rate.
      std::vector<double> se;
      for (const Pose& p : d.statics) {
        se.push_back(p.gyro_sd.norm() /
                     std::sqrt(3.0 * static_cast<double>(std::max<size_t>(p.n, 1))));
      }
      std::nth_element(se.begin(), se.begin() + static_cast<std::ptrdiff_t>(se.size() / 2),
                       se.end());
      fit.s_static = std::max(se[se.size() / 2], 1e-9);
      fit.s_rotation = 0.5 * ci::kRadPerDeg;
      fit.s_table = 0.01;
    }
    if (o.gyro_model != ModelKind::kBias) {
      double k_iso = gyro_nominal;
      if (!d.tables.empty()) {
        std::vector<double> ratios;
        for (const Pose& p : d.tables) {
          const double n = (p.gyro - Eigen::Vector3d(x.gb[0], x.gb[1], x.gb[2])).norm();
          if (n > 0) ratios.push_back(std::abs(p.segment->table_rate_dps) / n);
        }
        if (!ratios.empty()) {
          std::nth_element(ratios.begin(),
                           ratios.begin() + static_cast<std::ptrdiff_t>(ratios.size() / 2),
                           ratios.end());
          k_iso = ratios[ratios.size() / 2];
        }
      } else {
        // One-dimensional search of an isotropic scale: log grid then golden section.
        auto cost = [&](double k) {
          double gk[3] = {k, k, k};
          const double* p[8] = {x.ab, x.ak, x.am, x.ab1, x.gb, gk, x.gm, x.gb1};
          double c = 0;
          for (const ci::RotationData& rd : d.rotations) {
            c += ci::RotationResidual(rd, p).squaredNorm();
          }
          return c;
        };
        const double c_none = cost(0.0);
        double best_log = 0, best_cost = 1e300;
        for (double lg = -3.0; lg <= 3.0 + 1e-9; lg += 0.05) {
          const double c = cost(gyro_nominal * std::pow(10.0, lg));
          if (c < best_cost) {
            best_cost = c;
            best_log = lg;
          }
        }
        double lo = best_log - 0.05, hi = best_log + 0.05;
        const double gr = (std::sqrt(5.0) - 1) / 2;
        for (int it = 0; it < 40; ++it) {
          const double a = hi - gr * (hi - lo), b = lo + gr * (hi - lo);
          if (cost(gyro_nominal * std::pow(10.0, a)) < cost(gyro_nominal * std::pow(10.0, b))) {
            hi = b;
          } else {
            lo = a;
          }
        }
        best_log = 0.5 * (lo + hi);
        best_cost = cost(gyro_nominal * std::pow(10.0, best_log));
        if (!(best_cost < 0.5 * c_none)) {
          return MakeError(fmt::format(
              "sensor {}: the gyroscope rotations do not match the accelerometer's gravity "
              "directions at any scale (best residual {:.3g} vs {:.3g} without rotation); check "
              "that the accelerometer and gyroscope columns belong to one sensor with the same "
              "axes",
              out.sensor, best_cost, c_none));
        }
        k_iso = gyro_nominal * std::pow(10.0, best_log);
      }
      for (int a = 0; a < 3; ++a) x.gk[a] = k_iso;
    }
    // From here on the gyroscope works in scaled units (TagProblemData::gyro_ref).
    d.gyro_ref = Eigen::Vector3d(x.gk[0], x.gk[1], x.gk[2]);
    for (int a = 0; a < 3; ++a) {
      x.gb[a] *= d.gyro_ref[a];
      x.gk[a] = 1.0;
    }
    fit.s_static *= d.gyro_ref.mean();
    for (ci::RotationData& rd : d.rotations) {
      for (Eigen::Vector3d& g : rd.gyro) g = d.gyro_ref.cwiseProduct(g);
    }
    // Stage 2: gyroscope with the accelerometer held; twice, re-weighting the groups.
    for (int pass = 0; pass < 2; ++pass) {
      int m_gyro = 0;
      Status s = SolveStage(Stage::kGyro, d, o, &x, &fit, nullptr, &free_blocks, &m_gyro);
      if (!s.ok()) return s.error();
      const double ratio = static_cast<double>(m_gyro - pg) / static_cast<double>(m_gyro);
      const bool robust = o.loss != LossKind::kTrivial;
      fit.s_static = GroupSigma(fit.r_static, ratio, robust);
      if (!fit.r_table.empty()) fit.s_table = GroupSigma(fit.r_table, ratio, robust);
      if (!fit.r_rotation.empty()) {
        // 2 degrees of freedom per 3 components (see SolveStage).
        fit.s_rotation = GroupSigma(fit.r_rotation, ratio * 2.0 / 3.0, robust);
      }
    }
    // Gyroscope final: whitened, rank, covariance with the accelerometer held ...
    std::vector<double*> gyro_free;
    Status s =
        SolveStage(Stage::kGyroFinal, d, o, &x, &fit, &gyro_problem, &gyro_free, &m_gyro_final);
    if (!s.ok()) return s.error();
    std::vector<std::string> names;
    for (const std::string& n : FreeNames(ImuSensor::kGyro, o.gyro_model, d.temperature)) {
      names.push_back("gyro." + n);
    }
    Status rank = CheckRank(&gyro_problem, gyro_free, names);
    if (!rank.ok())
      return MakeError(fmt::format("sensor {}: {}", out.sensor, rank.error().message));
    Result<Eigen::MatrixXd> c =
        ScaledCovariance(&gyro_problem, gyro_free, pg, m_gyro_final, &chi2_gyro);
    if (!c.ok()) return MakeError(fmt::format("sensor {}: {}", out.sensor, c.error().message));
    cov_g = c.value();
    // ... plus the accelerometer's uncertainty carried by the rotations: with the whitened
    // Jacobians G_g (gyro parameters) and G_a (accel parameters) of the gyroscope residuals,
    // the gyro solution moves by S da, S = -(G_g^T G_g)^-1 G_g^T G_a (implicit function
    // theorem), so cov_g += S cov_a S^T (JCGM 100:2008 5.2, correlated inputs).
    std::vector<double*> accel_in_gyro;
    for (double* b : accel_free) {
      if (gyro_problem.HasParameterBlock(b)) accel_in_gyro.push_back(b);
    }
    if (!accel_in_gyro.empty() && accel_in_gyro.size() == accel_free.size()) {
      for (double* b : accel_in_gyro) gyro_problem.SetParameterBlockVariable(b);
      std::vector<double*> all = gyro_free;
      all.insert(all.end(), accel_in_gyro.begin(), accel_in_gyro.end());
      std::optional<Eigen::MatrixXd> j = DenseJacobian(&gyro_problem, all);
      if (!j) return MakeError("could not evaluate the gyroscope Jacobian at the solution");
      const Eigen::MatrixXd gg = j->leftCols(pg);
      const Eigen::MatrixXd ga = j->rightCols(pa);
      const Eigen::MatrixXd sens = -(gg.transpose() * gg).ldlt().solve(gg.transpose() * ga);
      cov_g += sens * cov_a * sens.transpose();
    }
  }

  out.iterations = fit.iterations;
  // Back to input units: b = b' / k_ref, k = k' k_ref, b1 = b1' / k_ref; the covariance
  // transforms with the diagonal Jacobian D of that map (JCGM 100:2008 5.1.2).
  auto unscale = [&](const Eigen::Vector3d& ref, ModelKind kind, ImuSensor sensor, double* b,
                     double* k, double* b1, Eigen::MatrixXd* cov) {
    std::vector<double> dvec;
    for (int a = 0; a < 3; ++a) {
      b[a] /= ref[a];
      k[a] *= ref[a];
      b1[a] /= ref[a];
    }
    for (int a = 0; a < 3; ++a) dvec.push_back(1.0 / ref[a]);
    if (kind != ModelKind::kBias) {
      for (int a = 0; a < 3; ++a) dvec.push_back(ref[a]);
    }
    if (kind == ModelKind::kFull) {
      for (int a = 0; a < MisalignmentCount(sensor); ++a) dvec.push_back(1.0);
    }
    if (d.temperature) {
      for (int a = 0; a < 3; ++a) dvec.push_back(1.0 / ref[a]);
    }
    METRO_CHECK(static_cast<Eigen::Index>(dvec.size()) == cov->rows());
    const Eigen::VectorXd dd =
        Eigen::Map<Eigen::VectorXd>(dvec.data(), static_cast<Eigen::Index>(dvec.size()));
    *cov = dd.asDiagonal() * (*cov) * dd.asDiagonal();
  };
  if (d.has_gyro) {
    unscale(d.gyro_ref, o.gyro_model, ImuSensor::kGyro, x.gb, x.gk, x.gb1, &cov_g);
  }
  unscale(d.accel_ref, o.accel_model, ImuSensor::kAccel, x.ab, x.ak, x.ab1, &cov_a);

  SensorCalibration accel =
      MakeSensorCalibration(ImuSensor::kAccel, o.accel_model, d.temperature, d.t_ref_c, accel_unit,
                            x.ab, x.ak, x.am, x.ab1, cov_a);
  accel.dof = m_accel - pa;
  accel.reduced_chi2 = chi2_accel;
  accel.coverage_factor_95 = StudentT975(accel.dof);
  accel.residual_rms = Rms(fit.r_accel);
  accel.residual_unit = "g";
  accel.groups.push_back(
      {"static_pose_norm", static_cast<int>(fit.r_accel.size()), accel.residual_rms, "g"});
  {
    // Per-sample gravity-norm residual over the static samples (includes the noise).
    const SensorModel& mo = accel.model;
    double ss = 0;
    int64_t n = 0;
    for (const Pose& p : d.statics) {
      const Record& r = d.records[static_cast<size_t>(p.record)];
      for (size_t i = p.segment->begin; i < p.segment->end; ++i) {
        if (r.saturated[i]) continue;
        const double t = r.temp_c.empty() ? 0.0 : r.temp_c[i];
        const double e = mo.Apply(r.accel[i], t).norm() - d.target_norm;
        ss += e * e;
        ++n;
      }
    }
    accel.groups.push_back({"static_sample_norm", static_cast<int>(n),
                            n > 0 ? std::sqrt(ss / static_cast<double>(n)) : 0.0, "g"});
  }
  for (const Pose& p : d.statics) accel.segments.push_back(*p.segment);
  {
    Status det = CheckDetermined(accel, out.sensor);
    if (!det.ok()) return det.error();
  }
  accel.static_pose_temperature = pose_temperature;
  out.accel = std::move(accel);

  if (d.has_gyro) {
    SensorCalibration gyro =
        MakeSensorCalibration(ImuSensor::kGyro, o.gyro_model, d.temperature, d.t_ref_c, gyro_unit,
                              x.gb, x.gk, x.gm, x.gb1, cov_g);
    gyro.dof = m_gyro_final - pg;
    gyro.reduced_chi2 = chi2_gyro;
    gyro.coverage_factor_95 = StudentT975(gyro.dof);
    gyro.groups.push_back(
        {"static_rate", static_cast<int>(fit.r_static.size() / 3), Rms(fit.r_static), "deg/s"});
    std::vector<double> table_dps = fit.r_table;
    if (!d.tables.empty()) {
      gyro.groups.push_back(
          {"table_rate", static_cast<int>(d.tables.size()), Rms(table_dps), "deg/s"});
    }
    // Rotation residuals as angles: |R^T u_i - u_j| is the chord of the angle between them.
    std::vector<double> angles_deg;
    for (size_t i = 0; i + 2 < fit.r_rotation.size(); i += 3) {
      const double chord = std::sqrt(fit.r_rotation[i] * fit.r_rotation[i] +
                                     fit.r_rotation[i + 1] * fit.r_rotation[i + 1] +
                                     fit.r_rotation[i + 2] * fit.r_rotation[i + 2]);
      angles_deg.push_back(2.0 * std::asin(std::min(1.0, chord / 2.0)) * 180.0 / kPi);
    }
    if (!d.rotations.empty()) {
      gyro.groups.push_back(
          {"rotation_gravity", static_cast<int>(d.rotations.size()), Rms(angles_deg), "deg"});
      gyro.residual_rms = Rms(angles_deg);
      gyro.residual_unit = "deg";
    } else if (!d.tables.empty()) {
      gyro.residual_rms = Rms(table_dps);
      gyro.residual_unit = "deg/s";
    } else {
      gyro.residual_rms = Rms(fit.r_static);
      gyro.residual_unit = "deg/s";
    }
    for (const Pose& p : d.statics) gyro.segments.push_back(*p.segment);
    for (const Pose& p : d.tables) gyro.segments.push_back(*p.segment);
    for (const Segment* s : d.rotation_segments) gyro.segments.push_back(*s);
    std::sort(gyro.segments.begin(), gyro.segments.end(), [](const Segment& a, const Segment& b) {
      return a.piece != b.piece ? a.piece < b.piece : a.begin < b.begin;
    });
    Status det = CheckDetermined(gyro, out.sensor);
    if (!det.ok()) return det.error();
    gyro.static_pose_temperature = pose_temperature;
    out.gyro = std::move(gyro);
  }
  if (!fit.converged) {
    out.warnings.push_back(fmt::format(
        "sensor {}: the solver stopped before convergence (no-convergence after {} iterations)",
        out.sensor, o.max_iterations));
  }
  return out;
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
    const Eigen::Matrix3d d =
        (MatrixFromFree(mo.sensor, mo.kind, k, xp) - MatrixFromFree(mo.sensor, mo.kind, k, xm)) /
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
    return MakeError(std::string("calibration failed: ") + e.what());
  }
}

Status CheckCalibrationColumns(const std::vector<const Session*>& sessions,
                               const CalibrationOptions& options) {
  // Sensors with a gyroscope family in some session.
  std::map<int, std::string> gyro_seen;  // sensor -> a session that has it
  for (const Session* s : sessions) {
    for (const Tag& t : s->tags) {
      if (options.sensor != 0 && t.sensor != options.sensor) continue;
      const FamilyMatch accel = FindFamily(t, ImuSensor::kAccel);
      if (accel.unit == nullptr) {
        return MakeError(s->path, 0,
                         accel.family.empty()
                             ? fmt::format("sensor {}: no accelerometer columns: the calibrator "
                                           "needs {} in static poses",
                                           t.sensor, FamilyChoices(ImuSensor::kAccel))
                             : IncompleteFamilyMessage(t.sensor, ImuSensor::kAccel, accel));
      }
      const FamilyMatch gyro = FindFamily(t, ImuSensor::kGyro);
      if (gyro.unit == nullptr && !gyro.family.empty() && options.fit_gyro) {
        return MakeError(
            s->path, 0,
            IncompleteFamilyMessage(t.sensor, ImuSensor::kGyro, gyro) + " (or --accel-only)");
      }
      if (gyro.unit != nullptr && gyro_seen.count(t.sensor) == 0) gyro_seen[t.sensor] = s->path;
    }
  }
  if (!options.fit_gyro) return Status::Ok();
  for (const Session* s : sessions) {
    for (const Tag& t : s->tags) {
      if (options.sensor != 0 && t.sensor != options.sensor) continue;
      if (gyro_seen.count(t.sensor) != 0 && FindFamily(t, ImuSensor::kGyro).unit == nullptr) {
        return MakeError(
            s->path, 0,
            fmt::format("sensor {}: no gyroscope columns while {} has them: records of one tag "
                        "are fitted together; log {} in every record or give --accel-only",
                        t.sensor, gyro_seen[t.sensor], FamilyChoices(ImuSensor::kGyro)));
      }
    }
  }
  return Status::Ok();
}

Result<Calibration> CalibrateSessions(const std::vector<const Session*>& sessions,
                                      const CalibrationOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) return MakeError("invalid calibration options: " + why);
  if (sessions.empty()) return MakeError("no sessions to calibrate");
  Calibration cal;
  cal.gravity_mps2 = options.gravity_mps2;
  cal.tool_version = std::string(kToolName) + " " + kVersion;
  {
    const std::time_t now = std::time(nullptr);
    std::tm tm{};
    gmtime_r(&now, &tm);
    char buf[32];
    std::strftime(buf, sizeof(buf), "%Y-%m-%dT%H:%M:%SZ", &tm);
    cal.date_utc = buf;
  }
  std::map<int, std::vector<const Tag*>> by_sensor;
  for (const Session* s : sessions) {
    cal.inputs.push_back({s->path, s->sha256});
    for (const Tag& t : s->tags) {
      if (options.sensor == 0 || t.sensor == options.sensor) by_sensor[t.sensor].push_back(&t);
    }
  }
  if (by_sensor.empty()) {
    return MakeError(options.sensor != 0
                         ? fmt::format("no tag with sensor number {} in the input", options.sensor)
                         : std::string("the input has no tags"));
  }
  for (const auto& [sensor, tags] : by_sensor) {
    Result<TagCalibration> t = CalibrateTag(tags, options);
    if (!t.ok()) {
      Error e = t.error();
      if (e.file.empty() && sessions.size() == 1) e.file = sessions.front()->path;
      return e;
    }
    cal.tags.push_back(std::move(t).value());
  }
  return cal;
}

}  // namespace metro
