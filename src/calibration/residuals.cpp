#include "calibration/residuals.hpp"

#include <ceres/autodiff_cost_function.h>
#include <ceres/jet.h>
#include <ceres/rotation.h>
#include <ceres/sized_cost_function.h>

#include <cmath>

#include "calibration/parameter_blocks.hpp"

namespace metro::calibration_internal {
namespace {

using PB = ParameterBlocks;
constexpr auto kSize = PB::kSize;

// T K v for the accelerometer (3 misalignment terms, imu_model.hpp).
template <typename T>
void AccelApply(const T* k, const T* m, const T* v, T* out) {
  const T x = k[0] * v[0], y = k[1] * v[1], z = k[2] * v[2];
  out[0] = x - m[0] * y + m[1] * z;
  out[1] = y - m[2] * z;
  out[2] = z;
}

// T K v for the gyroscope (6 misalignment terms, imu_model.hpp).
template <typename T>
void GyroApply(const T* k, const T* m, const T* v, T* out) {
  const T x = k[0] * v[0], y = k[1] * v[1], z = k[2] * v[2];
  out[0] = x - m[0] * y + m[1] * z;
  out[1] = m[2] * x + y - m[3] * z;
  out[2] = -m[4] * x + m[5] * y + z;
}

template <typename T>
void AccelDirection(const T* b, const T* k, const T* m, const T* b1, const Eigen::Vector3d& raw,
                    double dtemp_c, T* u) {
  T v[3];
  for (int i = 0; i < 3; ++i) v[i] = raw[i] - b[i] - b1[i] * dtemp_c;
  T a[3];
  AccelApply(k, m, v, a);
  using std::sqrt;
  const T norm = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
  for (int i = 0; i < 3; ++i) u[i] = a[i] / norm;
}

// q = Exp(w_1 dt_1) * ... * Exp(w_n dt_n), w in rad/s.
template <typename T>
void IntegrateRotation(const RotationData& d, const T* b, const T* k, const T* m, const T* b1,
                       T* q) {
  q[0] = T(1);
  q[1] = T(0);
  q[2] = T(0);
  q[3] = T(0);
  for (size_t s = 0; s < d.gyro.size(); ++s) {
    T v[3];
    for (int i = 0; i < 3; ++i) v[i] = d.gyro[s][i] - b[i] - b1[i] * d.dtemp_c[s];
    T w[3];
    GyroApply(k, m, v, w);
    const double f = kRadPerDeg * d.dt_s[s];
    T rv[3] = {w[0] * f, w[1] * f, w[2] * f};
    T dq[4];
    ceres::AngleAxisToQuaternion(rv, dq);
    T out[4];
    ceres::QuaternionProduct(q, dq, out);
    for (int i = 0; i < 4; ++i) q[i] = out[i];
  }
}

// R(q)^T u: rotation by the conjugate (QuaternionRotatePoint normalises q).
template <typename T>
void RotateInverse(const T* q, const T* u, T* out) {
  const T qc[4] = {q[0], -q[1], -q[2], -q[3]};
  ceres::QuaternionRotatePoint(qc, u, out);
}

struct AccelNormFunctor {
  Eigen::Vector3d raw;
  double dtemp_c, target, weight;
  template <typename T>
  bool operator()(const T* b, const T* k, const T* m, const T* b1, T* r) const {
    T v[3];
    for (int i = 0; i < 3; ++i) v[i] = raw[i] - b[i] - b1[i] * dtemp_c;
    T a[3];
    AccelApply(k, m, v, a);
    using std::sqrt;
    r[0] = weight * (sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]) - target);
    return true;
  }
};

struct GyroStaticFunctor {
  Eigen::Vector3d raw;
  double dtemp_c, weight;
  template <typename T>
  bool operator()(const T* b, const T* b1, T* r) const {
    for (int i = 0; i < 3; ++i) r[i] = weight * (raw[i] - b[i] - b1[i] * dtemp_c);
    return true;
  }
};

struct GyroTableFunctor {
  Eigen::Vector3d raw;
  double dtemp_c, rate, weight;
  template <typename T>
  bool operator()(const T* b, const T* k, const T* m, const T* b1, T* r) const {
    T v[3];
    for (int i = 0; i < 3; ++i) v[i] = raw[i] - b[i] - b1[i] * dtemp_c;
    T w[3];
    GyroApply(k, m, v, w);
    using std::sqrt;
    r[0] = weight * (sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]) - rate);
    return true;
  }
};

// The 8 blocks in ParameterBlocks order.
class RotationCost : public ceres::SizedCostFunction<3, kSize[0], kSize[1], kSize[2], kSize[3],
                                                     kSize[4], kSize[5], kSize[6], kSize[7]> {
 public:
  explicit RotationCost(RotationData data) : d_(std::move(data)) {}

  bool Evaluate(double const* const* p, double* residuals, double** jacobians) const override {
    bool want_accel = false, want_gyro = false;
    if (jacobians != nullptr) {
      for (int i = PB::kAccelBias; i <= PB::kAccelBiasPerC; ++i) {
        want_accel = want_accel || jacobians[i] != nullptr;
      }
      for (int i = PB::kGyroBias; i <= PB::kGyroBiasPerC; ++i) {
        want_gyro = want_gyro || jacobians[i] != nullptr;
      }
    }
    // Accelerometer directions, with derivatives over its 12 parameters when wanted.
    using JA = ceres::Jet<double, PB::kAccelTotal>;
    double ui[3], uj[3];
    JA ui_j[3], uj_j[3];
    if (want_accel) {
      JA b[3], k[3], m[3], b1[3];
      for (int i = 0; i < 3; ++i) {
        b[i] = JA(p[PB::kAccelBias][i], PB::kOffset[PB::kAccelBias] + i);
        k[i] = JA(p[PB::kAccelScale][i], PB::kOffset[PB::kAccelScale] + i);
        m[i] = JA(p[PB::kAccelMisalignment][i], PB::kOffset[PB::kAccelMisalignment] + i);
        b1[i] = JA(p[PB::kAccelBiasPerC][i], PB::kOffset[PB::kAccelBiasPerC] + i);
      }
      AccelDirection(b, k, m, b1, d_.accel_start, d_.dtemp_start_c, ui_j);
      AccelDirection(b, k, m, b1, d_.accel_end, d_.dtemp_end_c, uj_j);
      for (int i = 0; i < 3; ++i) {
        ui[i] = ui_j[i].a;
        uj[i] = uj_j[i].a;
      }
    } else {
      const double* const* a = p + PB::kAccelBias;
      AccelDirection(a[0], a[1], a[2], a[3], d_.accel_start, d_.dtemp_start_c, ui);
      AccelDirection(a[0], a[1], a[2], a[3], d_.accel_end, d_.dtemp_end_c, uj);
    }
    // Integrated rotation, with derivatives over the gyroscope's 15 parameters when wanted.
    using JG = ceres::Jet<double, PB::kGyroTotal>;
    constexpr int kG = PB::kOffset[PB::kGyroBias];  // Jet index of the first gyro parameter.
    double q[4];
    double pred[3];
    JG pred_j[3];
    if (want_gyro) {
      JG b[3], k[3], m[6], b1[3];
      for (int i = 0; i < 3; ++i) {
        b[i] = JG(p[PB::kGyroBias][i], PB::kOffset[PB::kGyroBias] - kG + i);
        k[i] = JG(p[PB::kGyroScale][i], PB::kOffset[PB::kGyroScale] - kG + i);
        b1[i] = JG(p[PB::kGyroBiasPerC][i], PB::kOffset[PB::kGyroBiasPerC] - kG + i);
      }
      for (int i = 0; i < kSize[PB::kGyroMisalignment]; ++i) {
        m[i] = JG(p[PB::kGyroMisalignment][i], PB::kOffset[PB::kGyroMisalignment] - kG + i);
      }
      JG qj[4];
      IntegrateRotation(d_, b, k, m, b1, qj);
      const JG u[3] = {JG(ui[0]), JG(ui[1]), JG(ui[2])};
      RotateInverse(qj, u, pred_j);
      for (int i = 0; i < 4; ++i) q[i] = qj[i].a;
      for (int i = 0; i < 3; ++i) pred[i] = pred_j[i].a;
    } else {
      const double* const* g = p + PB::kGyroBias;
      IntegrateRotation(d_, g[0], g[1], g[2], g[3], q);
      RotateInverse(q, ui, pred);
    }
    for (int i = 0; i < 3; ++i) residuals[i] = d_.weight * (pred[i] - uj[i]);
    if (jacobians == nullptr) return true;

    if (want_gyro) {
      for (int blk = PB::kGyroBias; blk <= PB::kGyroBiasPerC; ++blk) {
        double* jac = jacobians[blk];
        if (jac == nullptr) continue;
        const int size = kSize[blk], offset = PB::kOffset[blk] - kG;
        for (int r = 0; r < 3; ++r) {
          for (int c = 0; c < size; ++c) {
            jac[r * size + c] = d_.weight * pred_j[r].v[offset + c];
          }
        }
      }
    }
    if (want_accel) {
      // d(R^T u_i - u_j) = R^T du_i - du_j, R^T as the rotation by the conjugate of q.
      const double qn = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
      const double qc[4] = {q[0] / qn, -q[1] / qn, -q[2] / qn, -q[3] / qn};
      for (int blk = PB::kAccelBias; blk <= PB::kAccelBiasPerC; ++blk) {
        double* jac = jacobians[blk];
        if (jac == nullptr) continue;
        for (int c = 0; c < kSize[blk]; ++c) {
          const int col = PB::kOffset[blk] + c;
          const double dui[3] = {ui_j[0].v[col], ui_j[1].v[col], ui_j[2].v[col]};
          double rot[3];
          ceres::UnitQuaternionRotatePoint(qc, dui, rot);
          for (int r = 0; r < 3; ++r) {
            jac[r * 3 + c] = d_.weight * (rot[r] - uj_j[r].v[col]);
          }
        }
      }
    }
    return true;
  }

  const RotationData& data() const { return d_; }

 private:
  RotationData d_;
};

}  // namespace

ceres::CostFunction* NewAccelNormCost(const Eigen::Vector3d& raw_mean, double dtemp_c,
                                      double target_norm, double weight) {
  return new ceres::AutoDiffCostFunction<AccelNormFunctor, 1, kSize[PB::kAccelBias],
                                         kSize[PB::kAccelScale], kSize[PB::kAccelMisalignment],
                                         kSize[PB::kAccelBiasPerC]>(
      new AccelNormFunctor{raw_mean, dtemp_c, target_norm, weight});
}

ceres::CostFunction* NewGyroStaticCost(const Eigen::Vector3d& raw_mean, double dtemp_c,
                                       double weight) {
  return new ceres::AutoDiffCostFunction<GyroStaticFunctor, 3, kSize[PB::kGyroBias],
                                         kSize[PB::kGyroBiasPerC]>(
      new GyroStaticFunctor{raw_mean, dtemp_c, weight});
}

ceres::CostFunction* NewGyroTableCost(const Eigen::Vector3d& raw_mean, double dtemp_c,
                                      double rate_abs_dps, double weight) {
  return new ceres::AutoDiffCostFunction<GyroTableFunctor, 1, kSize[PB::kGyroBias],
                                         kSize[PB::kGyroScale], kSize[PB::kGyroMisalignment],
                                         kSize[PB::kGyroBiasPerC]>(
      new GyroTableFunctor{raw_mean, dtemp_c, rate_abs_dps, weight});
}

ceres::CostFunction* NewRotationCost(RotationData data) {
  return new RotationCost(std::move(data));
}

Eigen::Vector3d RotationResidual(const RotationData& data, const double* const* p) {
  double ui[3], uj[3], q[4], pred[3];
  const double* const* a = p + PB::kAccelBias;
  const double* const* g = p + PB::kGyroBias;
  AccelDirection(a[0], a[1], a[2], a[3], data.accel_start, data.dtemp_start_c, ui);
  AccelDirection(a[0], a[1], a[2], a[3], data.accel_end, data.dtemp_end_c, uj);
  IntegrateRotation(data, g[0], g[1], g[2], g[3], q);
  RotateInverse(q, ui, pred);
  return Eigen::Vector3d(pred[0] - uj[0], pred[1] - uj[1], pred[2] - uj[2]);
}

Eigen::Matrix3d PredictionMatrix(const RotationData& data, const double* const* p) {
  const double* const* g = p + PB::kGyroBias;
  double q[4];
  IntegrateRotation(data, g[0], g[1], g[2], g[3], q);
  Eigen::Matrix3d out;
  for (int c = 0; c < 3; ++c) {
    const double e[3] = {c == 0 ? 1.0 : 0.0, c == 1 ? 1.0 : 0.0, c == 2 ? 1.0 : 0.0};
    double col[3];
    RotateInverse(q, e, col);
    out.col(c) = Eigen::Vector3d(col[0], col[1], col[2]);
  }
  return out;
}

}  // namespace metro::calibration_internal
