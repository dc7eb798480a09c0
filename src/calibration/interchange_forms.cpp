#include "calibration/interchange_forms.hpp"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

namespace metro::interchange_internal {
namespace {

constexpr char kAxes[3] = {'X', 'Y', 'Z'};

void AddMatrix(std::vector<InterchangeValue>* out, const std::string& name,
               const std::string& unit) {
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) out->push_back({fmt::format("{}[{}][{}]", name, r, c), 0.0, unit});
  }
}

void AddArray(std::vector<InterchangeValue>* out, const std::string& name, int n,
              const std::string& unit, int first = 0) {
  for (int i = first; i < first + n; ++i)
    out->push_back({fmt::format("{}[{}]", name, i), 0.0, unit});
}

// Row-major 3 x 3 from values starting at `at`.
Eigen::Matrix3d Mat(const Eigen::VectorXd& v, int at) {
  Eigen::Matrix3d m;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) m(r, c) = v(at + 3 * r + c);
  }
  return m;
}

void PutMat(Eigen::VectorXd* v, int at, const Eigen::Matrix3d& m) {
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) (*v)(at + 3 * r + c) = m(r, c);
  }
}

// The Q of Q U with U's diagonal made positive (Householder QR, then signs moved to Q).
void PositiveQr(const Eigen::Matrix3d& m, Eigen::Matrix3d* q, Eigen::Matrix3d* u) {
  const Eigen::HouseholderQR<Eigen::Matrix3d> qr(m);
  Eigen::Matrix3d uu = qr.matrixQR().triangularView<Eigen::Upper>();
  Eigen::Matrix3d qq = qr.householderQ();
  for (int i = 0; i < 3; ++i) {
    if (uu(i, i) < 0.0) {
      uu.row(i) *= -1.0;
      qq.col(i) *= -1.0;
    }
  }
  *q = qq;
  *u = uu;
}

}  // namespace

std::vector<InterchangeValue> Layout(InterchangeFormat format, int instance) {
  std::vector<InterchangeValue> out;
  const std::string imu = fmt::format("imu{}.", instance);
  switch (format) {
    case InterchangeFormat::kKalibr:
      AddMatrix(&out, imu + "accelerometers.M", "1");
      AddMatrix(&out, imu + "gyroscopes.M", "1");
      AddMatrix(&out, imu + "gyroscopes.A", "(rad/s)/(m/s^2)");
      AddMatrix(&out, imu + "gyroscopes.C_gyro_i", "1");
      break;
    case InterchangeFormat::kOpenVins:
      AddMatrix(&out, imu + "Tw", "1");
      AddMatrix(&out, imu + "R_IMUtoGYRO", "1");
      AddMatrix(&out, imu + "Ta", "1");
      AddMatrix(&out, imu + "R_IMUtoACC", "1");
      AddMatrix(&out, imu + "Tg", "(rad/s)/(m/s^2)");
      break;
    case InterchangeFormat::kBasalt:
      AddArray(&out, "value0.calib_accel_bias", 3, "m/s^2");
      AddArray(&out, "value0.calib_accel_bias", 6, "1", 3);
      AddArray(&out, "value0.calib_gyro_bias", 3, "rad/s");
      AddArray(&out, "value0.calib_gyro_bias", 9, "1", 3);
      break;
    case InterchangeFormat::kRealSense: {
      const std::string p = fmt::format("imus[{}].", instance);
      AddArray(&out, p + "accelerometer.scale_and_alignment", 9, "1");
      AddArray(&out, p + "accelerometer.bias", 3, "m/s^2");
      AddArray(&out, p + "gyroscope.scale_and_alignment", 9, "1");
      AddArray(&out, p + "gyroscope.bias", 3, "rad/s");
      break;
    }
    case InterchangeFormat::kPx4:
      for (int a = 0; a < 3; ++a)
        out.push_back({fmt::format("CAL_ACC{}_{}OFF", instance, kAxes[a]), 0, "m/s^2"});
      for (int a = 0; a < 3; ++a)
        out.push_back({fmt::format("CAL_ACC{}_{}SCALE", instance, kAxes[a]), 0, "1"});
      for (int a = 0; a < 3; ++a)
        out.push_back({fmt::format("CAL_GYRO{}_{}OFF", instance, kAxes[a]), 0, "rad/s"});
      break;
    case InterchangeFormat::kArduPilot: {
      const std::string n = instance == 0 ? "" : std::to_string(instance + 1);
      for (int a = 0; a < 3; ++a)
        out.push_back({fmt::format("INS_ACC{}OFFS_{}", n, kAxes[a]), 0, "m/s^2"});
      for (int a = 0; a < 3; ++a)
        out.push_back({fmt::format("INS_ACC{}SCAL_{}", n, kAxes[a]), 0, "1"});
      for (int a = 0; a < 3; ++a)
        out.push_back({fmt::format("INS_GYR{}OFFS_{}", n, kAxes[a]), 0, "rad/s"});
      break;
    }
  }
  return out;
}

bool LowerTriangularAccel(InterchangeFormat format) {
  return format == InterchangeFormat::kKalibr || format == InterchangeFormat::kOpenVins ||
         format == InterchangeFormat::kBasalt;
}

void RotationTimesUpper(const Eigen::Matrix3d& m, Eigen::Matrix3d* q, Eigen::Matrix3d* u) {
  PositiveQr(m, q, u);
}

void RotationTimesLower(const Eigen::Matrix3d& m, Eigen::Matrix3d* r, Eigen::Matrix3d* l) {
  // With J the exchange matrix (J = J^T = J^-1): M J = Q U gives M = (Q J)(J U J), and J U J is
  // lower triangular with U's diagonal reversed. det(Q J) = det(M) / det(J U J) > 0.
  Eigen::Matrix3d j = Eigen::Matrix3d::Zero();
  j(0, 2) = j(1, 1) = j(2, 0) = 1.0;
  Eigen::Matrix3d q, u;
  PositiveQr(m * j, &q, &u);
  *r = q * j;
  *l = j * u * j;
  for (int a = 0; a < 3; ++a) {
    for (int b = a + 1; b < 3; ++b) (*l)(a, b) = 0.0;
  }
}

Eigen::VectorXd ValuesFromForms(InterchangeFormat format, const FramedForms& f) {
  const Eigen::Matrix3d id = Eigen::Matrix3d::Identity();
  Eigen::VectorXd v;
  switch (format) {
    case InterchangeFormat::kKalibr:
    case InterchangeFormat::kOpenVins: {
      // Gyroscope: w_raw = M_g C w_I + b, so (M_g C)^-1 = the calibrated matrix: X = G^-1 = M_g C,
      // X^T = C^T M_g^T is a rotation times an upper triangular matrix.
      const Eigen::Matrix3d m_a = f.accel.matrix.inverse();
      Eigen::Matrix3d c_t, m_g_t;
      RotationTimesUpper(f.gyro.matrix.inverse().transpose(), &c_t, &m_g_t);
      const Eigen::Matrix3d m_g = m_g_t.transpose(), c = c_t.transpose();
      if (format == InterchangeFormat::kKalibr) {
        v.resize(36);
        PutMat(&v, 0, m_a);
        PutMat(&v, 9, m_g);
        PutMat(&v, 18, Eigen::Matrix3d::Zero());
        PutMat(&v, 27, c);
      } else {
        v.resize(45);
        PutMat(&v, 0, m_g);
        PutMat(&v, 9, c);
        PutMat(&v, 18, m_a);
        PutMat(&v, 27, id);
        PutMat(&v, 36, Eigen::Matrix3d::Zero());
      }
      return v;
    }
    case InterchangeFormat::kBasalt: {
      v.resize(21);
      const Eigen::Matrix3d s_a = f.accel.matrix - id, s_g = f.gyro.matrix - id;
      v.segment<3>(0) = f.accel.matrix * f.accel.bias;
      v(3) = s_a(0, 0), v(4) = s_a(1, 0), v(5) = s_a(2, 0);
      v(6) = s_a(1, 1), v(7) = s_a(2, 1), v(8) = s_a(2, 2);
      v.segment<3>(9) = f.gyro.matrix * f.gyro.bias;
      for (int c = 0; c < 3; ++c) {
        for (int r = 0; r < 3; ++r) v(12 + 3 * c + r) = s_g(r, c);
      }
      return v;
    }
    case InterchangeFormat::kRealSense:
      v.resize(24);
      PutMat(&v, 0, f.accel.matrix.transpose());
      v.segment<3>(9) = f.accel.matrix * f.accel.bias;
      PutMat(&v, 12, f.gyro.matrix.transpose());
      v.segment<3>(21) = f.gyro.matrix * f.gyro.bias;
      return v;
    case InterchangeFormat::kPx4:
    case InterchangeFormat::kArduPilot:
      v.resize(9);
      v.segment<3>(0) = f.accel.bias;
      v.segment<3>(3) = f.accel.matrix.diagonal();
      v.segment<3>(6) = f.gyro.bias;
      return v;
  }
  return v;
}

FramedForms FormsFromValues(InterchangeFormat format, const Eigen::VectorXd& v) {
  FramedForms f;
  switch (format) {
    case InterchangeFormat::kKalibr:
      f.accel.matrix = Mat(v, 0).inverse();
      f.gyro.matrix = (Mat(v, 9) * Mat(v, 27)).inverse();
      break;
    case InterchangeFormat::kOpenVins:
      f.gyro.matrix = Mat(v, 9).transpose() * Mat(v, 0).inverse();
      f.accel.matrix = Mat(v, 27).transpose() * Mat(v, 18).inverse();
      break;
    case InterchangeFormat::kBasalt: {
      Eigen::Matrix3d s_a = Eigen::Matrix3d::Zero();
      s_a(0, 0) = v(3), s_a(1, 0) = v(4), s_a(2, 0) = v(5);
      s_a(1, 1) = v(6), s_a(2, 1) = v(7), s_a(2, 2) = v(8);
      Eigen::Matrix3d s_g;
      for (int c = 0; c < 3; ++c) {
        for (int r = 0; r < 3; ++r) s_g(r, c) = v(12 + 3 * c + r);
      }
      f.accel.matrix = Eigen::Matrix3d::Identity() + s_a;
      f.gyro.matrix = Eigen::Matrix3d::Identity() + s_g;
      f.accel.bias = f.accel.matrix.inverse() * Eigen::Vector3d(v.segment<3>(0));
      f.gyro.bias = f.gyro.matrix.inverse() * Eigen::Vector3d(v.segment<3>(9));
      break;
    }
    case InterchangeFormat::kRealSense:
      f.accel.matrix = Mat(v, 0).transpose();
      f.accel.bias = f.accel.matrix.inverse() * Eigen::Vector3d(v.segment<3>(9));
      f.gyro.matrix = Mat(v, 12).transpose();
      f.gyro.bias = f.gyro.matrix.inverse() * Eigen::Vector3d(v.segment<3>(21));
      break;
    case InterchangeFormat::kPx4:
    case InterchangeFormat::kArduPilot:
      f.accel.bias = v.segment<3>(0);
      f.accel.matrix = Eigen::Vector3d(v.segment<3>(3)).asDiagonal();
      f.gyro.bias = v.segment<3>(6);
      break;
  }
  return f;
}

Eigen::MatrixXd NumericJacobian(const std::function<Eigen::VectorXd(const Eigen::VectorXd&)>& f,
                                const Eigen::VectorXd& x, const Eigen::VectorXd& h) {
  const Eigen::VectorXd f0 = f(x);
  Eigen::MatrixXd j = Eigen::MatrixXd::Zero(f0.size(), x.size());
  for (Eigen::Index i = 0; i < x.size(); ++i) {
    if (!(h(i) > 0.0)) continue;
    Eigen::VectorXd xp = x, xm = x;
    xp(i) += h(i);
    xm(i) -= h(i);
    j.col(i) = (f(xp) - f(xm)) / (2.0 * h(i));
  }
  return j;
}

namespace {

int AxisOf(const std::string& name) { return name.back() - 'x'; }

// Index of a misalignment term in imu_model.hpp's layout, or -1.
int MisalignmentIndex(ImuSensor sensor, const std::string& name) {
  static const char* const kAccelTerms[] = {"a_yz", "a_zy", "a_zx"};
  static const char* const kGyroTerms[] = {"g_yz", "g_zy", "g_xz", "g_zx", "g_xy", "g_yx"};
  for (int i = 0; i < MisalignmentCount(sensor); ++i) {
    if (name == (sensor == ImuSensor::kAccel ? kAccelTerms[i] : kGyroTerms[i])) return i;
  }
  return -1;
}

}  // namespace

void SetParameter(const std::string& name, double value, SensorModel* m) {
  if (name.rfind("b1_", 0) == 0) {
    m->bias_per_c(AxisOf(name)) = value;
  } else if (name.rfind("b_", 0) == 0) {
    m->bias(AxisOf(name)) = value;
  } else if (name.rfind("k_", 0) == 0) {
    m->scale(AxisOf(name)) = value;
  } else if (const int i = MisalignmentIndex(m->sensor, name); i >= 0) {
    if (m->misalignment.empty()) {
      m->misalignment.assign(static_cast<size_t>(MisalignmentCount(m->sensor)), 0.0);
    }
    m->misalignment[static_cast<size_t>(i)] = value;
  }
}

double GetParameter(const std::string& name, const SensorModel& m) {
  if (name.rfind("b1_", 0) == 0) return m.bias_per_c(AxisOf(name));
  if (name.rfind("b_", 0) == 0) return m.bias(AxisOf(name));
  if (name.rfind("k_", 0) == 0) return m.scale(AxisOf(name));
  const int i = MisalignmentIndex(m.sensor, name);
  if (i < 0 || m.misalignment.empty()) return 0.0;
  return m.misalignment[static_cast<size_t>(i)];
}

double RotationAngle(const Eigen::Matrix3d& r) {
  const double c = std::clamp((r.trace() - 1.0) / 2.0, -1.0, 1.0);
  // acos loses digits near 0; the skew part's norm keeps them.
  const Eigen::Vector3d s(r(2, 1) - r(1, 2), r(0, 2) - r(2, 0), r(1, 0) - r(0, 1));
  return std::atan2(0.5 * s.norm(), c);
}

}  // namespace metro::interchange_internal
