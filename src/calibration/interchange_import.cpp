// The import side of the calibration interchange (interchange.hpp, ImportInterchange): a
// format's numbers as metro's model in its body frame, their plausibility, and the covariance
// a sidecar carries back.
#include <fmt/format.h>

#include <Eigen/Dense>
#include <cmath>

#include "calibration/interchange_forms.hpp"
#include "calibration/parameter_blocks.hpp"
#include "core/json_reader.hpp"
#include "metro/calibration/interchange.hpp"

namespace metro {
namespace {

namespace ii = interchange_internal;
using PB = calibration_internal::ParameterBlocks;

constexpr double kPi = 3.14159265358979323846;
constexpr double kRadToDeg = 180.0 / kPi;
constexpr char kAxisNames[3] = {'x', 'y', 'z'};

// Plausibility limits (docs/calibration-interchange.md): a MEMS gain is within a few % of its
// nominal value (MPU-6000/6050 PS-MPU-6000A-00 rev 3.4: sensitivity tolerance +-3 %), its zero
// offsets within +-150 mg (accelerometer z) and +-20 deg/s (gyroscope), its cross-axis
// sensitivity +-2 %.
constexpr double kGainLimit = 0.10;           // |gain - 1|
constexpr double kAccelBiasLimitMps2 = 1.5;   // about 150 mg
constexpr double kGyroBiasLimitRadps = 0.35;  // about 20 deg/s
constexpr double kMisalignmentLimitRad = 0.05;
constexpr double kConditionLimit = 1e6;

struct Layout {
  int accel_first, gyro_first;      // First value of each sensor's block (for positions).
  int accel_diag[3], gyro_diag[3];  // The values on each sensor's diagonal (gains).
};

Layout LayoutOf(InterchangeFormat format) {
  switch (format) {
    case InterchangeFormat::kKalibr:
      return {0, 9, {0, 4, 8}, {9, 13, 17}};
    case InterchangeFormat::kOpenVins:
      return {18, 0, {18, 22, 26}, {0, 4, 8}};
    case InterchangeFormat::kBasalt:
      return {0, 9, {3, 6, 8}, {12, 16, 20}};
    case InterchangeFormat::kRealSense:
      return {0, 12, {0, 4, 8}, {12, 16, 20}};
    default:
      return {0, 6, {3, 4, 5}, {-1, -1, -1}};
  }
}

bool CarriesBias(InterchangeFormat f) {
  return f != InterchangeFormat::kKalibr && f != InterchangeFormat::kOpenVins;
}
bool GyroBiasOnly(InterchangeFormat f) {
  return f == InterchangeFormat::kPx4 || f == InterchangeFormat::kArduPilot;
}

// metro's models from the format's numbers; `kinds` fixes the models (from the values read).
struct Models {
  SensorModel accel, gyro;
  Eigen::Matrix3d body_from_format = Eigen::Matrix3d::Identity();
};

SensorModel FromMatrix(ImuSensor sensor, const Eigen::Matrix3d& m, const Eigen::Vector3d& bias,
                       ModelKind kind) {
  SensorModel s;
  s.sensor = sensor;
  s.kind = kind;
  const bool accel = sensor == ImuSensor::kAccel;
  s.input_unit = accel ? "m/s^2" : "rad/s";
  s.output_unit = accel ? "g" : "deg/s";
  s.bias = bias;
  s.scale = m.diagonal();
  const Eigen::Matrix3d t = m * s.scale.cwiseInverse().asDiagonal();
  if (kind == ModelKind::kFull) {
    if (accel) {
      s.misalignment = {-t(0, 1), t(0, 2), -t(1, 2)};
    } else {
      s.misalignment = {-t(0, 1), t(0, 2), t(1, 0), -t(1, 2), -t(2, 0), t(2, 1)};
    }
  }
  return s;
}

Models ModelsFromValues(InterchangeFormat format, const Eigen::VectorXd& v, ModelKind accel_kind,
                        ModelKind gyro_kind) {
  const ii::FramedForms f = ii::FormsFromValues(format, v);
  Eigen::Matrix3d q, u;
  ii::RotationTimesUpper(f.accel.matrix, &q, &u);
  Models m;
  m.body_from_format = q.transpose();
  // Input in SI (c_in = 1), output g and deg/s: M_metro = M_si / c_out.
  m.accel = FromMatrix(ImuSensor::kAccel, u / kStandardGravityMps2, f.accel.bias, accel_kind);
  m.gyro = FromMatrix(ImuSensor::kGyro, kRadToDeg * q.transpose() * f.gyro.matrix, f.gyro.bias,
                      gyro_kind);
  return m;
}

ModelKind KindOf(const Eigen::Matrix3d& body_matrix, bool upper_only) {
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) {
      if (r != c && (!upper_only || c > r) && body_matrix(r, c) != 0.0) return ModelKind::kFull;
    }
  }
  return ModelKind::kScale;
}

// The free parameters of the imported models, accelerometer first.
Eigen::VectorXd Theta(const Models& m, bool has_gyro) {
  std::vector<double> out;
  for (const SensorModel* s : {&m.accel, &m.gyro}) {
    if (s == &m.gyro && !has_gyro) continue;
    for (const std::string& n : PB::FreeNames(s->sensor, s->kind, false)) {
      out.push_back(ii::GetParameter(n, *s));
    }
  }
  return Eigen::Map<Eigen::VectorXd>(out.data(), static_cast<Eigen::Index>(out.size()));
}

Error At(const InterchangeFile& f, int index, const std::string& message) {
  const auto& [line, column] = f.positions[static_cast<size_t>(index)];
  return MakeError(f.file, line, column, message);
}

// Refusals: a value outside physical sense.
Status CheckPhysical(const InterchangeFile& f, const ii::FramedForms& forms, bool has_gyro) {
  const Layout l = LayoutOf(f.format);
  for (int s = 0; s < (has_gyro ? 2 : 1); ++s) {
    const bool accel = s == 0;
    const Eigen::Matrix3d& m = accel ? forms.accel.matrix : forms.gyro.matrix;
    const int first = accel ? l.accel_first : l.gyro_first;
    const char* name = accel ? "accelerometer" : "gyroscope";
    for (int a = 0; a < 3; ++a) {
      const int d = accel ? l.accel_diag[a] : l.gyro_diag[a];
      if (d >= 0 && !(m(a, a) > 0.0)) {
        return At(
            f, d,
            fmt::format("{} = {:.6g}: the {}'s gain on {} is {:.6g}: expected > 0 (a gain "
                        "<= 0 reverses or kills the axis; no physical sensor has one)",
                        f.values[static_cast<size_t>(d)].name,
                        f.values[static_cast<size_t>(d)].value, name, kAxisNames[a], m(a, a)));
      }
    }
    const Eigen::Vector3d sv = Eigen::JacobiSVD<Eigen::Matrix3d>(m).singularValues();
    const double cond = sv(0) / sv(2);
    if (!(m.determinant() > 0.0) || !(cond < kConditionLimit)) {
      return At(f, first,
                fmt::format("the {}'s matrix (from {} ...) has det {:.6g} and condition number "
                            "{:.3g}: expected det > 0 and a condition number below {:g} (a "
                            "singular or reflecting matrix has no physical sense)",
                            name, f.values[static_cast<size_t>(first)].name, m.determinant(), cond,
                            kConditionLimit));
    }
  }
  return {};
}

std::string UnitHint(double gain) {
  const auto near = [gain](double x) { return std::fabs(gain / x - 1.0) < 0.05; };
  if (near(kStandardGravityMps2) || near(1.0 / kStandardGravityMps2)) {
    return " (the ratio of m/s^2 to g: data in the wrong unit?)";
  }
  if (near(kRadToDeg) || near(1.0 / kRadToDeg))
    return " (the ratio of deg/s to rad/s: data in the wrong unit?)";
  return "";
}

// Warnings: constants far from what a MEMS IMU has (Kalibr issue #334: gyroscope gains
// 0.4 - 0.5 from a failed fit).
std::vector<std::string> PlausibilityFlags(const InterchangeFile& f, const Models& m,
                                           bool has_gyro) {
  std::vector<std::string> out;
  const Layout l = LayoutOf(f.format);
  for (int s = 0; s < (has_gyro ? 2 : 1); ++s) {
    const SensorModel& sm = s == 0 ? m.accel : m.gyro;
    const double c_out = s == 0 ? kStandardGravityMps2 : 1.0 / kRadToDeg;
    const char* name = ImuSensorLongName(sm.sensor);
    for (int a = 0; a < 3; ++a) {
      const double gain = sm.scale(a) * c_out;  // SI per SI
      const int d = s == 0 ? l.accel_diag[a] : l.gyro_diag[a];
      if (d < 0 || std::fabs(gain - 1.0) <= kGainLimit) continue;
      out.push_back(fmt::format(
          "implausible {} gain: {} = {:.6g} makes the calibrated gain on {} {:.6g} (SI per SI), "
          "{:.3g} % from 1; a MEMS gain is within a few % (MPU-6050 +-3 %){} (cf. Kalibr issue "
          "#334, gyroscope gains 0.4-0.5 from a failed fit)",
          name, f.values[static_cast<size_t>(d)].name, f.values[static_cast<size_t>(d)].value,
          kAxisNames[a], gain, 100.0 * (gain - 1.0), UnitHint(gain)));
    }
    const double bias_limit = s == 0 ? kAccelBiasLimitMps2 : kGyroBiasLimitRadps;
    if (sm.bias.cwiseAbs().maxCoeff() > bias_limit) {
      out.push_back(fmt::format(
          "implausible {} bias {:.6g} {:.6g} {:.6g} {}: beyond {:g} {} "
          "(MPU-6050 zero offsets: +-150 mg, +-20 deg/s)",
          name, sm.bias(0), sm.bias(1), sm.bias(2), sm.input_unit, bias_limit, sm.input_unit));
    }
    for (double t : sm.misalignment) {
      if (std::fabs(t) > kMisalignmentLimitRad) {
        out.push_back(
            fmt::format("implausible {} misalignment term {:.4g} rad (beyond {:g} rad; "
                        "cross-axis sensitivity is about +-2 %)",
                        name, t, kMisalignmentLimitRad));
        break;
      }
    }
  }
  const double angle = ii::RotationAngle(m.body_from_format);
  if (angle > kMisalignmentLimitRad) {
    out.push_back(
        fmt::format("the file's frame is turned {:.4g} rad from the accelerometer's "
                    "axes: more than a misalignment",
                    angle));
  }
  return out;
}

// What the format did not carry, with sizes where the file had them.
std::vector<std::string> NotCarried(const InterchangeFile& f, const Eigen::VectorXd& v,
                                    bool has_gyro, double angle) {
  std::vector<std::string> out;
  if (!CarriesBias(f.format)) {
    out.push_back(
        fmt::format("the biases ({} estimates them as states): written as 0, "
                    "uncertainty unknown",
                    f.format == InterchangeFormat::kKalibr ? "Kalibr" : "OpenVINS"));
  }
  if (GyroBiasOnly(f.format)) {
    out.push_back(
        "the misalignment of both sensors and the gyroscope's scale: not in the "
        "autopilot's parameters (taken as I and the nominal scale)");
  }
  if (!has_gyro) out.push_back("the gyroscope: not in the file");
  out.push_back("a bias temperature term: no format holds one");
  const int g_at = f.format == InterchangeFormat::kKalibr     ? 18
                   : f.format == InterchangeFormat::kOpenVins ? 36
                                                              : -1;
  if (g_at >= 0) {
    const double g = v.segment(g_at, 9).cwiseAbs().maxCoeff();
    if (g > 0.0) {
      out.push_back(
          fmt::format("the g-sensitivity {} (largest |element| {:.4g} (rad/s)/(m/s^2)): "
                      "metro has no g-sensitivity term",
                      f.format == InterchangeFormat::kKalibr ? "A" : "Tg", g));
    }
  }
  if (angle > 0.0) {
    out.push_back(
        fmt::format("the file's frame: the constants are in the accelerometer's axes "
                    "(metro's body frame), turned {:.4g} mrad from the file's frame",
                    1e3 * angle));
  }
  for (const std::string& n : f.notes) out.push_back(n);
  return out;
}

// The sidecar's covariance of the file's values, checked against the file.
Result<Eigen::MatrixXd> SidecarCovariance(const InterchangeFile& f,
                                          const InterchangeImportOptions& o) {
  Result<JsonDocument> doc = JsonDocument::Parse(o.sidecar_text, o.sidecar_file);
  if (!doc.ok()) return doc.error();
  const JsonCursor root(doc.value());
  if (root["schema"].String() != "metro.interchange_covariance/1" && root.ok()) {
    root["schema"].Fail("\"metro.interchange_covariance/1\"");
  }
  if (root.ok() && root["format"].String() != InterchangeFormatName(f.format)) {
    root["format"].Fail(
        fmt::format("\"{}\" (the format of {})", InterchangeFormatName(f.format), f.file));
  }
  const JsonCursor values = root["values"];
  const size_t n = f.values.size();
  if (root.ok() && (!values.IsArray() || values.Size() != n)) {
    values.Fail(fmt::format("an array of the {} values of {}", n, f.file));
  }
  for (size_t i = 0; i < n && root.ok(); ++i) {
    const std::string name = values[i]["name"].String();
    const double v = values[i]["value"].Number();
    if (!root.ok()) break;
    const double w = f.values[i].value;
    if (name != f.values[i].name) {
      values[i]["name"].Fail(
          fmt::format("\"{}\" (the sidecar does not belong to {})", f.values[i].name, f.file));
    } else if (std::fabs(v - w) > 1e-12 * std::max(std::fabs(v), std::fabs(w))) {
      values[i]["value"].Fail(
          fmt::format("{:.17g}, the value in {} (the sidecar belongs to "
                      "another export)",
                      w, f.file));
    }
  }
  Eigen::MatrixXd cov =
      Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(n));
  const JsonCursor c = root["covariance"];
  if (root.ok() && (!c.IsArray() || c.Size() != n)) c.Fail(fmt::format("a {} x {} matrix", n, n));
  for (size_t r = 0; r < n && root.ok(); ++r) {
    const std::vector<double> row = c[r].Numbers();
    if (root.ok() && row.size() != n) c[r].Fail(fmt::format("a row of {} numbers", n));
    for (size_t k = 0; k < n && root.ok(); ++k) {
      cov(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(k)) = row[k];
    }
  }
  if (!root.ok()) return root.error();
  return cov;
}

SensorCalibration Imported(const SensorModel& m, const Eigen::MatrixXd& cov, bool known,
                           const std::string& reason) {
  SensorCalibration c;
  c.model = m;
  c.parameter_names = PB::FreeNames(m.sensor, m.kind, false);
  c.covariance = cov;
  DeriveUncertainties(&c);
  ModelCheck check;
  check.selection = kImportedSelection;
  check.status = "not_tested";
  check.model_rejected = !known;
  check.reason = reason;
  c.model_check = check;
  return c;
}

}  // namespace

Result<InterchangeImport> ImportInterchange(const InterchangeFile& f,
                                            const InterchangeImportOptions& o) {
  Eigen::VectorXd v(static_cast<Eigen::Index>(f.values.size()));
  for (size_t i = 0; i < f.values.size(); ++i) v(static_cast<Eigen::Index>(i)) = f.values[i].value;
  const bool has_gyro = !GyroBiasOnly(f.format) || f.present[6];
  const ii::FramedForms forms = ii::FormsFromValues(f.format, v);
  if (Status s = CheckPhysical(f, forms, has_gyro); !s.ok()) return s.error();
  // The models' kinds from the values read (fixed for the Jacobian below).
  const Models probe = ModelsFromValues(f.format, v, ModelKind::kFull, ModelKind::kFull);
  const ModelKind accel_kind = KindOf(probe.accel.Matrix(), true);
  const ModelKind gyro_kind =
      GyroBiasOnly(f.format) ? ModelKind::kBias : KindOf(probe.gyro.Matrix(), false);
  const Models m = ModelsFromValues(f.format, v, accel_kind, gyro_kind);
  InterchangeImport out;
  out.body_from_format = m.body_from_format;
  out.flags = PlausibilityFlags(f, m, has_gyro);
  out.not_carried = NotCarried(f, v, has_gyro, ii::RotationAngle(m.body_from_format));
  const Eigen::Index na =
      static_cast<Eigen::Index>(PB::FreeCount(ImuSensor::kAccel, accel_kind, false));
  const Eigen::Index ng =
      static_cast<Eigen::Index>(PB::FreeCount(ImuSensor::kGyro, gyro_kind, false));
  Eigen::MatrixXd cov = Eigen::MatrixXd::Zero(na + (has_gyro ? ng : 0), na + (has_gyro ? ng : 0));
  if (!o.sidecar_text.empty()) {
    Result<Eigen::MatrixXd> cv = SidecarCovariance(f, o);
    if (!cv.ok()) return cv.error();
    const Eigen::VectorXd u = cv.value().diagonal().cwiseMax(0.0).cwiseSqrt();
    Eigen::VectorXd h(v.size());
    for (Eigen::Index i = 0; i < v.size(); ++i) {
      h(i) = u(i) > 0.0 ? 1e-2 * u(i) : 1e-7 * std::max(1.0, std::fabs(v(i)));
    }
    const auto theta = [&](const Eigen::VectorXd& x) {
      return Theta(ModelsFromValues(f.format, x, accel_kind, gyro_kind), has_gyro);
    };
    // JCGM 102:2011 6.2.1.3 with the Jacobian of the inverse conversion.
    const Eigen::MatrixXd j = ii::NumericJacobian(theta, v, h);
    cov = j * cv.value() * j.transpose();
    out.uncertainty_known = CarriesBias(f.format);
  }
  const std::string why =
      o.sidecar_text.empty()
          ? fmt::format(
                "imported from {} ({}) without a covariance sidecar: the standard "
                "uncertainties are unknown (the covariance's zeros stand for nothing)",
                InterchangeFormatName(f.format), f.file)
          : fmt::format(
                "imported from {} ({}): the biases were not carried, their "
                "uncertainty is unknown",
                InterchangeFormatName(f.format), f.file);
  const std::string reason = out.uncertainty_known
                                 ? fmt::format(
                                       "imported from {} ({}) with its covariance sidecar "
                                       "({}); not tested by metro",
                                       InterchangeFormatName(f.format), f.file, o.sidecar_file)
                                 : why;
  Calibration& cal = out.calibration;
  cal.gravity_mps2 = kStandardGravityMps2;
  cal.tool_version = o.tool_version;
  cal.date_utc = o.date_utc;
  InputFile in(f.file, f.sha256);
  in.format = InterchangeFormatName(f.format);
  cal.inputs.push_back(in);
  TagCalibration tag;
  tag.sensor = o.sensor;
  tag.accel = Imported(m.accel, cov.topLeftCorner(na, na), out.uncertainty_known, reason);
  if (has_gyro)
    tag.gyro = Imported(m.gyro, cov.bottomRightCorner(ng, ng), out.uncertainty_known, reason);
  for (const std::string& n : out.not_carried) tag.warnings.push_back("not carried: " + n);
  for (const std::string& flag : out.flags) tag.warnings.push_back(flag);
  cal.tags.push_back(std::move(tag));
  return out;
}

}  // namespace metro
