// The calibration against the noise of the data (issue #23): the accelerometer's covariance
// from each pose's noise and the distinct orientations, and the gyroscope's residuals measured
// against the noise of its static poses, table runs and integrated rotations
// (calibrate_stages.hpp).
//
// HonestAccelCovariance runs these stages, in this order:
//
//   pose noise    PoseNoiseAlongGravity     each static pose's noise along gravity
//   orientations  OrientationClusters       the distinct orientations (degenerate: refused)
//   residuals     SplitResidualNoise        chi-square, within-orientation factor f, tau^2
//   covariance    SandwichCovariance,       the sandwich covariance, dof, and the warning
//                 WarnOnAccelChiSquare
//
// GyroNoiseChiSquare runs these stages, in this order:
//
//   pose noise  MeasurePoseNoise          each static pose's rate noise and gravity direction
//   system      StaticAndTableRows,       residuals, Jacobian and noise covariance row by
//               RotationRows,             row: static poses, table runs, rotations (with the
//               SharedDirectionNoise,     pose directions they share and the accelerometer's
//               AccelParameterNoise       parameter error)
//   chi-square  GlsChiSquare              the generalized least-squares chi-square, its
//                                         groups' shares and the warning
#include <ceres/ceres.h>
#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <boost/math/distributions/chi_squared.hpp>
#include <cmath>
#include <optional>

#include "calibration/calibrate_stages.hpp"
#include "calibration/residuals.hpp"

namespace metro::calibration_internal {

namespace {

constexpr double kPi = 3.14159265358979323846;
using PB = ParameterBlocks;

// Noise of a segment's mean of `samples` (times `ref` per axis) along the unit direction u:
// sample variance times (1 + rho) / (1 - rho) / n, rho the lag-1 autocorrelation clamped to
// [0, 0.9] (AR(1) effective sample size); saturated samples are left out. 0 when it cannot
// be measured (fewer than 3 samples, or every sample alike).
double SegmentMeanNoise(const std::vector<Eigen::Vector3d>& samples,
                        const std::vector<unsigned char>& saturated, const Segment& s,
                        const Eigen::Vector3d& ref, const Eigen::Vector3d& u) {
  std::vector<double> z;
  for (size_t i = s.begin; i < s.end; ++i) {
    if (saturated[i]) continue;
    z.push_back(u.dot(ref.cwiseProduct(samples[i])));
  }
  const size_t n = z.size();
  if (n < 3) return 0.0;
  double mean = 0;
  for (double v : z) mean += v;
  mean /= static_cast<double>(n);
  double c0 = 0, c1 = 0;
  for (size_t i = 0; i < n; ++i) {
    c0 += (z[i] - mean) * (z[i] - mean);
    if (i + 1 < n) c1 += (z[i] - mean) * (z[i + 1] - mean);
  }
  if (!(c0 > 0)) return 0.0;
  const double rho = std::clamp(c1 / c0, 0.0, 0.9);
  const double var = c0 / static_cast<double>(n - 1);
  return std::sqrt(var / static_cast<double>(n) * (1 + rho) / (1 - rho));
}

double PoseMeanNoise(const Record& r, const Segment& s, const Eigen::Vector3d& ref,
                     const Eigen::Vector3d& u) {
  return SegmentMeanNoise(r.accel, r.saturated, s, ref, u);
}

}  // namespace

namespace {

// ---- the accelerometer's covariance -------------------------------------------------------

// The noise (*sigma) and gravity direction (*dir) of each static pose; false, with a warning,
// when a pose shows no noise along gravity.
bool PoseNoiseAlongGravity(const TagProblemData& d, const ParameterBlocks& x, int sensor,
                           std::vector<double>* sigma, std::vector<Eigen::Vector3d>* dir,
                           SensorSolution* solution) {
  const size_t m = d.statics.size();
  const double* b = x.Get(ImuSensor::kAccel, PB::kBias);
  const Eigen::Vector3d bias(b[0], b[1], b[2]);
  sigma->resize(m);
  dir->resize(m);
  for (size_t i = 0; i < m; ++i) {
    const Pose& pose = d.statics[i];
    const Eigen::Vector3d v = d.accel_ref.cwiseProduct(pose.accel) - bias;
    (*dir)[i] = v.normalized();
    (*sigma)[i] = PoseMeanNoise(d.records[static_cast<size_t>(pose.record)], *pose.segment,
                                d.accel_ref, (*dir)[i]);
    if (!((*sigma)[i] > 0)) {
      // Every sample of the pose alike (quantised data, or fewer than 3): no noise to rest u
      // on; the covariance scaled by the residuals stays, and says so.
      solution->warnings.push_back(fmt::format(
          "sensor {}: static pose {} (t = {:.2f} .. {:.2f} s) shows no noise along gravity; the "
          "accelerometer's u is scaled by the residuals' own scatter, not by the poses' noise "
          "and orientations",
          sensor, i + 1, pose.segment->start_s, pose.segment->end_s));
      return false;
    }
  }
  return true;
}

// Orientation clusters (greedy, in pose order): each pose's cluster; *count of them.
std::vector<int> OrientationClusters(const TagProblemData& d,
                                     const std::vector<Eigen::Vector3d>& dir, int* count) {
  const size_t m = dir.size();
  const double cos_same = std::cos(kSameOrientationDeg * kPi / 180.0);
  std::vector<int> cluster(m, -1);
  std::vector<size_t> first_of;
  for (size_t i = 0; i < m; ++i) {
    for (size_t c = 0; c < first_of.size(); ++c) {
      const size_t j = first_of[c];
      const bool same_temp =
          !d.temperature || std::abs(d.statics[i].temp_c - d.statics[j].temp_c) < 1.0;
      if (dir[i].dot(dir[j]) >= cos_same && same_temp) {
        cluster[i] = static_cast<int>(c);
        break;
      }
    }
    if (cluster[i] < 0) {
      cluster[i] = static_cast<int>(first_of.size());
      first_of.push_back(i);
    }
  }
  *count = static_cast<int>(first_of.size());
  return cluster;
}

// The residuals against the noise: all of them (chi2_all), the within-orientation scatter
// factor f and the between-orientation variance tau^2 (method of moments).
struct ResidualNoise {
  double chi2_all = 0;
  double f = 1.0;
  double tau2 = 0;
};

ResidualNoise SplitResidualNoise(const Fit& fit, const std::vector<double>& sigma,
                                 const std::vector<int>& cluster, int clusters, int p) {
  const size_t m = sigma.size();
  // Within-cluster excess and between-orientation variance (method of moments).
  std::vector<double> sum_r(static_cast<size_t>(clusters), 0.0), sum_s2(sum_r), count(sum_r);
  for (size_t i = 0; i < m; ++i) {
    const size_t c = static_cast<size_t>(cluster[i]);
    sum_r[c] += fit.r_accel[i];
    sum_s2[c] += sigma[i] * sigma[i];
    count[c] += 1;
  }
  double chi2_within = 0, chi2_all = 0;
  for (size_t i = 0; i < m; ++i) {
    const size_t c = static_cast<size_t>(cluster[i]);
    const double e = fit.r_accel[i] - sum_r[c] / count[c];
    chi2_within += e * e / (sigma[i] * sigma[i]);
    chi2_all += fit.r_accel[i] * fit.r_accel[i] / (sigma[i] * sigma[i]);
  }
  const int dof_within = static_cast<int>(m) - clusters;
  const double f = dof_within >= 3 ? std::max(1.0, chi2_within / dof_within) : 1.0;
  double between = 0, noise_of_means = 0;
  for (size_t c = 0; c < static_cast<size_t>(clusters); ++c) {
    const double mean = sum_r[c] / count[c];
    between += mean * mean;
    noise_of_means += f * sum_s2[c] / (count[c] * count[c]);
  }
  // tau^2 only when the cluster means are significantly larger than their noise (their
  // chi-square above its 95 % quantile with C - p degrees of freedom); with C = p the model
  // cannot be checked and u rests on the noise alone (a warning says so).
  double chi2_between = 0;
  for (size_t c = 0; c < static_cast<size_t>(clusters); ++c) {
    const double mean = sum_r[c] / count[c];
    chi2_between += mean * mean / (f * sum_s2[c] / (count[c] * count[c]));
  }
  double tau2 = 0;
  if (clusters > p &&
      chi2_between > boost::math::quantile(boost::math::chi_squared(clusters - p), 0.95)) {
    tau2 = std::max(
        0.0, (between * clusters / static_cast<double>(clusters - p) - noise_of_means) / clusters);
  }
  return {chi2_all, f, tau2};
}

// Sandwich covariance over the free parameters (unwhitened Jacobian j): nothing when it
// cannot be formed.
std::optional<Eigen::MatrixXd> SandwichCovariance(const Eigen::MatrixXd& j,
                                                  const std::vector<double>& sigma,
                                                  const std::vector<int>& cluster,
                                                  const ResidualNoise& noise) {
  const size_t m = sigma.size();
  const double f = noise.f, tau2 = noise.tau2;
  Eigen::MatrixXd v =
      Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(m), static_cast<Eigen::Index>(m));
  for (size_t a = 0; a < m; ++a) {
    for (size_t bb = 0; bb < m; ++bb) {
      double e = cluster[a] == cluster[bb] ? tau2 : 0.0;
      if (a == bb) e += f * sigma[a] * sigma[a];
      v(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(bb)) = e;
    }
  }
  const Eigen::MatrixXd jtj = j.transpose() * j;
  const Eigen::MatrixXd a_inv = jtj.ldlt().solve(Eigen::MatrixXd::Identity(jtj.rows(), jtj.cols()));
  const Eigen::MatrixXd cov = a_inv * j.transpose() * v * j * a_inv;
  if (!cov.allFinite()) return std::nullopt;
  return cov;
}

// The residuals beyond their noise's 99 % limit: said, with what u includes.
void WarnOnAccelChiSquare(const CalibrationOptions& o, int sensor, size_t m, int clusters, int dof,
                          const ResidualNoise& noise, SensorSolution* solution) {
  if (dof <= 0) return;
  const double f = noise.f, tau2 = noise.tau2;
  const boost::math::chi_squared dist(dof);
  if (noise.chi2_all > boost::math::quantile(dist, 0.99)) {
    solution->warnings.push_back(fmt::format(
        "sensor {}: the accelerometer residuals are {:.3g} times their noise (reduced "
        "chi-square {:.3g} over {} poses in {} orientations, 99 % limit {:.3g}): the '{}' model "
        "does not describe the data to its noise, or poses were disturbed; u includes a "
        "between-orientation component of {:.3g} mg{}",
        sensor, std::sqrt(solution->reduced_chi2), solution->reduced_chi2, m, clusters,
        boost::math::quantile(dist, 0.99) / dof, ModelKindName(o.accel_model),
        1000.0 * std::sqrt(tau2),
        f > 1.0 ? fmt::format(" and scatter within orientations "
                              "{:.3g} times the noise",
                              std::sqrt(f))
                : std::string()));
  }
}

}  // namespace

Status HonestAccelCovariance(const TagProblemData& d, const ParameterBlocks& x,
                             const CalibrationOptions& o, int sensor, const Fit& fit,
                             ceres::Problem* problem, SensorSolution* solution) {
  const size_t m = d.statics.size();
  const int p = solution->parameters;
  if (fit.r_accel.size() != m || m == 0) return Status::Ok();
  std::vector<double> sigma;
  std::vector<Eigen::Vector3d> dir;
  if (!PoseNoiseAlongGravity(d, x, sensor, &sigma, &dir, solution)) return Status::Ok();
  int clusters = 0;
  const std::vector<int> cluster = OrientationClusters(d, dir, &clusters);
  if (clusters < p) {
    return MakeFailedError(fmt::format(
        "sensor {}: degenerate calibration: the {} static poses hold {} distinct orientations "
        "(gravity directions more than {} deg apart); the accelerometer '{}' model{} has {} "
        "parameters, and repeated stops at one orientation do not determine more constants. Add "
        "poses in new orientations (the corners and edges of a cube), or use a simpler --model",
        sensor, m, clusters, kSameOrientationDeg, ModelKindName(o.accel_model),
        d.temperature ? " with temperature term" : "", p));
  }
  const ResidualNoise noise = SplitResidualNoise(fit, sigma, cluster, clusters, p);
  // The residuals against the noise, for the model comparisons (issue #36).
  solution->chi2 = noise.chi2_all;
  solution->chi2_dof = static_cast<double>(static_cast<int>(m) - p);
  solution->orientations = clusters;
  if (clusters == p) {
    solution->warnings.push_back(fmt::format(
        "sensor {}: the accelerometer '{}' model has as many parameters as the {} distinct "
        "orientations: the fit is exact and cannot show whether the model describes the data; "
        "u comes from the noise of the poses alone",
        sensor, ModelKindName(o.accel_model), clusters));
  }
  std::optional<Eigen::MatrixXd> jw = DenseJacobian(problem, solution->free_blocks);
  if (!jw || jw->rows() != static_cast<Eigen::Index>(m)) return Status::Ok();
  const std::optional<Eigen::MatrixXd> cov =
      SandwichCovariance(*jw * fit.s_accel, sigma, cluster, noise);
  if (!cov) return Status::Ok();
  solution->covariance = 0.5 * (*cov + cov->transpose());
  const int dof = static_cast<int>(m) - p;
  solution->reduced_chi2 = dof > 0 ? noise.chi2_all / dof : 0.0;
  solution->dof = noise.tau2 > 0 ? clusters - p : std::max(dof, 0);
  solution->u_from_noise = noise.tau2 == 0;
  WarnOnAccelChiSquare(o, sensor, m, clusters, dof, noise, solution);
  return Status::Ok();
}

namespace {

// ---- pose noise ---------------------------------------------------------------------------

// Every sample alike (quantised data): no noise to measure the residuals against; said.
void WarnNoNoise(int sensor, const Segment& s, const char* what, SensorSolution* solution) {
  solution->warnings.push_back(
      fmt::format("sensor {}: the {} at t = {:.2f} .. {:.2f} s shows no measurable noise; the "
                  "gyroscope's reduced chi-square cannot be measured against the noise of the data",
                  sensor, what, s.start_s, s.end_s));
}

// The static poses' noise: of each mean rate per axis, the rate samples' long-run variance,
// and each gravity direction with its noise normal to gravity.
struct PoseNoise {
  std::vector<Eigen::Vector3d> rate_var;  // Per pose and axis.
  double long_run_dps2 = 0;               // Variance of the mean times n, averaged.
  std::vector<Eigen::Vector3d> dir;       // Gravity directions.
  std::vector<double> dir_var;            // rad^2 per in-plane axis.
};

// Nothing (with the warning) when a pose shows no noise.
std::optional<PoseNoise> MeasurePoseNoise(const TagProblemData& d, const ParameterBlocks& x,
                                          int sensor, SensorSolution* solution) {
  const size_t ns = d.statics.size();
  PoseNoise noise;
  std::vector<Eigen::Vector3d>& rate_var = noise.rate_var;
  rate_var.resize(ns);
  double long_run_dps2 = 0;
  for (size_t i = 0; i < ns; ++i) {
    const Pose& pose = d.statics[i];
    const Record& r = d.records[static_cast<size_t>(pose.record)];
    for (int a = 0; a < 3; ++a) {
      const double s = SegmentMeanNoise(r.gyro, r.saturated, *pose.segment, d.gyro_ref,
                                        Eigen::Vector3d::Unit(a));
      if (!(s > 0)) {
        WarnNoNoise(sensor, *pose.segment, "static pose", solution);
        return std::nullopt;
      }
      rate_var[i][a] = s * s;
      long_run_dps2 += s * s * static_cast<double>(pose.n);
    }
  }
  long_run_dps2 /= 3.0 * static_cast<double>(ns);
  noise.long_run_dps2 = long_run_dps2;
  // Gravity directions and their noise normal to gravity (rad^2 per in-plane axis).
  const double* ba = x.Get(ImuSensor::kAccel, PB::kBias);
  const Eigen::Vector3d accel_bias(ba[0], ba[1], ba[2]);
  std::vector<Eigen::Vector3d>& dir = noise.dir;
  std::vector<double>& dir_var = noise.dir_var;
  dir.resize(ns);
  dir_var.resize(ns);
  for (size_t i = 0; i < ns; ++i) {
    const Pose& pose = d.statics[i];
    const Eigen::Vector3d v = d.accel_ref.cwiseProduct(pose.accel) - accel_bias;
    dir[i] = v.normalized();
    const Eigen::Vector3d e1 = dir[i].unitOrthogonal(), e2 = dir[i].cross(e1);
    const Record& r = d.records[static_cast<size_t>(pose.record)];
    const double n1 = PoseMeanNoise(r, *pose.segment, d.accel_ref, e1);
    const double n2 = PoseMeanNoise(r, *pose.segment, d.accel_ref, e2);
    if (!(n1 > 0) || !(n2 > 0)) {
      WarnNoNoise(sensor, *pose.segment, "static pose", solution);
      return std::nullopt;
    }
    dir_var[i] = 0.5 * (n1 * n1 + n2 * n2) / v.squaredNorm();
  }
  return noise;
}

// ---- the system ---------------------------------------------------------------------------

// The residuals r, their Jacobian j and the noise's covariance s. Rows: 3 per static pose,
// 1 per table run, 2 per rotation (projected on E_r, an orthonormal basis of the plane
// normal to gravity at the rotation's end pose).
struct NoiseSystem {
  Eigen::Index m3 = 0, mt = 0, mr = 0, mp = 0, p = 0;
  Eigen::MatrixXd j;
  Eigen::VectorXd r;
  Eigen::MatrixXd s;
  std::vector<Eigen::Matrix<double, 3, 2>> basis;  // E_r per rotation.
  std::vector<Eigen::Matrix3d> carry;              // M_a per rotation.
};

// The static and table rows; false (with the warning) when a table run shows no noise.
bool StaticAndTableRows(const TagProblemData& d, const ParameterBlocks& x, int sensor,
                        const Fit& fit, const PoseNoise& noise, const Eigen::MatrixXd& jw,
                        NoiseSystem* sys, SensorSolution* solution) {
  Eigen::MatrixXd& j = sys->j;
  Eigen::VectorXd& r = sys->r;
  Eigen::MatrixXd& s = sys->s;
  for (size_t i = 0; i < d.statics.size(); ++i) {
    for (int a = 0; a < 3; ++a) {
      const Eigen::Index row = static_cast<Eigen::Index>(3 * i) + a;
      j.row(row) = jw.row(row) * fit.s_static;
      r(row) = fit.r_static[3 * i + static_cast<size_t>(a)];
      s(row, row) = noise.rate_var[i][a];
    }
  }
  const double* bg = x.Get(ImuSensor::kGyro, PB::kBias);
  const Eigen::Vector3d gyro_bias(bg[0], bg[1], bg[2]);
  for (size_t t = 0; t < d.tables.size(); ++t) {
    const Pose& pose = d.tables[t];
    const Record& rec = d.records[static_cast<size_t>(pose.record)];
    const Eigen::Vector3d along = (d.gyro_ref.cwiseProduct(pose.gyro) - gyro_bias).normalized();
    const double sd = SegmentMeanNoise(rec.gyro, rec.saturated, *pose.segment, d.gyro_ref, along);
    if (!(sd > 0)) {
      WarnNoNoise(sensor, *pose.segment, "table run", solution);
      return false;
    }
    const Eigen::Index row = sys->m3 + static_cast<Eigen::Index>(t);
    j.row(row) = jw.row(row) * fit.s_table;
    r(row) = fit.r_table[t];
    s(row, row) = sd * sd;
  }
  return true;
}

// The rotation rows and their own noise; false when a rotation lacks a pose.
// Rotation a: d_a = M_a du_i - du_j + [v]x dphi (M_a = R^T at the solution, v = M_a u_i).
bool RotationRows(const TagProblemData& d, const ParameterBlocks& x, const Fit& fit,
                  const PoseNoise& noise, const Eigen::MatrixXd& jw, NoiseSystem* sys) {
  const size_t nr = d.rotations.size();
  const Eigen::Index m3 = sys->m3, mt = sys->mt;
  const std::vector<Eigen::Vector3d>& dir = noise.dir;
  const std::array<const double*, PB::kBlockCount> all = x.AllConst();
  std::vector<Eigen::Matrix<double, 3, 2>>& basis = sys->basis;
  std::vector<Eigen::Matrix3d>& carry = sys->carry;
  basis.resize(nr);
  carry.resize(nr);
  for (size_t a = 0; a < nr; ++a) {
    const RotationData& rd = d.rotations[a];
    if (rd.pose_start < 0 || rd.pose_end < 0) return false;
    const Eigen::Vector3d& uj = dir[static_cast<size_t>(rd.pose_end)];
    basis[a].col(0) = uj.unitOrthogonal();
    basis[a].col(1) = uj.cross(basis[a].col(0));
    carry[a] = PredictionMatrix(rd, all.data());
    const Eigen::Index row3 = m3 + mt + static_cast<Eigen::Index>(3 * a);
    const Eigen::Index row = m3 + mt + static_cast<Eigen::Index>(2 * a);
    sys->j.middleRows(row, 2) = basis[a].transpose() * jw.middleRows(row3, 3) * fit.s_rotation;
    const Eigen::Vector3d res(fit.r_rotation[3 * a], fit.r_rotation[3 * a + 1],
                              fit.r_rotation[3 * a + 2]);
    sys->r.segment(row, 2) = basis[a].transpose() * res;
    double sum_dt2 = 0;
    for (double dt : rd.dt_s) sum_dt2 += dt * dt;
    const Eigen::Vector3d v = carry[a] * dir[static_cast<size_t>(rd.pose_start)];
    Eigen::Matrix3d skew;
    skew << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
    sys->s.block(row, row, 2, 2) += noise.long_run_dps2 * kRadPerDeg * kRadPerDeg * sum_dt2 *
                                    basis[a].transpose() * skew * skew.transpose() * basis[a];
  }
  return true;
}

// Pose direction noise shared between rotations (the end of one is the start of the next).
void SharedDirectionNoise(const TagProblemData& d, const PoseNoise& noise, NoiseSystem* sys) {
  const size_t nr = d.rotations.size();
  const Eigen::Index m3 = sys->m3, mt = sys->mt;
  const std::vector<Eigen::Matrix3d>& carry = sys->carry;
  const std::vector<Eigen::Matrix<double, 3, 2>>& basis = sys->basis;
  const auto terms = [&](size_t a) {
    const RotationData& rd = d.rotations[a];
    return std::array<std::pair<int, Eigen::Matrix3d>, 2>{
        std::pair{rd.pose_start, carry[a]}, std::pair{rd.pose_end, -Eigen::Matrix3d::Identity()}};
  };
  for (size_t a = 0; a < nr; ++a) {
    for (size_t b = 0; b < nr; ++b) {
      Eigen::Matrix3d c = Eigen::Matrix3d::Zero();
      for (const auto& [pa, ca] : terms(a)) {
        for (const auto& [pb, cb] : terms(b)) {
          if (pa != pb) continue;
          const Eigen::Vector3d& u = noise.dir[static_cast<size_t>(pa)];
          const Eigen::Matrix3d normal = Eigen::Matrix3d::Identity() - u * u.transpose();
          c += noise.dir_var[static_cast<size_t>(pa)] * ca * normal * cb.transpose();
        }
      }
      const Eigen::Index ra = m3 + mt + static_cast<Eigen::Index>(2 * a);
      const Eigen::Index rb = m3 + mt + static_cast<Eigen::Index>(2 * b);
      sys->s.block(ra, rb, 2, 2) += basis[a].transpose() * c * basis[b];
    }
  }
}

// The accelerometer's parameter error moves every gravity direction at once:
// + G_a cov_a G_a^T, G_a the rotations' Jacobian over the accelerometer's free parameters.
// (The final stage's Jacobian over the accelerometer's free blocks, SolveGyro; empty when the
// problem does not hold them all.)
void AccelParameterNoise(const Fit& fit, const SensorSolution& accel, const Eigen::MatrixXd& jw,
                         const Eigen::MatrixXd& ga, NoiseSystem* sys) {
  const size_t nr = sys->basis.size();
  const Eigen::Index m3 = sys->m3, mt = sys->mt, mr = sys->mr;
  if (nr > 0 && ga.size() > 0) {
    if (ga.rows() == jw.rows() && ga.cols() == accel.covariance.rows()) {
      Eigen::MatrixXd gp(mr, ga.cols());
      for (size_t a = 0; a < nr; ++a) {
        gp.middleRows(static_cast<Eigen::Index>(2 * a), 2) =
            sys->basis[a].transpose() *
            ga.middleRows(m3 + mt + static_cast<Eigen::Index>(3 * a), 3) * fit.s_rotation;
      }
      sys->s.block(m3 + mt, m3 + mt, mr, mr) += gp * accel.covariance * gp.transpose();
    }
  }
}

// ---- the chi-square -----------------------------------------------------------------------

// The chi-square is that of the generalized least-squares step from the solution in the
// noise's own metric S (block diagonal over the groups): delta = -A^-1 J^T S^-1 r with
// A = J^T S^-1 J, r_G = r + J delta, chi2 = r_G^T S^-1 r_G. For Gaussian noise of covariance
// S and a model linear near the solution it is chi-squared with m - p dof exactly (the
// Gauss-Markov theorem), and the difference of two nested models' chi-squares is
// chi-squared with the difference in p: the F and likelihood-ratio comparisons need that.
// (The fit's own residuals, weighted by the scalar W, are not: their quadratic form in S^-1
// is a weighted sum of chi-squares whose mean only was matched, and with 8 rotations the
// comparison then took the full gyroscope model on 11 of 100 tags without cross-axis terms
// at its 5 % level.) Each group's share: chi2_g = r_G,g^T S_gg^-1 r_G,g with expectation
// size_g - tr(S_gg^-1 J_g A^-1 J_g^T); they add up to m - p.
void GlsChiSquare(const NoiseSystem& sys, const CalibrationOptions& o, int sensor,
                  SensorSolution* solution) {
  const Eigen::MatrixXd& j = sys.j;
  const Eigen::VectorXd& r = sys.r;
  const Eigen::MatrixXd& s = sys.s;
  const Eigen::Index m3 = sys.m3, mt = sys.mt, mr = sys.mr, mp = sys.mp, p = sys.p;
  const Eigen::LDLT<Eigen::MatrixXd> s_ldlt(s);
  const Eigen::MatrixXd s_inv_j = s_ldlt.solve(j);
  const Eigen::LDLT<Eigen::MatrixXd> a_ldlt(j.transpose() * s_inv_j);
  if (s_ldlt.info() != Eigen::Success || a_ldlt.info() != Eigen::Success) return;
  const Eigen::VectorXd delta = -a_ldlt.solve(s_inv_j.transpose() * r);
  const Eigen::VectorXd r_gls = r + j * delta;
  const Eigen::MatrixXd a_inv = a_ldlt.solve(Eigen::MatrixXd::Identity(p, p));
  struct Group {
    const char* name;
    Eigen::Index begin, size;
    double chi2 = 0, expected = 0;
  };
  std::vector<Group> groups = {
      {"static poses", 0, m3}, {"table runs", m3, mt}, {"rotations", m3 + mt, mr}};
  double chi2 = 0, expected = 0;
  for (Group& g : groups) {
    if (g.size == 0) continue;
    const Eigen::LDLT<Eigen::MatrixXd> sgg(s.block(g.begin, g.begin, g.size, g.size));
    const Eigen::VectorXd rg = r_gls.segment(g.begin, g.size);
    const Eigen::MatrixXd jg = j.middleRows(g.begin, g.size);
    g.chi2 = rg.dot(sgg.solve(rg));
    g.expected = static_cast<double>(g.size) - sgg.solve(jg * a_inv * jg.transpose()).trace();
    if (!std::isfinite(g.chi2) || !std::isfinite(g.expected)) return;
    chi2 += g.chi2;
    expected += g.expected;
  }
  expected = static_cast<double>(mp - p);  // The groups' shares add up to it (to rounding).
  if (!(expected > 0)) return;
  solution->reduced_chi2 = chi2 / expected;
  solution->chi2 = chi2;
  solution->chi2_dof = expected;
  const boost::math::chi_squared law(expected);
  if (chi2 > boost::math::quantile(law, 0.99)) {
    std::string parts;
    for (const Group& g : groups) {
      if (g.size == 0 || !(g.expected > 0.5)) continue;  // A group the parameters absorb.
      parts += fmt::format("{}{} {:.3g}", parts.empty() ? "" : ", ", g.name, g.chi2 / g.expected);
    }
    solution->warnings.push_back(fmt::format(
        "sensor {}: the gyroscope residuals are {:.3g} times their noise (reduced chi-square "
        "{:.3g}: {}; 99 % limit {:.3g}): the '{}' model does not describe the data to its "
        "noise, the bias moved between poses, or the motion was disturbed; u is scaled by the "
        "residuals' scatter, which holds the excess",
        sensor, std::sqrt(solution->reduced_chi2), solution->reduced_chi2, parts,
        boost::math::quantile(law, 0.99) / expected, ModelKindName(o.gyro_model)));
  }
  return;
}

}  // namespace

Status GyroNoiseChiSquare(const TagProblemData& d, const ParameterBlocks& x,
                          const CalibrationOptions& o, int sensor, const Fit& fit,
                          const SensorSolution& accel, SensorSolution* solution) {
  const size_t ns = d.statics.size(), nt = d.tables.size(), nr = d.rotations.size();
  if (ns == 0 || fit.r_static.size() != 3 * ns || fit.r_table.size() != nt ||
      fit.r_rotation.size() != 3 * nr) {
    return Status::Ok();
  }
  const std::optional<PoseNoise> noise = MeasurePoseNoise(d, x, sensor, solution);
  if (!noise) return Status::Ok();
  NoiseSystem sys;
  sys.m3 = static_cast<Eigen::Index>(3 * ns);
  sys.mt = static_cast<Eigen::Index>(nt);
  sys.mr = static_cast<Eigen::Index>(2 * nr);
  sys.mp = sys.m3 + sys.mt + sys.mr;
  const Eigen::MatrixXd& jw = solution->jacobian_free;
  if (jw.rows() != sys.m3 + sys.mt + static_cast<Eigen::Index>(3 * nr)) return Status::Ok();
  sys.p = jw.cols();
  sys.j = Eigen::MatrixXd(sys.mp, sys.p);
  sys.r = Eigen::VectorXd(sys.mp);
  sys.s = Eigen::MatrixXd::Zero(sys.mp, sys.mp);
  if (!StaticAndTableRows(d, x, sensor, fit, *noise, jw, &sys, solution)) return Status::Ok();
  if (!RotationRows(d, x, fit, *noise, jw, &sys)) return Status::Ok();
  SharedDirectionNoise(d, *noise, &sys);
  AccelParameterNoise(fit, accel, jw, solution->jacobian_accel, &sys);
  GlsChiSquare(sys, o, sensor, solution);
  return Status::Ok();
}

}  // namespace metro::calibration_internal
