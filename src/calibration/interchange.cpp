// The export side of the calibration interchange (interchange.hpp): metro's constants as the
// numbers of each format, their covariance, and the file text.
#include "metro/calibration/interchange.hpp"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <cmath>
#include <map>

#include "calibration/interchange_forms.hpp"
#include "core/json_text.hpp"
#include "metro/calibration/autopilot_export.hpp"
#include "metro/calibration/calibration_io.hpp"

namespace metro {

using interchange_internal::FramedForms;

namespace {

namespace ii = interchange_internal;

using ii::GetParameter;
using ii::SetParameter;

// SI form of a model with the calibration's unit factors.
SiSensorForm SiOf(const SensorModel& m, double c_in, double c_out) {
  SiSensorForm f;
  f.matrix = (c_out / c_in) * m.Matrix();
  f.bias = c_in * m.bias;
  return f;
}

// The free parameters of the tag's sensors, accelerometer first (the sidecar's theta).
struct TagParameters {
  std::vector<const SensorCalibration*> sensors;  // accel, gyro (present ones)
  std::vector<double> c_in, c_out;
  Eigen::VectorXd theta, u;
  Eigen::MatrixXd covariance;
};

Result<TagParameters> CollectParameters(const TagCalibration& tag) {
  TagParameters p;
  Eigen::Index n = 0;
  for (const auto* s : {&tag.accel, &tag.gyro}) {
    if (!s->has_value()) continue;
    Result<AutopilotSensorForm> units = AutopilotForm(**s);
    if (!units.ok()) return units.error();
    p.sensors.push_back(&**s);
    p.c_in.push_back(units.value().input_to_si);
    p.c_out.push_back(units.value().output_to_si);
    n += static_cast<Eigen::Index>((*s)->parameter_names.size());
  }
  p.theta = Eigen::VectorXd::Zero(n);
  p.covariance = Eigen::MatrixXd::Zero(n, n);
  Eigen::Index at = 0;
  for (const SensorCalibration* c : p.sensors) {
    const Eigen::Index k = static_cast<Eigen::Index>(c->parameter_names.size());
    for (Eigen::Index i = 0; i < k; ++i) {
      p.theta(at + i) = GetParameter(c->parameter_names[static_cast<size_t>(i)], c->model);
    }
    if (c->covariance.rows() == k) p.covariance.block(at, at, k, k) = c->covariance;
    at += k;
  }
  p.u = p.covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
  return p;
}

// The body-frame forms at theta; a sensor the tag lacks is the identity.
FramedForms BodyForms(const TagParameters& p, const Eigen::VectorXd& theta) {
  FramedForms f;
  Eigen::Index at = 0;
  for (size_t s = 0; s < p.sensors.size(); ++s) {
    SensorModel m = p.sensors[s]->model;
    for (const std::string& name : p.sensors[s]->parameter_names)
      SetParameter(name, theta(at++), &m);
    (m.sensor == ImuSensor::kAccel ? f.accel : f.gyro) = SiOf(m, p.c_in[s], p.c_out[s]);
  }
  return f;
}

// The forms in the format's frame and R (a_B = R a_I).
FramedForms ToFormatFrame(InterchangeFormat format, const FramedForms& body, Eigen::Matrix3d* r) {
  *r = Eigen::Matrix3d::Identity();
  if (!ii::LowerTriangularAccel(format)) return body;
  Eigen::Matrix3d l;
  ii::RotationTimesLower(body.accel.matrix, r, &l);
  FramedForms f = body;
  f.accel.matrix = l;
  f.gyro.matrix = r->transpose() * body.gyro.matrix;
  return f;
}

// ---- Text ---------------------------------------------------------------------------------

std::string Num(double v) { return fmt::format("{:.17g}", v == 0.0 ? 0.0 : v); }  // no "-0"

std::string YamlMatrix(const std::string& indent, const Eigen::VectorXd& v, int at) {
  std::string out;
  for (int r = 0; r < 3; ++r) {
    out += fmt::format("{}- [{}, {}, {}]\n", indent, Num(v(at + 3 * r)), Num(v(at + 3 * r + 1)),
                       Num(v(at + 3 * r + 2)));
  }
  return out;
}

std::string MatrixLine(const Eigen::Matrix3d& m) {
  return fmt::format(
      "[[{:.12g}, {:.12g}, {:.12g}], [{:.12g}, {:.12g}, {:.12g}], [{:.12g}, "
      "{:.12g}, {:.12g}]]",
      m(0, 0), m(0, 1), m(0, 2), m(1, 0), m(1, 1), m(1, 2), m(2, 0), m(2, 1), m(2, 2));
}

// The convention lines every format carries (a YAML comment block or a JSON key).
std::vector<std::string> ConventionLines(InterchangeFormat format, const InterchangeExport& e,
                                         const std::string& source, int sensor) {
  std::vector<std::string> l;
  l.push_back(fmt::format("metro calibration of tag {} ({}) as {} intrinsics", sensor, source,
                          InterchangeFormatName(format)));
  switch (format) {
    case InterchangeFormat::kKalibr:
      l.push_back(
          "Kalibr imu-chain yaml, model scale-misalignment (Kalibr IccSensors.py "
          "IccScaledMisalignedImu): a_raw = M_a a_i + b_a; w_raw = M_g C_gyro_i w_i + "
          "A C_gyro_i a_i + b_g; M lower triangular; SI units");
      l.push_back(
          "A = 0: metro does not model g-sensitivity; b_a, b_g are Kalibr's bias states "
          "(not in this file); the noise keys come from characterize noise-export");
      break;
    case InterchangeFormat::kOpenVins:
      l.push_back(
          "OpenVINS kalibr_imu_chain.yaml, imu model kalibr (OpenVINS "
          "docs/propagation-analytical.dox, "
          "'IMU Intrinsic Models'): w_I = R_IMUtoGYRO^T Tw^-1 (w_m - Tg a_I - b_g); a_I = "
          "R_IMUtoACC^T Ta^-1 (a_m - b_a); Tw, Ta lower triangular; SI units");
      l.push_back(
          "Tg = 0: metro does not model g-sensitivity; b_g, b_a are the filter's states "
          "(not in this file); set the estimator's imu model to kalibr; the noise keys come from "
          "characterize noise-export");
      l.push_back(
          "not certain: the model key is written as OpenVINS's example configs write it; "
          "whether your OpenVINS version takes the imu model from it or from "
          "estimator_config.yaml was not verified");
      break;
    case InterchangeFormat::kBasalt:
      l.push_back(
          "basalt calibration.json value0 (basalt-headers calib_bias.hpp): a_I = (I + "
          "S_a) a_raw - b_a, calib_accel_bias = [b_a, s1..s6], S_a = [[s1,0,0],[s2,s4,0],"
          "[s3,s5,s6]]; w_I = (I + S_g) w_raw - b_g, calib_gyro_bias = [b_g, s1..s9] "
          "column by column; bias after scaling; m/s^2, rad/s");
      l.push_back("merge these two keys into your calibration.json's value0");
      break;
    case InterchangeFormat::kRealSense:
      l.push_back(
          "librealsense rs-imu-calibration.py calibration.json: a = S^T a_raw - bias with "
          "S = scale_and_alignment row by row (its check_X); bias after scaling; m/s^2, "
          "rad/s. The device table holds S^T; the convention is that of check_X");
      break;
    case InterchangeFormat::kPx4:
    case InterchangeFormat::kArduPilot:
      break;
  }
  l.push_back(
      "metro: calibrated = M (data - b) in SI, bias before scaling "
      "(docs/calibration-interchange.md)");
  const double angle = ii::RotationAngle(e.body_from_format);
  l.push_back(
      fmt::format("frame: a_metro = R a_file, R = {} (a turn of {:.3g} mrad; the "
                  "format holds a lower triangular accelerometer matrix)",
                  MatrixLine(e.body_from_format), 1e3 * angle));
  for (const std::string& n : e.not_held) l.push_back("NOT HELD: " + n);
  l.push_back("standard uncertainties and covariance: the sidecar FILE.covariance.json");
  return l;
}

std::string YamlComments(const std::vector<std::string>& lines) {
  std::string out;
  for (const std::string& l : lines) out += "# " + l + "\n";
  return out;
}

std::string KalibrText(const InterchangeExport& e, const Eigen::VectorXd& v, int instance,
                       const std::vector<std::string>& lines) {
  std::string out = YamlComments(lines);
  out += fmt::format("imu{}:\n  model: scale-misalignment\n  accelerometers:\n    M:\n", instance);
  out += YamlMatrix("    ", v, 0);
  out += "  gyroscopes:\n    A:\n" + YamlMatrix("    ", v, 18);
  out += "    C_gyro_i:\n" + YamlMatrix("    ", v, 27);
  out += "    M:\n" + YamlMatrix("    ", v, 9);
  (void)e;
  return out;
}

std::string OpenVinsText(const Eigen::VectorXd& v, int instance,
                         const std::vector<std::string>& lines) {
  std::string out = "%YAML:1.0\n" + YamlComments(lines);
  out += fmt::format("imu{}:\n  model: kalibr\n", instance);
  const char* const keys[] = {"Tw", "R_IMUtoGYRO", "Ta", "R_IMUtoACC", "Tg"};
  for (int k = 0; k < 5; ++k) out += fmt::format("  {}:\n", keys[k]) + YamlMatrix("    ", v, 9 * k);
  return out;
}

nlohmann::ordered_json Array(const Eigen::VectorXd& v, int at, int n) {
  nlohmann::ordered_json a = nlohmann::ordered_json::array();
  for (int i = at; i < at + n; ++i) a.push_back(v(i));
  return a;
}

std::string BasaltText(const Eigen::VectorXd& v, const std::vector<std::string>& lines) {
  nlohmann::ordered_json root;
  root["value0"]["calib_accel_bias"] = Array(v, 0, 9);
  root["value0"]["calib_gyro_bias"] = Array(v, 9, 12);
  root["metro_convention"] = lines;
  return JsonText(root, 2) + "\n";
}

std::string RealSenseText(const Eigen::VectorXd& v, const std::vector<std::string>& lines) {
  nlohmann::ordered_json imu;
  imu["accelerometer"]["bias"] = Array(v, 9, 3);
  imu["accelerometer"]["scale_and_alignment"] = Array(v, 0, 9);
  imu["gyroscope"]["bias"] = Array(v, 21, 3);
  imu["gyroscope"]["scale_and_alignment"] = Array(v, 12, 9);
  nlohmann::ordered_json root;
  root["imus"] = nlohmann::ordered_json::array({imu});
  root["metro_convention"] = lines;
  return JsonText(root, 4) + "\n";
}

// What the form leaves out of the tag's constants.
std::vector<std::string> NotHeld(InterchangeFormat format, const TagCalibration& tag,
                                 const FramedForms& body, double angle) {
  std::vector<std::string> out;
  if (format == InterchangeFormat::kKalibr || format == InterchangeFormat::kOpenVins) {
    out.push_back(fmt::format(
        "the biases (accelerometer {:.6g} {:.6g} {:.6g} m/s^2, gyroscope {:.6g} {:.6g} {:.6g} "
        "rad/s): {} estimates them as states; give them as its initial biases",
        body.accel.bias(0), body.accel.bias(1), body.accel.bias(2), body.gyro.bias(0),
        body.gyro.bias(1), body.gyro.bias(2),
        format == InterchangeFormat::kKalibr ? "Kalibr" : "OpenVINS"));
  }
  for (const auto* s : {&tag.accel, &tag.gyro}) {
    if (!s->has_value()) {
      out.push_back(fmt::format("the {}: the tag has no {} calibration (identity written)",
                                s == &tag.accel ? "accelerometer" : "gyroscope",
                                s == &tag.accel ? "accelerometer" : "gyroscope"));
      continue;
    }
    const SensorModel& m = (*s)->model;
    if (m.has_temperature && m.bias_per_c.cwiseAbs().maxCoeff() > 0.0) {
      out.push_back(
          fmt::format("the {} bias temperature term b1 = {:.4g} {:.4g} {:.4g} {}/degC "
                      "(the bias written is at t_ref {:g} degC)",
                      ImuSensorLongName(m.sensor), m.bias_per_c(0), m.bias_per_c(1),
                      m.bias_per_c(2), m.input_unit, m.t_ref_c));
    }
  }
  if (angle > 0.0) {
    out.push_back(
        fmt::format("metro's body frame: the file's frame is turned by {:.4g} mrad "
                    "from it (R above; the extrinsics the estimator calibrates absorb it)",
                    1e3 * angle));
  }
  return out;
}

// Steps for the Jacobian: u / 100 (the derivative over the span the law of propagation uses
// it on; rounding then costs about eps |v| / h, 1e-9 relative), or
// 1e-7 of the value's size for a held one (no variance: its column does not matter).
Eigen::VectorXd Steps(const Eigen::VectorXd& theta, const Eigen::VectorXd& u) {
  Eigen::VectorXd h(theta.size());
  for (Eigen::Index i = 0; i < theta.size(); ++i) {
    h(i) = u(i) > 0.0 ? 1e-2 * u(i) : 1e-7 * std::max(1.0, std::fabs(theta(i)));
  }
  return h;
}

Status CheckExportable(const Calibration& calibration, int sensor, const TagCalibration& tag) {
  for (const auto* s : {&tag.accel, &tag.gyro}) {
    if (!s->has_value()) continue;
    const SensorCalibration& c = **s;
    // An import's constants without their uncertainties pass on (ExportInterchange says so
    // and writes no covariance); a fit's rejected model does not.
    const bool imported = c.model_check && c.model_check->selection == kImportedSelection;
    if (c.model_check && c.model_check->model_rejected && !imported) {
      return CalibrationErrorAt(
          calibration, CalibrationSensorPath(calibration, sensor, c.model.sensor),
          fmt::format("the {} model is model_rejected ({}): its constants are not exported",
                      ImuSensorLongName(c.model.sensor), c.model_check->reason));
    }
    if (!(c.M().determinant() > 0.0)) {
      return CalibrationErrorAt(
          calibration, CalibrationSensorPath(calibration, sensor, c.model.sensor),
          fmt::format("the {} matrix has det {:.3g}: expected > 0 (a matrix that reverses or "
                      "collapses the axes has no exported form)",
                      ImuSensorLongName(c.model.sensor), c.M().determinant()));
    }
  }
  if (!tag.accel && !tag.gyro) {
    return CalibrationErrorAt(calibration, CalibrationTagPath(calibration, sensor),
                              "the tag has neither an accelerometer nor a gyroscope calibration");
  }
  return {};
}

}  // namespace

const char* InterchangeFormatName(InterchangeFormat format) {
  switch (format) {
    case InterchangeFormat::kKalibr:
      return "kalibr";
    case InterchangeFormat::kOpenVins:
      return "openvins";
    case InterchangeFormat::kBasalt:
      return "basalt";
    case InterchangeFormat::kRealSense:
      return "realsense";
    case InterchangeFormat::kPx4:
      return "px4";
    case InterchangeFormat::kArduPilot:
      return "ardupilot";
  }
  return "";
}

std::optional<InterchangeFormat> ParseInterchangeFormat(std::string_view name) {
  for (InterchangeFormat f :
       {InterchangeFormat::kKalibr, InterchangeFormat::kOpenVins, InterchangeFormat::kBasalt,
        InterchangeFormat::kRealSense, InterchangeFormat::kPx4, InterchangeFormat::kArduPilot}) {
    if (name == InterchangeFormatName(f)) return f;
  }
  return std::nullopt;
}

Result<SiSensorForm> SiForm(const SensorCalibration& calibration) {
  Result<AutopilotSensorForm> units = AutopilotForm(calibration);
  if (!units.ok()) return units.error();
  SiSensorForm f;
  f.matrix = (units.value().output_to_si / units.value().input_to_si) * calibration.M();
  f.bias = units.value().input_to_si * calibration.model.bias;
  return f;
}

Result<InterchangeExport> ExportInterchange(const Calibration& calibration,
                                            const InterchangeExportOptions& options) {
  const TagCalibration* tag = calibration.FindTag(options.sensor);
  if (tag == nullptr) return NoSensorError(calibration, options.sensor);
  if (Status s = CheckExportable(calibration, options.sensor, *tag); !s.ok()) return s.error();
  Result<TagParameters> params = CollectParameters(*tag);
  if (!params.ok()) return params.error();
  const TagParameters& p = params.value();
  const InterchangeFormat format = options.format;
  InterchangeExport e;
  e.format = format;
  const auto values_at = [&](const Eigen::VectorXd& theta) {
    Eigen::Matrix3d r;
    return ii::ValuesFromForms(format, ToFormatFrame(format, BodyForms(p, theta), &r));
  };
  const FramedForms body = BodyForms(p, p.theta);
  const FramedForms framed = ToFormatFrame(format, body, &e.body_from_format);
  const Eigen::VectorXd v = ii::ValuesFromForms(format, framed);
  // realsense: the file holds one imu, imus[0].
  e.values = ii::Layout(format, format == InterchangeFormat::kRealSense ? 0 : options.instance);
  for (size_t i = 0; i < e.values.size(); ++i) e.values[i].value = v(static_cast<Eigen::Index>(i));
  // JCGM 102:2011 6.2.1.3: U_v = C U_theta C^T with C the sensitivity matrix df/dtheta.
  const Eigen::MatrixXd jac = ii::NumericJacobian(values_at, p.theta, Steps(p.theta, p.u));
  e.covariance = jac * p.covariance * jac.transpose();
  e.u = e.covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
  for (const SensorCalibration* c : p.sensors) {
    if (UncertaintyUnknown(*c)) e.uncertainty_known = false;
  }
  const std::string source =
      calibration.source_file.empty() ? "calibration" : calibration.source_file;
  if (format == InterchangeFormat::kPx4 || format == InterchangeFormat::kArduPilot) {
    AutopilotExportOptions ao;
    ao.format =
        format == InterchangeFormat::kPx4 ? AutopilotFormat::kPx4 : AutopilotFormat::kArduPilot;
    ao.sensor = options.sensor;
    ao.instance = options.instance;
    Result<AutopilotExport> ap = ExportAutopilotParameters(calibration, ao);
    if (!ap.ok()) return ap.error();
    e.text = ap.value().text;
    e.warnings = ap.value().warnings;
    return e;
  }
  e.not_held = NotHeld(format, *tag, body, ii::RotationAngle(e.body_from_format));
  const std::vector<std::string> lines = ConventionLines(format, e, source, options.sensor);
  switch (format) {
    case InterchangeFormat::kKalibr:
      e.text = KalibrText(e, v, options.instance, lines);
      break;
    case InterchangeFormat::kOpenVins:
      e.text = OpenVinsText(v, options.instance, lines);
      break;
    case InterchangeFormat::kBasalt:
      e.text = BasaltText(v, lines);
      break;
    default:
      e.text = RealSenseText(v, lines);
      break;
  }
  for (const std::string& n : e.not_held) {
    e.warnings.push_back(fmt::format("sensor {}: {} cannot hold {}", options.sensor,
                                     InterchangeFormatName(format), n));
  }
  if (!e.uncertainty_known) {
    e.warnings.push_back(
        fmt::format("sensor {}: the constants were imported without their "
                    "uncertainties: no covariance sidecar is written",
                    options.sensor));
  }
  return e;
}

std::string InterchangeSidecarPath(const std::string& exported_path) {
  return exported_path + ".covariance.json";
}

std::string InterchangeSidecarJson(const InterchangeExport& e, const std::string& file,
                                   const std::string& calibration_file, int sensor) {
  nlohmann::ordered_json root;
  root["schema"] = "metro.interchange_covariance/1";
  root["format"] = InterchangeFormatName(e.format);
  root["file"] = file;
  root["calibration"] = calibration_file;
  root["sensor"] = sensor;
  root["method"] =
      "cov(v) = J cov(theta) J^T, J = dv/dtheta by central differences at metro's constants "
      "theta (JCGM 102:2011 6.2.1.3; JCGM 100:2008 5.1.2); u = sqrt of the diagonal, k = 1";
  nlohmann::ordered_json values = nlohmann::ordered_json::array();
  for (size_t i = 0; i < e.values.size(); ++i) {
    values.push_back({{"name", e.values[i].name},
                      {"value", e.values[i].value},
                      {"u", e.u(static_cast<Eigen::Index>(i))},
                      {"unit", e.values[i].unit}});
  }
  root["values"] = values;
  nlohmann::ordered_json cov = nlohmann::ordered_json::array();
  for (Eigen::Index r = 0; r < e.covariance.rows(); ++r) {
    nlohmann::ordered_json row = nlohmann::ordered_json::array();
    for (Eigen::Index c = 0; c < e.covariance.cols(); ++c) row.push_back(e.covariance(r, c));
    cov.push_back(row);
  }
  root["covariance"] = cov;
  nlohmann::ordered_json rot = nlohmann::ordered_json::array();
  for (int r = 0; r < 3; ++r) {
    rot.push_back({e.body_from_format(r, 0), e.body_from_format(r, 1), e.body_from_format(r, 2)});
  }
  root["body_from_format"] = rot;
  root["not_held"] = e.not_held;
  return JsonText(root, 2) + "\n";
}

}  // namespace metro
