#include "calibration/calibrate_stages.hpp"

#include <ceres/ceres.h>
#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <boost/math/distributions/chi_squared.hpp>
#include <boost/math/distributions/students_t.hpp>
#include <cmath>
#include <memory>
#include <numeric>

namespace metro::calibration_internal {

namespace {

constexpr double kPi = 3.14159265358979323846;

using PB = ParameterBlocks;

const Quantity* FindQuantity(const Tag& tag, std::string_view name) {
  for (const Quantity& q : tag.quantities) {
    if (q.name == name) return &q;
  }
  return nullptr;
}

std::string JoinNames(const std::vector<std::string>& names, const char* separator) {
  std::string out;
  for (const std::string& n : names) out += (out.empty() ? "" : separator) + n;
  return out;
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

std::string AxisWord(int axis, bool positive) {
  return fmt::format("{}{}", positive ? '+' : '-', "XYZ"[axis]);
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

// Rank of the whitened Jacobian `j` over the free blocks; names the null direction on failure.
Status CheckRankOf(Eigen::MatrixXd j, const std::vector<std::string>& names) {
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
  return MakeFailedError(fmt::format(
      "degenerate calibration: the Jacobian is rank deficient (smallest/largest singular value "
      "{:.2e}); the data do not determine {}. Collect poses and rotations that exercise these "
      "parameters (every axis up and down, rotations about every axis)",
      sv.size() > 0 && sv(0) > 0 ? sv(last) / sv(0) : 0.0, list));
}

Status CheckRank(ceres::Problem* problem, const std::vector<double*>& free_blocks,
                 const std::vector<std::string>& names) {
  std::optional<Eigen::MatrixXd> jac = DenseJacobian(problem, free_blocks);
  if (!jac) return MakeFailedError("could not evaluate the Jacobian at the solution");
  return CheckRankOf(std::move(*jac), names);
}

std::vector<std::string> QualifiedFreeNames(ImuSensor imu, ModelKind kind, bool temperature) {
  std::vector<std::string> names;
  for (const std::string& n : PB::FreeNames(imu, kind, temperature)) {
    names.push_back(std::string(ImuSensorName(imu)) + "." + n);
  }
  return names;
}

constexpr const char* kNoCovariance =
    "degenerate calibration: Ceres could not compute the parameter covariance (the "
    "Jacobian is rank deficient); the data do not determine every constant: collect more "
    "varied poses and rotations";

// The residual variance s^2 = 2 cost / (m - p) of a whitened fit (Type A, JCGM 100:2008 4.2.3
// and G.4; the groups are whitened, so s^2 is the reduced chi-square). robust_scale > 0 (a
// robust loss of that scale): s^2 from the blocks the loss keeps (below).
double ResidualVariance(ceres::Problem* problem, int p, int m, double robust_scale) {
  double cost = 0;
  problem->Evaluate(ceres::Problem::EvaluateOptions(), &cost, nullptr, nullptr, nullptr);
  int dof = m - p;
  double s2 = dof > 0 ? 2.0 * cost / static_cast<double>(dof) : 0.0;
  if (robust_scale > 0) {
    // With a robust loss the outlying blocks (where the loss has cut the weight below half:
    // squared whitened norm above robust_scale^2) would dominate 2 cost; s^2 comes from the
    // rest, each block counting its degrees of freedom (2 for a rotation's 3 components).
    std::vector<ceres::ResidualBlockId> ids;
    problem->GetResidualBlocks(&ids);
    double ss = 0;
    int count = 0;
    for (ceres::ResidualBlockId id : ids) {
      const int size = problem->GetCostFunctionForResidualBlock(id)->num_residuals();
      std::vector<double> r(static_cast<size_t>(size));
      double block_cost = 0;
      if (!problem->EvaluateResidualBlock(id, false, &block_cost, r.data(), nullptr)) continue;
      double n2 = 0;
      for (double v : r) n2 += v * v;
      if (n2 > robust_scale * robust_scale) continue;
      ss += n2;
      std::vector<double*> blocks;
      problem->GetParameterBlocksForResidualBlock(id, &blocks);
      const bool rotation = size == 3 && blocks.size() == PB::kBlockCount;  // R^T u_i - u_j
      count += rotation ? 2 : size;
    }
    dof = count - p;
    s2 = dof > 0 ? ss / static_cast<double>(dof) : 0.0;
  }
  return s2;
}

// (J^T J)^-1 of the free parameters from Ceres's Covariance API (DENSE_SVD, no pseudo-inverse),
// times s2.
Result<Eigen::MatrixXd> CeresCovariance(ceres::Problem* problem,
                                        const std::vector<double*>& free_blocks, int p, double s2) {
  ceres::Covariance::Options co;
  co.algorithm_type = ceres::DENSE_SVD;
  co.null_space_rank = 0;
  co.num_threads = 1;
  ceres::Covariance covariance(co);
  std::vector<const double*> cblocks(free_blocks.begin(), free_blocks.end());
  if (!covariance.Compute(cblocks, problem)) return MakeFailedError(kNoCovariance);
  int block_total = 0;
  for (const double* b : cblocks) block_total += problem->ParameterBlockSize(b);
  METRO_CHECK(block_total == p);
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> cov(p, p);
  covariance.GetCovarianceMatrix(cblocks, cov.data());
  return Eigen::MatrixXd(cov * s2);
}

// (J^T J)^-1 of the whitened Jacobian `j` by its SVD, refused as Ceres's DENSE_SVD refuses it
// (a singular value below sqrt(1e-14), Ceres's min_reciprocal_condition_number, times the
// largest), times s2: the covariance a model of the ladder needs for the comparison and
// CheckDetermined, from a Jacobian already evaluated. It equals CeresCovariance to rounding.
Result<Eigen::MatrixXd> DenseSvdCovariance(const Eigen::MatrixXd& j, double s2) {
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(j, Eigen::ComputeThinV);
  const Eigen::VectorXd& sv = svd.singularValues();
  if (sv.size() < j.cols() || sv.size() == 0 || !(sv(0) > 0)) {
    return MakeFailedError(kNoCovariance);
  }
  Eigen::VectorXd inv2(sv.size());
  for (Eigen::Index i = 0; i < sv.size(); ++i) {
    if (sv(i) / sv(0) < std::sqrt(1e-14)) return MakeFailedError(kNoCovariance);
    inv2(i) = 1.0 / (sv(i) * sv(i));
  }
  return Eigen::MatrixXd(svd.matrixV() * inv2.asDiagonal() * svd.matrixV().transpose() * s2);
}

// Covariance of the free parameters from Ceres's Covariance API scaled by the residual
// variance (ResidualVariance); *reduced_chi2 = s^2.
Result<Eigen::MatrixXd> ScaledCovariance(ceres::Problem* problem,
                                         const std::vector<double*>& free_blocks, int p, int m,
                                         double robust_scale, double* reduced_chi2) {
  const double s2 = ResidualVariance(problem, p, m, robust_scale);
  *reduced_chi2 = s2;
  return CeresCovariance(problem, free_blocks, p, s2);
}

// Rank and covariance of a final stage's problem; errors name the tag.
Status RankAndCovariance(ceres::Problem* problem, ImuSensor imu, ModelKind kind, bool temperature,
                         int sensor, double robust_scale, SensorSolution* s) {
  Status rank = CheckRank(problem, s->free_blocks, QualifiedFreeNames(imu, kind, temperature));
  if (!rank.ok()) return rank.error().WithContext(fmt::format("sensor {}", sensor));
  Result<Eigen::MatrixXd> c = ScaledCovariance(problem, s->free_blocks, s->parameters, s->residuals,
                                               robust_scale, &s->reduced_chi2);
  if (!c.ok()) return c.error().WithContext(fmt::format("sensor {}", sensor));
  s->covariance = c.value();
  return Status::Ok();
}

}  // namespace

std::optional<Eigen::MatrixXd> HeldTermSensitivity(ceres::Problem* problem,
                                                   const std::vector<double*>& free_blocks, int p,
                                                   const std::vector<double*>& held) {
  for (double* b : held) {
    if (!problem->HasParameterBlock(b)) return std::nullopt;
  }
  for (double* b : held) problem->SetParameterBlockVariable(b);
  std::vector<double*> blocks = free_blocks;
  blocks.insert(blocks.end(), held.begin(), held.end());
  std::optional<Eigen::MatrixXd> j = DenseJacobian(problem, blocks);
  for (double* b : held) problem->SetParameterBlockConstant(b);
  if (!j || j->cols() <= p) return std::nullopt;
  const Eigen::MatrixXd jf = j->leftCols(p);
  const Eigen::MatrixXd jh = j->rightCols(j->cols() - p);
  Eigen::MatrixXd out = -(jf.transpose() * jf).ldlt().solve(jf.transpose() * jh);
  if (!out.allFinite()) return std::nullopt;
  return out;
}

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

// ---- Records ----------------------------------------------------------------------------

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

std::string IncompleteFamilyMessage(int sensor, ImuSensor imu, const FamilyMatch& match) {
  return fmt::format("sensor {}: the {} calibration needs {}; missing {}", sensor,
                     ImuSensorLongName(imu), JoinNames(match.family, ", "),
                     JoinNames(match.missing, ", "));
}

std::string FamilyChoices(ImuSensor imu) {
  std::string out;
  const std::vector<const Unit*> units = AxisUnits(ColumnSensorKind(imu));
  for (size_t i = 0; i < units.size(); ++i) {
    out += i == 0 ? "" : (i == 1 ? " (or " : ", or ");
    out += JoinNames(FamilyColumns(ColumnSensorKind(imu), units[i]), " ");
  }
  return units.size() > 1 ? out + ")" : out;
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
  in.temp_c = r.temp_c.empty() ? nullptr : &r.temp_c;  // The bias follows it (segments.hpp).
  in.piece = piece;
  if (!options.annotated_segments.empty()) {
    Result<SegmentationSummary> given =
        SegmentsFromAnnotations(in, options.annotated_segments, options.segments_path);
    if (!given.ok()) return given.error();
    r.seg = std::move(given).value();
    return r;
  }
  SegmentationOptions seg = options.segmentation;
  if (!r.gyro_unit.empty() && seg.gyro_units_per_dps == 0) {
    // The steady-rotation limit in the record's own units (nominal scale: deg/s per unit).
    const std::optional<double> dps_per_unit =
        NominalScale(ImuSensor::kGyro, r.gyro_unit, options.gyro_fs_dps);
    if (dps_per_unit && *dps_per_unit > 0) seg.gyro_units_per_dps = 1.0 / *dps_per_unit;
  }
  r.seg = DetectSegments(in, seg);
  return r;
}

Result<RecordSet> ReadRecords(const std::vector<const Tag*>& tags, const CalibrationOptions& o,
                              int sensor) {
  RecordSet set;
  for (size_t i = 0; i < tags.size(); ++i) {
    if (tags[i]->size() < 10) {
      return MakeError(
          fmt::format("sensor {}: input {} has {} samples; a calibration record needs "
                      "static poses of at least {} s each",
                      sensor, i + 1, tags[i]->size(), o.segmentation.min_static_s));
    }
    Result<Record> r = ReadRecord(*tags[i], static_cast<int>(i), o);
    if (!r.ok()) return r.error();
    set.records.push_back(std::move(r).value());
  }
  set.accel_unit = set.records.front().accel_unit;
  set.gyro_unit = set.records.front().gyro_unit;
  for (const Record& r : set.records) {
    if (r.accel_unit != set.accel_unit || r.gyro_unit != set.gyro_unit) {
      return MakeError(fmt::format(
          "sensor {}: the inputs disagree on units (accelerometer {} vs {}, gyroscope '{}' vs "
          "'{}'); calibrate records of one kind together",
          sensor, set.accel_unit, r.accel_unit, set.gyro_unit, r.gyro_unit));
    }
  }
  set.has_gyro = o.fit_gyro && !set.gyro_unit.empty();
  return set;
}

std::string PoseShortfallHint(const std::vector<Record>& records) {
  int shorts = 0, steady = 0;
  double shortest = 0, longest = 0, suggested = 0;
  for (const Record& r : records) {
    const SegmentationSummary& s = r.seg;
    steady += s.steady_count;
    if (s.short_static_count == 0) continue;
    shortest = shorts == 0 ? s.short_static_min_s : std::min(shortest, s.short_static_min_s);
    longest = std::max(longest, s.short_static_max_s);
    suggested =
        suggested == 0 ? s.suggested_min_static_s : std::min(suggested, s.suggested_min_static_s);
    shorts += s.short_static_count;
  }
  std::string hint;
  if (shorts > 0) {
    hint += fmt::format(
        ". {} shorter still periods were recorded ({:.2f} .. {:.2f} s) and left out: "
        "--min-static-s {:.2f} accepts them",
        shorts, shortest, longest, suggested);
  }
  if (steady > 0) {
    hint += fmt::format(
        ". {} steady rotations (the gyroscope turning at a constant rate) are not "
        "static poses; give their rate in a table_rate_dps column to use them as "
        "table runs",
        steady);
  }
  return hint;
}

void SummarizeRecords(const RecordSet& set, const CalibrationOptions& o, TagCalibration* out) {
  if (o.fit_gyro && set.gyro_unit.empty()) {
    out->warnings.push_back(fmt::format(
        "sensor {}: no gyroscope columns, accelerometer only: the gyroscope calibration needs {}",
        out->sensor, FamilyChoices(ImuSensor::kGyro)));
  }
  for (const Record& r : set.records) {
    out->saturated_samples += static_cast<int>(
        std::count(r.saturated.begin(), r.saturated.end(), static_cast<unsigned char>(1)));
    if (r.accel_sat_count > 0) {
      out->warnings.push_back(fmt::format(
          "sensor {}: {} accelerometer samples at the count limits (saturated) were excluded; "
          "if they fall in static poses, use a larger --accel-fs-g range",
          out->sensor, r.accel_sat_count));
    }
    if (r.gyro_sat_count > 0) {
      out->warnings.push_back(fmt::format(
          "sensor {}: {} gyroscope samples at the count limits (saturated) were excluded; the "
          "rotations containing them are not used: rotate more slowly or use a larger "
          "--gyro-fs-dps range",
          out->sensor, r.gyro_sat_count));
    }
    if (r.has_table_column && r.seg.table_count == 0) {
      out->warnings.push_back(fmt::format(
          "sensor {}: table_rate_dps is present but has no runs (every value empty or 0, or "
          "runs shorter than {} s): the gyroscope scale must come from hand rotations; record "
          "runs at a known constant rate",
          out->sensor, o.segmentation.min_table_s + 2 * o.segmentation.table_settle_s));
    }
    for (const Segment& s : r.seg.segments) {
      const bool disturbance =
          s.kind == SegmentKind::kRotation && s.note.rfind("disturbance inside pose", 0) == 0;
      if (s.kind == SegmentKind::kSteady || disturbance) {
        out->warnings.push_back(fmt::format("sensor {}: input {}, t = {:.2f} .. {:.2f} s: {}",
                                            out->sensor, r.piece + 1, s.start_s, s.end_s, s.note));
      }
    }
    if (r.seg.short_static_count > 0) {
      out->warnings.push_back(fmt::format(
          "sensor {}: input {}: {} still periods of {:.2f} .. {:.2f} s are shorter than the "
          "--min-static-s of {} s and were left out; --min-static-s {:.2f} accepts them",
          out->sensor, r.piece + 1, r.seg.short_static_count, r.seg.short_static_min_s,
          r.seg.short_static_max_s, o.segmentation.min_static_s, r.seg.suggested_min_static_s));
    }
    for (const Segment& s : r.seg.segments) out->segments.push_back(s);
  }
  out->threshold_factor = set.records.front().seg.threshold_factor;
}

// ---- Poses ------------------------------------------------------------------------------

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

PoseMeans MeanPoses(const std::vector<Record>& records, bool with_tables) {
  PoseMeans out;
  for (size_t ri = 0; ri < records.size(); ++ri) {
    const Record& r = records[ri];
    for (const Segment& s : r.seg.segments) {
      if (s.kind == SegmentKind::kStatic)
        out.statics.push_back(MeanOver(r, static_cast<int>(ri), s));
      if (s.kind == SegmentKind::kTable && with_tables) {
        out.tables.push_back(MeanOver(r, static_cast<int>(ri), s));
      }
    }
  }
  return out;
}

// ---- Temperature decision ---------------------------------------------------------------

bool EveryRecordHasTemperature(const std::vector<Record>& records) {
  bool all_temp = true;
  for (const Record& r : records) all_temp = all_temp && !r.temp_c.empty();
  return all_temp;
}

Result<TemperatureDecision> DecideTemperature(bool every_input_has_temp,
                                              const std::vector<Pose>& statics,
                                              const CalibrationOptions& o, int sensor) {
  TemperatureDecision out;
  double tmin = 1e300, tmax = -1e300, tsum = 0;
  for (const Pose& p : statics) {
    tmin = std::min(tmin, p.temp_c);
    tmax = std::max(tmax, p.temp_c);
    tsum += p.temp_c;
  }
  if (o.temperature == TemperatureMode::kOn && !every_input_has_temp) {
    return MakeError(fmt::format(
        "sensor {}: a temperature term was requested but not every input has a temp_c column",
        sensor));
  }
  if (every_input_has_temp && !statics.empty()) {
    const double span = tmax - tmin;
    if (o.temperature == TemperatureMode::kOn) {
      if (!(span > 0)) {
        return MakeError(fmt::format(
            "sensor {}: a temperature term was requested but the static poses all have the same "
            "temperature; record poses over a temperature range (e.g. warm-up)",
            sensor));
      }
      out.fit = true;
    } else if (o.temperature == TemperatureMode::kAuto && span >= o.min_temp_span_c) {
      out.fit = true;
    }
    if (out.fit) out.t_ref_c = tsum / static_cast<double>(statics.size());
    out.pose_range = PoseTemperatureRange{tmin, tsum / static_cast<double>(statics.size()), tmax,
                                          static_cast<int>(statics.size())};
  }
  return out;
}

// ---- Start values -----------------------------------------------------------------------

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

Result<SensorStart> StartAccel(const std::vector<Pose>& statics, double target_norm,
                               const std::string& accel_unit, bool temperature,
                               const CalibrationOptions& o, int sensor,
                               std::vector<std::string>* warnings, const std::string& hint) {
  // Too few poses for the accelerometer model.
  const int pa = PB::FreeCount(ImuSensor::kAccel, o.accel_model, temperature);
  // With the trivial loss u comes from each pose's noise (HonestAccelCovariance), so as many
  // poses as parameters determine the model (the 6-position protocol for bias and scale); a
  // robust loss scales by the residuals and needs 3 more.
  const int need = o.loss == LossKind::kTrivial ? pa : pa + 3;
  if (static_cast<int>(statics.size()) < need) {
    return MakeError(fmt::format(
        "sensor {}: {} static poses found; the accelerometer '{}' model{} has {} parameters and "
        "needs at least {} poses for a fit with an uncertainty. Collect more static poses (hold "
        "each still for at least {} s), e.g. the 6 faces, 8 corners and 12 edges of a cube{}",
        sensor, statics.size(), ModelKindName(o.accel_model),
        temperature ? " with temperature term" : "", pa, need,
        o.segmentation.min_static_s +
            std::min(o.segmentation.window_s, o.segmentation.min_static_s),
        hint));
  }
  // Ellipsoid fit, else nominal.
  const double accel_nominal = NominalScale(ImuSensor::kAccel, accel_unit, o.accel_fs_g).value();
  std::vector<Eigen::Vector3d> pose_means;
  for (const Pose& p : statics) pose_means.push_back(p.accel);
  Eigen::Vector3d b0 = Eigen::Vector3d::Zero(), k0 = Eigen::Vector3d::Constant(accel_nominal);
  Eigen::Vector3d be, ke;
  if (EllipsoidStart(pose_means, target_norm, &be, &ke)) {
    b0 = be;
    if (o.accel_model != ModelKind::kBias) k0 = ke;
  } else if (o.accel_model != ModelKind::kBias) {
    warnings->push_back(fmt::format(
        "sensor {}: the pose means do not fit an ellipsoid; starting from the nominal scale",
        sensor));
  }
  // Do the poses span the sphere? Each axis should point up and down at least once.
  std::vector<std::string> missing;
  for (int a = 0; a < 3; ++a) {
    double hi = -1, lo = 1;
    for (const Pose& p : statics) {
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
        sensor, list, list);
    if (o.accel_model == ModelKind::kBias) {
      warnings->push_back(msg);
    } else {
      return MakeError(msg + " (the scale and misalignment need every axis up and down)");
    }
  }
  SensorStart start;
  start.bias = b0;
  start.scale = k0;
  return start;
}

void SetScaledStart(ImuSensor sensor, const SensorStart& start, ParameterBlocks* x) {
  double* b = x->Get(sensor, PB::kBias);
  double* k = x->Get(sensor, PB::kScale);
  for (int a = 0; a < 3; ++a) {
    b[a] = start.scale[a] * start.bias[a];
    k[a] = 1.0;
  }
}

Result<GyroStart> StartGyro(const std::vector<Pose>& statics, const std::vector<Pose>& tables,
                            const std::vector<RotationData>& rotations, const ParameterBlocks& x,
                            double gyro_nominal, ModelKind gyro_model, int sensor) {
  GyroStart out;
  // Bias: the static means.
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const Pose& p : statics) mean += p.gyro;
  mean /= static_cast<double>(statics.size());
  out.start.bias = mean;
  out.start.scale = Eigen::Vector3d::Constant(gyro_nominal);
  // Initial weights: static means' standard error, 0.5 deg of direction, 0.1 % of rate.
  std::vector<double> se;
  for (const Pose& p : statics) {
    se.push_back(p.gyro_sd.norm() / std::sqrt(3.0 * static_cast<double>(std::max<size_t>(p.n, 1))));
  }
  std::nth_element(se.begin(), se.begin() + static_cast<std::ptrdiff_t>(se.size() / 2), se.end());
  out.weights.s_static = std::max(se[se.size() / 2], 1e-9);
  out.weights.s_rotation = 0.5 * kRadPerDeg;
  out.weights.s_table = 0.01;
  if (gyro_model == ModelKind::kBias) return out;

  double k_iso = gyro_nominal;
  if (!tables.empty()) {
    std::vector<double> ratios;
    for (const Pose& p : tables) {
      const double n = (p.gyro - mean).norm();
      if (n > 0) ratios.push_back(std::abs(p.segment->table_rate_dps) / n);
    }
    if (!ratios.empty()) {
      std::nth_element(ratios.begin(),
                       ratios.begin() + static_cast<std::ptrdiff_t>(ratios.size() / 2),
                       ratios.end());
      k_iso = ratios[ratios.size() / 2];
    }
  } else {
    // One-dimensional search of an isotropic scale: log grid then golden section, with the
    // gyroscope bias at its start and its other blocks at their start (identity) values.
    ParameterBlocks at = x;
    for (int a = 0; a < 3; ++a) at[PB::kGyroBias][a] = mean[a];
    auto cost = [&](double k) {
      double gk[3] = {k, k, k};
      std::array<const double*, PB::kBlockCount> p = at.AllConst();
      p[PB::kGyroScale] = gk;
      double c = 0;
      for (const RotationData& rd : rotations) c += RotationResidual(rd, p.data()).squaredNorm();
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
          sensor, best_cost, c_none));
    }
    k_iso = gyro_nominal * std::pow(10.0, best_log);
  }
  out.start.scale = Eigen::Vector3d::Constant(k_iso);
  return out;
}

void ApplyGyroStart(const GyroStart& start, TagProblemData* d, ParameterBlocks* x, Fit* fit) {
  d->gyro_ref = start.start.scale;
  SetScaledStart(ImuSensor::kGyro, start.start, x);
  fit->s_static = start.weights.s_static * d->gyro_ref.mean();
  fit->s_rotation = start.weights.s_rotation;
  fit->s_table = start.weights.s_table;
  for (RotationData& rd : d->rotations) {
    for (Eigen::Vector3d& g : rd.gyro) g = d->gyro_ref.cwiseProduct(g);
  }
}

// ---- Rotations --------------------------------------------------------------------------

RotationSet BuildRotations(const std::vector<Record>& records, const std::vector<Pose>& statics,
                           const TemperatureDecision& temperature, const Eigen::Vector3d& accel_ref,
                           double max_rotation_s, std::vector<Segment>* segments) {
  RotationSet out;
  const bool temp = temperature.fit;
  const double t_ref_c = temperature.t_ref_c;
  for (size_t ri = 0; ri < records.size(); ++ri) {
    const Record& r = records[ri];
    const Pose* prev = nullptr;
    Segment* pending = nullptr;
    size_t pose_index = 0;
    for (size_t si = 0; si < statics.size(); ++si) {
      if (statics[si].record == static_cast<int>(ri)) {
        pose_index = si;
        break;
      }
    }
    for (Segment& s : *segments) {
      if (s.piece != static_cast<int>(ri)) continue;
      if (s.kind == SegmentKind::kStatic) {
        const Pose* cur = &statics[pose_index++];
        if (prev != nullptr && pending != nullptr && pending->used) {
          const size_t b = prev->segment->end, e = cur->segment->begin;
          bool ok = true;
          for (size_t k = b; k <= e; ++k) ok = ok && !r.gyro_sat[k];
          Segment* ps = pending;
          if (!ok) {
            ps->used = false;
            ps->note = "saturated gyroscope samples";
          } else if (r.t_s[e] - r.t_s[b - 1] > max_rotation_s) {
            ps->used = false;
            ps->note = fmt::format("longer than {} s", max_rotation_s);
          } else {
            RotationData rd;
            rd.pose_start = static_cast<int>(prev - statics.data());
            rd.pose_end = static_cast<int>(cur - statics.data());
            rd.accel_start = accel_ref.cwiseProduct(prev->accel);
            rd.accel_end = accel_ref.cwiseProduct(cur->accel);
            rd.dtemp_start_c = temp ? prev->temp_c - t_ref_c : 0.0;
            rd.dtemp_end_c = temp ? cur->temp_c - t_ref_c : 0.0;
            for (size_t k = b; k <= e; ++k) {
              rd.gyro.push_back(r.gyro[k]);
              rd.dt_s.push_back(r.t_s[k] - r.t_s[k - 1]);
              rd.dtemp_c.push_back(temp ? r.temp_c[k] - t_ref_c : 0.0);
            }
            out.data.push_back(std::move(rd));
            out.segments.push_back(pending);
          }
        }
        prev = cur;
        pending = nullptr;
      } else if (s.kind == SegmentKind::kRotation) {
        pending = &s;
      }
    }
  }
  return out;
}

Status CheckGyroMotion(size_t table_runs, size_t rotations, ModelKind gyro_model, bool temperature,
                       int sensor) {
  const int pg = PB::FreeCount(ImuSensor::kGyro, gyro_model, temperature);
  const int dynamic = static_cast<int>(table_runs + 2 * rotations);
  const int dyn_params = pg - 3 - (temperature ? 3 : 0);
  if (dyn_params > 0 && dynamic < dyn_params + 3) {
    return MakeError(fmt::format(
        "sensor {}: {} hand rotations between static poses and {} table runs found; the "
        "gyroscope '{}' model needs at least {} rotations (or {} table runs at a known rate "
        "in different orientations). Turn the tag by hand between the static poses, or record "
        "table runs, or use --model bias",
        sensor, rotations, table_runs, ModelKindName(gyro_model), (dyn_params + 4) / 2,
        dyn_params + 3));
  }
  return Status::Ok();
}

// ---- Solves -----------------------------------------------------------------------------

Status SolveStage(Stage stage, const TagProblemData& d, const CalibrationOptions& o,
                  ParameterBlocks* x, Fit* fit, ceres::Problem* keep_problem,
                  std::vector<double*>* free_blocks, int* residual_count) {
  ceres::Problem local;
  ceres::Problem& problem = keep_problem != nullptr ? *keep_problem : local;
  const bool accel_free = stage == Stage::kAccel || stage == Stage::kAccelFinal;
  const bool gyro_used = !accel_free && d.has_gyro;
  const bool whiten = stage == Stage::kAccelFinal || stage == Stage::kGyroFinal;
  int m = 0;
  if (accel_free) {
    for (const Pose& p : d.statics) {
      const double w = whiten ? 1.0 / fit->s_accel : 1.0;
      problem.AddResidualBlock(NewAccelNormCost(d.accel_ref.cwiseProduct(p.accel),
                                                p.temp_c - d.t_ref_c, d.target_norm, w),
                               whiten ? MakeLoss(o) : nullptr, x->SensorBlocks(ImuSensor::kAccel));
      m += 1;
    }
  }
  if (gyro_used) {
    for (const Pose& p : d.statics) {
      const double w = 1.0 / fit->s_static;
      problem.AddResidualBlock(
          NewGyroStaticCost(d.gyro_ref.cwiseProduct(p.gyro), p.temp_c - d.t_ref_c, w),
          whiten ? MakeLoss(o) : nullptr, (*x)[PB::kGyroBias], (*x)[PB::kGyroBiasPerC]);
      m += 3;
    }
    for (const Pose& p : d.tables) {
      const double w = 1.0 / fit->s_table;
      problem.AddResidualBlock(
          NewGyroTableCost(d.gyro_ref.cwiseProduct(p.gyro), p.temp_c - d.t_ref_c,
                           std::abs(p.segment->table_rate_dps), w),
          whiten ? MakeLoss(o) : nullptr, x->SensorBlocks(ImuSensor::kGyro));
      m += 1;
    }
    for (const RotationData& rd : d.rotations) {
      RotationData w = rd;
      w.weight = 1.0 / fit->s_rotation;
      problem.AddResidualBlock(NewRotationCost(std::move(w)), whiten ? MakeLoss(o) : nullptr,
                               x->All());
      // R^T u_i - u_j is a difference of unit vectors: it lies in the plane normal to
      // R^T u_i + u_j, so each rotation carries 2 degrees of freedom, not 3.
      m += 2;
    }
  }
  // Free and constant blocks.
  free_blocks->clear();
  auto set = [&](ImuSensor sensor, ModelKind kind, bool active) {
    for (int r = 0; r < PB::kRoleCount; ++r) {
      const PB::Role role = static_cast<PB::Role>(r);
      double* block = x->Get(sensor, role);
      if (!problem.HasParameterBlock(block)) continue;
      if (active && PB::IsFree(role, kind, d.temperature)) {
        free_blocks->push_back(block);
      } else {
        problem.SetParameterBlockConstant(block);
      }
    }
  };
  set(ImuSensor::kAccel, o.accel_model, accel_free);
  set(ImuSensor::kGyro, o.gyro_model, gyro_used);
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
    return MakeFailedError(fmt::format(
        "the {} fit failed: {}", accel_free ? "accelerometer" : "gyroscope", summary.message));
  }
  // Unwhitened residuals of every group at the solution.
  fit->r_accel.clear();
  fit->r_static.clear();
  fit->r_table.clear();
  fit->r_rotation.clear();
  const std::array<const double*, PB::kBlockCount> all = x->AllConst();
  const double* const* ap = all.data() + PB::kAccelBias;  // Accel b k t b1.
  for (const Pose& p : d.statics) {
    std::unique_ptr<ceres::CostFunction> c(NewAccelNormCost(
        d.accel_ref.cwiseProduct(p.accel), p.temp_c - d.t_ref_c, d.target_norm, 1.0));
    double r;
    c->Evaluate(ap, &r, nullptr);
    fit->r_accel.push_back(r);
  }
  if (gyro_used) {
    const double* sp[2] = {all[PB::kGyroBias], all[PB::kGyroBiasPerC]};
    for (const Pose& p : d.statics) {
      std::unique_ptr<ceres::CostFunction> c(
          NewGyroStaticCost(d.gyro_ref.cwiseProduct(p.gyro), p.temp_c - d.t_ref_c, 1.0));
      double r[3];
      c->Evaluate(sp, r, nullptr);
      fit->r_static.insert(fit->r_static.end(), r, r + 3);
    }
    const double* const* tp = all.data() + PB::kGyroBias;  // Gyro b k t b1.
    for (const Pose& p : d.tables) {
      std::unique_ptr<ceres::CostFunction> c(
          NewGyroTableCost(d.gyro_ref.cwiseProduct(p.gyro), p.temp_c - d.t_ref_c,
                           std::abs(p.segment->table_rate_dps), 1.0));
      double r;
      c->Evaluate(tp, &r, nullptr);
      fit->r_table.push_back(r);
    }
    for (const RotationData& rd : d.rotations) {
      const Eigen::Vector3d r = RotationResidual(rd, all.data());
      fit->r_rotation.insert(fit->r_rotation.end(), r.data(), r.data() + 3);
    }
  }
  return Status::Ok();
}

Result<SensorSolution> SolveAccel(const TagProblemData& d, const CalibrationOptions& o, int sensor,
                                  ParameterBlocks* x, Fit* fit) {
  SensorSolution out;
  out.parameters = PB::FreeCount(ImuSensor::kAccel, o.accel_model, d.temperature);
  const int pa = out.parameters;
  // Unweighted fit; with a robust loss a robust pass follows, so that the scatter comes from a
  // fit that outlying poses did not drag.
  const bool robust = o.loss != LossKind::kTrivial;
  for (int pass = 0; pass < (robust ? 2 : 1); ++pass) {
    std::vector<double*> free_blocks;
    int m = 0;
    Status s = SolveStage(pass > 0 ? Stage::kAccelFinal : Stage::kAccel, d, o, x, fit, nullptr,
                          &free_blocks, &m);
    if (!s.ok()) return s.error();
    fit->s_accel =
        GroupSigma(fit->r_accel, static_cast<double>(m - pa) / static_cast<double>(m), robust);
  }
  // Final: whitened (robust loss if chosen), rank, covariance.
  out.problem = std::make_shared<ceres::Problem>();
  ceres::Problem& problem = *out.problem;
  Status s =
      SolveStage(Stage::kAccelFinal, d, o, x, fit, &problem, &out.free_blocks, &out.residuals);
  if (!s.ok()) return s.error();
  Status rc = RankAndCovariance(&problem, ImuSensor::kAccel, o.accel_model, d.temperature, sensor,
                                o.loss == LossKind::kTrivial ? 0.0 : o.loss_scale, &out);
  if (!rc.ok()) return rc.error();
  if (o.loss == LossKind::kTrivial) {
    Status honest = HonestAccelCovariance(d, *x, o, sensor, *fit, &problem, &out);
    if (!honest.ok()) return honest.error();
  }
  out.complete = o.accel_model == ModelKind::kFull;
  if (out.complete) out.problem.reset();
  return out;
}

void CompleteAccelUncertainty(ModelKind accel_model, ParameterBlocks* x, SensorSolution* s) {
  if (!s->complete && s->problem && accel_model != ModelKind::kFull) {
    // How the solution moves with the cross-axis terms the model holds at 0 (issue #36).
    double* held = x->Get(ImuSensor::kAccel, PB::kMisalignment);
    std::optional<Eigen::MatrixXd> s_m =
        HeldTermSensitivity(s->problem.get(), s->free_blocks, s->parameters, {held});
    if (s_m) s->cross_axis_sensitivity = std::move(*s_m);
  }
  s->complete = true;
  s->problem.reset();
}

namespace {
// Rotation i's residual as an angle: |R^T u_i - u_j| is the chord of the angle between them.
double RotationAngleDeg(const Fit& fit, size_t i) {
  const double chord = std::sqrt(fit.r_rotation[3 * i] * fit.r_rotation[3 * i] +
                                 fit.r_rotation[3 * i + 1] * fit.r_rotation[3 * i + 1] +
                                 fit.r_rotation[3 * i + 2] * fit.r_rotation[3 * i + 2]);
  return 2.0 * std::asin(std::min(1.0, chord / 2.0)) * 180.0 / kPi;
}
}  // namespace

std::optional<size_t> ContradictingRotation(const Fit& fit, size_t rotations) {
  if (rotations < 6 || fit.r_rotation.size() != 3 * rotations) return std::nullopt;
  std::vector<double> angles(rotations);
  for (size_t i = 0; i < rotations; ++i) angles[i] = RotationAngleDeg(fit, i);
  std::vector<double> sorted = angles;
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(rotations / 2),
                   sorted.end());
  const double sigma = sorted[rotations / 2] / 1.1774;  // Rayleigh median = sqrt(2 ln 2) sigma
  const size_t worst =
      static_cast<size_t>(std::max_element(angles.begin(), angles.end()) - angles.begin());
  if (angles[worst] > std::max(6.0 * sigma, 1.0)) return worst;
  return std::nullopt;
}

std::string ExcludeRotation(size_t index, const Fit& fit, TagProblemData* d,
                            std::vector<Segment>* segments, int sensor) {
  const Segment* gone = d->rotation_segments[index];
  const double angle = RotationAngleDeg(fit, index);
  std::string note = fmt::format(
      "excluded: after this rotation gravity is {:.2f} deg away from where the integrated "
      "gyroscope puts it (the other rotations: {:.2f} deg rms); an orientation change the "
      "gyroscope did not see (the tag re-seated), a knock or a burst",
      angle, [&] {
        double ss = 0;
        size_t n = 0;
        for (size_t i = 0; i < d->rotations.size(); ++i) {
          if (i == index) continue;
          const double a = RotationAngleDeg(fit, i);
          ss += a * a;
          ++n;
        }
        return n > 0 ? std::sqrt(ss / static_cast<double>(n)) : 0.0;
      }());
  for (Segment& s : *segments) {
    if (s.piece == gone->piece && s.begin == gone->begin && s.kind == gone->kind) {
      s.used = false;
      s.note = note;
    }
  }
  const std::string warning =
      fmt::format("sensor {}: input {}, rotation t = {:.2f} .. {:.2f} s {}", sensor,
                  gone->piece + 1, gone->start_s, gone->end_s, note);
  d->rotations.erase(d->rotations.begin() + static_cast<std::ptrdiff_t>(index));
  d->rotation_segments.erase(d->rotation_segments.begin() + static_cast<std::ptrdiff_t>(index));
  return warning;
}

namespace {

// cov_g += S cov_a S^T, S = -(G_g^T G_g)^-1 G_g^T G_a.
void AddAccelShare(const Eigen::MatrixXd& gg, const Eigen::MatrixXd& ga,
                   const Eigen::MatrixXd& cov_a, Eigen::MatrixXd* cov_g) {
  const Eigen::MatrixXd sens = -(gg.transpose() * gg).ldlt().solve(gg.transpose() * ga);
  *cov_g += sens * cov_a * sens.transpose();
}

}  // namespace

Status PropagateAccelUncertainty(ceres::Problem* gyro_problem,
                                 const std::vector<double*>& gyro_free, int pg,
                                 const SensorSolution& accel, Eigen::MatrixXd* cov_g) {
  // With the whitened Jacobians G_g (gyro parameters) and G_a (accel parameters) of the
  // gyroscope residuals, the gyro solution moves by S da, S = -(G_g^T G_g)^-1 G_g^T G_a
  // (implicit function theorem), so cov_g += S cov_a S^T (JCGM 100:2008 5.2, correlated
  // inputs).
  std::vector<double*> accel_in_gyro;
  for (double* b : accel.free_blocks) {
    if (gyro_problem->HasParameterBlock(b)) accel_in_gyro.push_back(b);
  }
  if (accel_in_gyro.empty() || accel_in_gyro.size() != accel.free_blocks.size()) {
    return Status::Ok();
  }
  for (double* b : accel_in_gyro) gyro_problem->SetParameterBlockVariable(b);
  std::vector<double*> all = gyro_free;
  all.insert(all.end(), accel_in_gyro.begin(), accel_in_gyro.end());
  std::optional<Eigen::MatrixXd> j = DenseJacobian(gyro_problem, all);
  for (double* b : accel_in_gyro) gyro_problem->SetParameterBlockConstant(b);
  if (!j) return MakeFailedError("could not evaluate the gyroscope Jacobian at the solution");
  AddAccelShare(j->leftCols(pg), j->rightCols(accel.parameters), accel.covariance, cov_g);
  return Status::Ok();
}

Result<SensorSolution> SolveGyro(const TagProblemData& d, const CalibrationOptions& o, int sensor,
                                 const SensorSolution& accel, ParameterBlocks* x, Fit* fit) {
  SensorSolution out;
  out.parameters = PB::FreeCount(ImuSensor::kGyro, o.gyro_model, d.temperature);
  const int pg = out.parameters;
  // Twice, re-weighting the groups; with a robust loss the later passes use it, so that the
  // groups' robust scatter comes from a fit that outliers did not drag (three passes).
  const bool robust = o.loss != LossKind::kTrivial;
  for (int pass = 0; pass < (robust ? 3 : 2); ++pass) {
    std::vector<double*> free_blocks;
    int m_gyro = 0;
    Status s = SolveStage(pass > 0 && robust ? Stage::kGyroFinal : Stage::kGyro, d, o, x, fit,
                          nullptr, &free_blocks, &m_gyro);
    if (!s.ok()) return s.error();
    const double ratio = static_cast<double>(m_gyro - pg) / static_cast<double>(m_gyro);
    fit->s_static = GroupSigma(fit->r_static, ratio, robust);
    if (!fit->r_table.empty()) fit->s_table = GroupSigma(fit->r_table, ratio, robust);
    if (!fit->r_rotation.empty()) {
      // 2 degrees of freedom per 3 components (see SolveStage).
      fit->s_rotation = GroupSigma(fit->r_rotation, ratio * 2.0 / 3.0, robust);
    }
  }
  // Final: whitened, with the accelerometer held ...
  out.problem = std::make_shared<ceres::Problem>();
  ceres::Problem& problem = *out.problem;
  Status s =
      SolveStage(Stage::kGyroFinal, d, o, x, fit, &problem, &out.free_blocks, &out.residuals);
  if (!s.ok()) return s.error();
  // ... its whitened Jacobian over the free blocks and, when the problem holds them all
  // (rotations), over the accelerometer's free blocks: evaluated once each for the rank, the
  // covariance and the chi-square below (each apart, as the gyroscope's own with the
  // accelerometer held: the rotations' value then comes from the accelerometer's plain
  // directions, not its jets, and the chi-square stays the same to the last digit) ...
  std::optional<Eigen::MatrixXd> jac = DenseJacobian(&problem, out.free_blocks);
  if (!jac || jac->cols() != pg) {
    return MakeFailedError("could not evaluate the Jacobian at the solution")
        .WithContext(fmt::format("sensor {}", sensor));
  }
  out.jacobian_free = std::move(*jac);
  std::vector<double*> held;
  for (double* b : accel.free_blocks) {
    if (problem.HasParameterBlock(b)) held.push_back(b);
  }
  if (!held.empty() && held.size() == accel.free_blocks.size()) {
    for (double* b : held) problem.SetParameterBlockVariable(b);
    std::optional<Eigen::MatrixXd> ga = DenseJacobian(&problem, held);
    for (double* b : held) problem.SetParameterBlockConstant(b);
    if (ga && ga->rows() == out.jacobian_free.rows()) out.jacobian_accel = std::move(*ga);
  }
  // ... rank, residual variance, the covariance for the comparison and CheckDetermined ...
  Status rank = CheckRankOf(out.jacobian_free,
                            QualifiedFreeNames(ImuSensor::kGyro, o.gyro_model, d.temperature));
  if (!rank.ok()) return rank.error().WithContext(fmt::format("sensor {}", sensor));
  out.s2 = ResidualVariance(&problem, pg, out.residuals, robust ? o.loss_scale : 0.0);
  out.reduced_chi2 = out.s2;
  Result<Eigen::MatrixXd> cov = DenseSvdCovariance(out.jacobian_free, out.s2);
  if (!cov.ok()) return cov.error().WithContext(fmt::format("sensor {}", sensor));
  out.covariance = std::move(cov).value();
  out.complete = false;
  // ... the residuals against the noise ...
  if (!robust) {
    Status chi2 = GyroNoiseChiSquare(d, *x, o, sensor, *fit, accel, &out);
    if (!chi2.ok()) return chi2.error();
  }
  // ... plus the accelerometer's uncertainty carried by the rotations (as
  // PropagateAccelUncertainty, from these Jacobians).
  if (out.jacobian_accel.cols() == accel.covariance.rows() && out.jacobian_accel.size() > 0) {
    AddAccelShare(out.jacobian_free, out.jacobian_accel, accel.covariance, &out.covariance);
  }
  return out;
}

Status CompleteGyroUncertainty(const CalibrationOptions& o, int sensor, const SensorSolution& accel,
                               ParameterBlocks* x, SensorSolution* s) {
  if (s->complete) return Status::Ok();
  METRO_CHECK(s->problem != nullptr);
  ceres::Problem& problem = *s->problem;
  const int pg = s->parameters;
  Result<Eigen::MatrixXd> cov = CeresCovariance(&problem, s->free_blocks, pg, s->s2);
  if (!cov.ok()) return cov.error().WithContext(fmt::format("sensor {}", sensor));
  s->covariance = std::move(cov).value();
  if (o.accel_model != ModelKind::kFull || o.gyro_model != ModelKind::kFull) {
    // How the solution moves with the cross-axis terms the models hold at 0 (issue #36):
    // the gyroscope's own directly; the accelerometer's through the gravity directions of the
    // rotations and through the accelerometer's constants, d theta_g / d m_a =
    // -(G_g^T G_g)^-1 G_g^T (G_a d theta_a / d m_a + G_m_a).
    const Eigen::Index pa = static_cast<Eigen::Index>(accel.parameters);
    double* accel_m = x->Get(ImuSensor::kAccel, PB::kMisalignment);
    double* gyro_m = x->Get(ImuSensor::kGyro, PB::kMisalignment);
    bool with_accel = o.accel_model != ModelKind::kFull && problem.HasParameterBlock(accel_m) &&
                      accel.cross_axis_sensitivity.rows() == pa &&
                      accel.cross_axis_sensitivity.cols() == 3;
    for (double* b : accel.free_blocks) with_accel = with_accel && problem.HasParameterBlock(b);
    std::vector<double*> extra;
    if (with_accel) {
      extra = accel.free_blocks;
      extra.push_back(accel_m);
    }
    const bool with_gyro = o.gyro_model != ModelKind::kFull && problem.HasParameterBlock(gyro_m);
    if (with_gyro) extra.push_back(gyro_m);
    Eigen::MatrixXd sens = Eigen::MatrixXd::Zero(pg, 9);
    if (!extra.empty()) {
      std::optional<Eigen::MatrixXd> s_m = HeldTermSensitivity(&problem, s->free_blocks, pg, extra);
      if (s_m) {
        Eigen::Index col = 0;
        if (with_accel) {
          sens.leftCols(3) =
              s_m->middleCols(col, pa) * accel.cross_axis_sensitivity + s_m->middleCols(pa, 3);
          col = pa + 3;
        }
        if (with_gyro) sens.rightCols(6) = s_m->middleCols(col, 6);
      }
    }
    s->cross_axis_sensitivity = std::move(sens);
  }
  Status pr = PropagateAccelUncertainty(&problem, s->free_blocks, pg, accel, &s->covariance);
  if (!pr.ok()) return pr.error();
  s->complete = true;
  s->problem.reset();
  s->jacobian_free.resize(0, 0);
  s->jacobian_accel.resize(0, 0);
  return Status::Ok();
}

// ---- Assembly ---------------------------------------------------------------------------

void Unscale(const Eigen::Vector3d& ref, ImuSensor sensor, ModelKind kind, bool temperature,
             ParameterBlocks* x, Eigen::MatrixXd* cov) {
  double* b = x->Get(sensor, PB::kBias);
  double* k = x->Get(sensor, PB::kScale);
  double* b1 = x->Get(sensor, PB::kBiasPerC);
  for (int a = 0; a < 3; ++a) {
    b[a] /= ref[a];
    k[a] *= ref[a];
    b1[a] /= ref[a];
  }
  // D in FreeNames order.
  std::vector<double> dvec;
  for (int r = 0; r < PB::kRoleCount; ++r) {
    const PB::Role role = static_cast<PB::Role>(r);
    if (!PB::IsFree(role, kind, temperature)) continue;
    for (int a = 0; a < PB::Size(sensor, role); ++a) {
      switch (role) {
        case PB::kBias:
        case PB::kBiasPerC:
          dvec.push_back(1.0 / ref[a]);
          break;
        case PB::kScale:
          dvec.push_back(ref[a]);
          break;
        case PB::kMisalignment:
          dvec.push_back(1.0);
          break;
      }
    }
  }
  METRO_CHECK(static_cast<Eigen::Index>(dvec.size()) == cov->rows());
  const Eigen::VectorXd dd =
      Eigen::Map<Eigen::VectorXd>(dvec.data(), static_cast<Eigen::Index>(dvec.size()));
  *cov = dd.asDiagonal() * (*cov) * dd.asDiagonal();
}

Eigen::Matrix3d MatrixFromFree(ImuSensor sensor, ModelKind kind, const double* k_fixed,
                               const Eigen::VectorXd& free) {
  double k[3] = {k_fixed[0], k_fixed[1], k_fixed[2]};
  double m[6] = {0, 0, 0, 0, 0, 0};
  // The temperature term does not enter M; it comes last, so it moves no offset.
  const int k_at = PB::FreeOffset(sensor, kind, false, PB::kScale);
  const int m_at = PB::FreeOffset(sensor, kind, false, PB::kMisalignment);
  if (k_at >= 0) {
    for (int i = 0; i < 3; ++i) k[i] = free[k_at + i];
  }
  if (m_at >= 0) {
    for (int i = 0; i < PB::Size(sensor, PB::kMisalignment); ++i) m[i] = free[m_at + i];
  }
  return MisalignmentMatrix(sensor, m) * Eigen::Vector3d(k[0], k[1], k[2]).asDiagonal();
}

SensorCalibration MakeSensorCalibration(ImuSensor sensor, ModelKind kind, bool temperature,
                                        double t_ref_c, const std::string& input_unit,
                                        const ParameterBlocks& x, const Eigen::MatrixXd& cov) {
  const double* b = x.Get(sensor, PB::kBias);
  const double* k = x.Get(sensor, PB::kScale);
  const double* m = x.Get(sensor, PB::kMisalignment);
  const double* b1 = x.Get(sensor, PB::kBiasPerC);
  SensorCalibration c;
  SensorModel& mo = c.model;
  mo.sensor = sensor;
  mo.kind = kind;
  mo.input_unit = input_unit;
  mo.output_unit = std::string(OutputUnit(sensor).symbol);
  mo.bias = Eigen::Vector3d(b[0], b[1], b[2]);
  mo.scale = Eigen::Vector3d(k[0], k[1], k[2]);
  mo.misalignment.assign(m, m + PB::Size(sensor, PB::kMisalignment));
  mo.has_temperature = temperature;
  if (temperature) {
    mo.bias_per_c = Eigen::Vector3d(b1[0], b1[1], b1[2]);
    mo.t_ref_c = t_ref_c;
  }
  c.parameter_names = PB::FreeNames(sensor, kind, temperature);
  c.covariance = cov;
  DeriveUncertainties(&c);
  return c;
}

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
  return MakeFailedError(fmt::format(
      "sensor {}: degenerate calibration: the data do not determine {}; the uncertainty is as "
      "large as the datasheet tolerance. Collect more distinct poses (every axis up and down, "
      "the corners and edges of a cube) and rotations about every axis, or use a simpler --model",
      sensor_number, list));
}

Result<SensorCalibration> AssembleAccel(const TagProblemData& d, const ParameterBlocks& x,
                                        const SensorSolution& solution, const Fit& fit,
                                        const TemperatureDecision& temperature,
                                        const std::string& accel_unit, const CalibrationOptions& o,
                                        int sensor) {
  SensorCalibration accel = MakeSensorCalibration(ImuSensor::kAccel, o.accel_model, d.temperature,
                                                  d.t_ref_c, accel_unit, x, solution.covariance);
  accel.dof = solution.dof >= 0 ? solution.dof : solution.residuals - solution.parameters;
  accel.reduced_chi2 = solution.reduced_chi2;
  // u from the poses' noise alone (hundreds of samples each): the normal 1.96 (JCGM 100:2008
  // G.6.6); with a between-orientation component, Student t with C - p degrees of freedom.
  accel.coverage_factor_95 = solution.u_from_noise ? 1.959963984540054 : StudentT975(accel.dof);
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
  Status det = CheckDetermined(accel, sensor);
  if (!det.ok()) return det.error();
  accel.static_pose_temperature = temperature.pose_range;
  return accel;
}

Result<SensorCalibration> AssembleGyro(const TagProblemData& d, const ParameterBlocks& x,
                                       const SensorSolution& solution, const Fit& fit,
                                       const TemperatureDecision& temperature,
                                       const std::string& gyro_unit, const CalibrationOptions& o,
                                       int sensor) {
  SensorCalibration gyro = MakeSensorCalibration(ImuSensor::kGyro, o.gyro_model, d.temperature,
                                                 d.t_ref_c, gyro_unit, x, solution.covariance);
  gyro.dof = solution.residuals - solution.parameters;
  gyro.reduced_chi2 = solution.reduced_chi2;
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
  for (size_t i = 0; 3 * i + 2 < fit.r_rotation.size(); ++i) {
    angles_deg.push_back(RotationAngleDeg(fit, i));
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
  Status det = CheckDetermined(gyro, sensor);
  if (!det.ok()) return det.error();
  gyro.static_pose_temperature = temperature.pose_range;
  return gyro;
}

double StudentT975(int dof) {
  if (dof < 1) return 0;
  boost::math::students_t dist(static_cast<double>(dof));
  return boost::math::quantile(dist, 0.975);
}

}  // namespace metro::calibration_internal
