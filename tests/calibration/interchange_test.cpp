// Calibration interchange (issue #40 step 4): every exported form, applied to the same samples
// with the equation its tool documents (written out here from the sources cited in
// interchange.hpp, not taken from the library), agrees with metro's model to 1e-12; export ->
// import returns the constants; the covariance sidecar agrees with a Monte Carlo and with the
// closed form; implausible and malformed files are flagged or refused at file:line:column.
#include "metro/calibration/interchange.hpp"

#include <Eigen/Dense>
#include <catch2/catch.hpp>
#include <cmath>
#include <random>
#include <string>

#include "calibration/parameter_blocks.hpp"
#include "metro/calibration/calibration_io.hpp"

namespace metro {
namespace {

using PB = calibration_internal::ParameterBlocks;
constexpr double kGn = 9.80665;
constexpr double kDeg = 3.14159265358979323846 / 180.0;  // rad per degree

// A sensor calibration with every free parameter's covariance a known SPD matrix (small u, so
// the conversions are linear over it).
SensorCalibration Sensor(ImuSensor s, ModelKind kind, const std::string& in, bool temperature) {
  SensorCalibration c;
  SensorModel& m = c.model;
  m.sensor = s;
  m.kind = kind;
  m.input_unit = in;
  const bool accel = s == ImuSensor::kAccel;
  m.output_unit = accel ? "g" : "deg/s";
  const double nominal = in == "LSB"                  ? (accel ? 1.0 / 16384.0 : 1.0 / 131.0)
                         : in == "g" || in == "deg/s" ? 1.0
                         : in == "m/s^2"              ? 1.0 / kGn
                                                      : 1.0 / kDeg;
  if (in == "LSB") c.full_scale = accel ? 2.0 : 250.0;
  const double b = in == "LSB" ? 300.0 : accel ? 0.2 : 0.03;
  m.bias = {b, -0.6 * b, 1.3 * b};
  m.scale = nominal * Eigen::Vector3d(1.013, 0.987, 1.021);
  if (kind == ModelKind::kFull) {
    m.misalignment = accel ? std::vector<double>{0.012, -0.008, 0.005}
                           : std::vector<double>{0.004, -0.011, 0.009, 0.006, -0.003, 0.015};
  }
  if (temperature) {
    m.has_temperature = true;
    m.bias_per_c = {0.5, -0.2, 0.1};
    m.t_ref_c = 25.0;
  }
  c.parameter_names = PB::FreeNames(s, kind, temperature);
  const Eigen::Index n = static_cast<Eigen::Index>(c.parameter_names.size());
  Eigen::VectorXd u(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const std::string& name = c.parameter_names[static_cast<size_t>(i)];
    u(i) = name[0] == 'b' ? 1e-3 * b : name[0] == 'k' ? 2e-4 * nominal : 1e-4;
  }
  Eigen::MatrixXd corr = Eigen::MatrixXd::Identity(n, n);
  for (Eigen::Index i = 0; i + 1 < n; ++i) corr(i, i + 1) = corr(i + 1, i) = 0.3;
  c.covariance = u.asDiagonal() * corr * u.asDiagonal();
  DeriveUncertainties(&c);
  return c;
}

Calibration Cal(ModelKind accel, ModelKind gyro, const std::string& accel_in,
                const std::string& gyro_in, bool temperature = false) {
  Calibration cal;
  TagCalibration t;
  t.sensor = 3;
  t.accel = Sensor(ImuSensor::kAccel, accel, accel_in, temperature);
  t.gyro = Sensor(ImuSensor::kGyro, gyro, gyro_in, temperature);
  cal.tags.push_back(t);
  return cal;
}

double UnitToSi(const std::string& u, bool accel, const SensorCalibration& c) {
  if (u == "LSB") return *c.full_scale / 32768.0 * (accel ? kGn : kDeg);
  if (u == "g") return kGn;
  if (u == "deg/s") return kDeg;
  return 1.0;
}

// metro's model in SI: (output in SI, data in SI) for a raw sample.
struct MetroSi {
  const SensorCalibration& c;
  Eigen::Vector3d Data(const Eigen::Vector3d& raw) const {
    return UnitToSi(c.model.input_unit, c.model.sensor == ImuSensor::kAccel, c) * raw;
  }
  Eigen::Vector3d Out(const Eigen::Vector3d& raw) const {
    return UnitToSi(c.model.output_unit, c.model.sensor == ImuSensor::kAccel, c) *
           c.model.Apply(raw, c.model.t_ref_c);
  }
};

std::vector<Eigen::Vector3d> Raw(const SensorCalibration& c, int n, unsigned seed) {
  std::mt19937_64 rng(seed);
  const double range = c.model.input_unit == "LSB"           ? 30000.0
                       : c.model.sensor == ImuSensor::kAccel ? 20.0
                                                             : 6.0;
  std::uniform_real_distribution<double> u(-range, range);
  std::vector<Eigen::Vector3d> out;
  for (int i = 0; i < n; ++i) out.emplace_back(u(rng), u(rng), u(rng));
  return out;
}

InterchangeFile ReadBack(const InterchangeExport& e, InterchangeFormat f) {
  InterchangeReadOptions o;
  o.format = f;
  Result<InterchangeFile> r = ReadInterchangeFile(e.text, o, "exported");
  INFO((r.ok() ? "" : r.error().ToString()));
  REQUIRE(r.ok());
  return r.value();
}

// A number of the file by name.
double V(const InterchangeFile& f, const std::string& name) {
  for (const InterchangeValue& v : f.values) {
    if (v.name == name) return v.value;
  }
  FAIL("no value " << name);
  return 0.0;
}

Eigen::Matrix3d M(const InterchangeFile& f, const std::string& name) {
  Eigen::Matrix3d m;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c)
      m(r, c) = V(f, name + "[" + std::to_string(r) + "][" + std::to_string(c) + "]");
  }
  return m;
}

Eigen::VectorXd Arr(const InterchangeFile& f, const std::string& name, int n) {
  Eigen::VectorXd v(n);
  for (int i = 0; i < n; ++i) v(i) = V(f, name + "[" + std::to_string(i) + "]");
  return v;
}

// The tool's output for one accelerometer and one gyroscope sample, in the file's frame,
// from the numbers the file holds; b_a, b_g: the estimator's bias states (Kalibr, OpenVINS).
struct ToolOut {
  Eigen::Vector3d a, w;
};

ToolOut ApplyTool(InterchangeFormat fmt, const InterchangeFile& f, const Eigen::Vector3d& a_raw,
                  const Eigen::Vector3d& w_raw, const Eigen::Vector3d& b_a,
                  const Eigen::Vector3d& b_g) {
  ToolOut o;
  switch (fmt) {
    case InterchangeFormat::kKalibr: {
      // IccScaledMisalignedImu: a_raw = M_a a_i + b_a; w_raw = M_g C w_i + A C a_i + b_g.
      const Eigen::Matrix3d m_a = M(f, "imu0.accelerometers.M"), m_g = M(f, "imu0.gyroscopes.M");
      const Eigen::Matrix3d a = M(f, "imu0.gyroscopes.A"), c = M(f, "imu0.gyroscopes.C_gyro_i");
      o.a = m_a.lu().solve(a_raw - b_a);
      o.w = c.transpose() * m_g.lu().solve(w_raw - b_g - a * c * o.a);
      break;
    }
    case InterchangeFormat::kOpenVins: {
      // w_I = R_IMUtoGYRO^T Tw^-1 (w_m - Tg a_I - b_g); a_I = R_IMUtoACC^T Ta^-1 (a_m - b_a).
      o.a = M(f, "imu0.R_IMUtoACC").transpose() * M(f, "imu0.Ta").lu().solve(a_raw - b_a);
      o.w = M(f, "imu0.R_IMUtoGYRO").transpose() *
            M(f, "imu0.Tw").lu().solve(w_raw - M(f, "imu0.Tg") * o.a - b_g);
      break;
    }
    case InterchangeFormat::kBasalt: {
      // calib_bias.hpp: a_c = (I + S) a_r - b, S = [[s1,0,0],[s2,s4,0],[s3,s5,s6]];
      // w_c = (I + S) w_r - b, S = [[s1,s4,s7],[s2,s5,s8],[s3,s6,s9]].
      const Eigen::VectorXd ab = Arr(f, "value0.calib_accel_bias", 9);
      const Eigen::VectorXd gb = Arr(f, "value0.calib_gyro_bias", 12);
      Eigen::Matrix3d s;
      s << ab(3), 0, 0, ab(4), ab(6), 0, ab(5), ab(7), ab(8);
      o.a = a_raw + s * a_raw - ab.head<3>();
      s << gb(3), gb(6), gb(9), gb(4), gb(7), gb(10), gb(5), gb(8), gb(11);
      o.w = w_raw + s * w_raw - gb.head<3>();
      break;
    }
    case InterchangeFormat::kRealSense: {
      // rs-imu-calibration.py check_X: fixed = raw . X[:3,:3] - X[3,:] (a row vector times X).
      const Eigen::VectorXd sa = Arr(f, "imus[0].accelerometer.scale_and_alignment", 9);
      const Eigen::VectorXd sg = Arr(f, "imus[0].gyroscope.scale_and_alignment", 9);
      for (int j = 0; j < 3; ++j) {
        o.a(j) = a_raw(0) * sa(j) + a_raw(1) * sa(3 + j) + a_raw(2) * sa(6 + j) -
                 V(f, "imus[0].accelerometer.bias[" + std::to_string(j) + "]");
        o.w(j) = w_raw(0) * sg(j) + w_raw(1) * sg(3 + j) + w_raw(2) * sg(6 + j) -
                 V(f, "imus[0].gyroscope.bias[" + std::to_string(j) + "]");
      }
      break;
    }
    default: {
      // PX4 / ArduPilot: corrected = (data - offset) .* scale; gyroscope data - offset.
      const char* const axes[3] = {"X", "Y", "Z"};
      const bool px4 = fmt == InterchangeFormat::kPx4;
      for (int j = 0; j < 3; ++j) {
        const std::string x = axes[j];
        o.a(j) = (a_raw(j) - V(f, px4 ? "CAL_ACC0_" + x + "OFF" : "INS_ACCOFFS_" + x)) *
                 V(f, px4 ? "CAL_ACC0_" + x + "SCALE" : "INS_ACCSCAL_" + x);
        o.w(j) = w_raw(j) - V(f, px4 ? "CAL_GYRO0_" + x + "OFF" : "INS_GYROFFS_" + x);
      }
      break;
    }
  }
  return o;
}

// Every sample through both forms: the largest |metro - R tool| / |metro|.
double WorstDisagreement(const Calibration& cal, InterchangeFormat fmt) {
  InterchangeExportOptions o;
  o.format = fmt;
  o.sensor = 3;
  Result<InterchangeExport> e = ExportInterchange(cal, o);
  INFO((e.ok() ? "" : e.error().ToString()));
  REQUIRE(e.ok());
  const InterchangeFile f = ReadBack(e.value(), fmt);
  const TagCalibration& t = cal.tags[0];
  const MetroSi ma{*t.accel}, mg{*t.gyro};
  const Eigen::Vector3d b_a = ma.Data(t.accel->model.bias), b_g = mg.Data(t.gyro->model.bias);
  const Eigen::Matrix3d r = e.value().body_from_format;
  CHECK((r.transpose() * r - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() < 1e-15);
  const std::vector<Eigen::Vector3d> as = Raw(*t.accel, 300, 1), ws = Raw(*t.gyro, 300, 2);
  double worst = 0.0;
  for (size_t i = 0; i < as.size(); ++i) {
    const ToolOut tool = ApplyTool(fmt, f, ma.Data(as[i]), mg.Data(ws[i]), b_a, b_g);
    const Eigen::Vector3d a = ma.Out(as[i]), w = mg.Out(ws[i]);
    worst = std::max(worst, (a - r * tool.a).norm() / a.norm());
    worst = std::max(worst, (w - r * tool.w).norm() / w.norm());
  }
  return worst;
}

TEST_CASE("Interchange: each exported form applied as its tool defines it agrees with metro",
          "[calibration][interchange]") {
  for (InterchangeFormat fmt : {InterchangeFormat::kKalibr, InterchangeFormat::kOpenVins,
                                InterchangeFormat::kBasalt, InterchangeFormat::kRealSense}) {
    INFO(InterchangeFormatName(fmt));
    CHECK(WorstDisagreement(Cal(ModelKind::kFull, ModelKind::kFull, "m/s^2", "rad/s"), fmt) <=
          1e-12);
    // Raw counts with their full scale, and a temperature term (the bias at t_ref is written).
    CHECK(WorstDisagreement(Cal(ModelKind::kFull, ModelKind::kFull, "LSB", "LSB", true), fmt) <=
          1e-12);
    CHECK(WorstDisagreement(Cal(ModelKind::kScale, ModelKind::kFull, "g", "deg/s"), fmt) <= 1e-12);
  }
  // The autopilots hold what a scale model and a gyroscope bias are.
  for (InterchangeFormat fmt : {InterchangeFormat::kPx4, InterchangeFormat::kArduPilot}) {
    INFO(InterchangeFormatName(fmt));
    Calibration cal = Cal(ModelKind::kScale, ModelKind::kBias, "m/s^2", "rad/s");
    cal.tags[0].gyro->model.scale = Eigen::Vector3d::Constant(1.0 / kDeg);
    CHECK(WorstDisagreement(cal, fmt) <= 1e-12);
  }
}

TEST_CASE("Interchange: the lower-triangular formats turn the frame by R, named",
          "[calibration][interchange]") {
  const Calibration cal = Cal(ModelKind::kFull, ModelKind::kFull, "m/s^2", "rad/s");
  InterchangeExportOptions o;
  o.sensor = 3;
  o.format = InterchangeFormat::kBasalt;
  const Result<InterchangeExport> e = ExportInterchange(cal, o);
  REQUIRE(e.ok());
  // metro's M_a = R L: R^T M_a is lower triangular, so R's angle is of the order of the
  // accelerometer's misalignment terms (0.012, -0.008, 0.005 rad here).
  const Eigen::Matrix3d l =
      e.value().body_from_format.transpose() * SiForm(*cal.tags[0].accel).value().matrix;
  CHECK(std::fabs(l(0, 1)) + std::fabs(l(0, 2)) + std::fabs(l(1, 2)) < 1e-15);
  CHECK_THAT(e.value().text, Catch::Contains("a turn of"));
  bool named = false;
  for (const std::string& w : e.value().warnings)
    named |= w.find("body frame") != std::string::npos;
  CHECK(named);
  // A scale model has no misalignment: no turn, nothing said.
  const Calibration diag = Cal(ModelKind::kScale, ModelKind::kFull, "m/s^2", "rad/s");
  const Result<InterchangeExport> d = ExportInterchange(diag, o);
  REQUIRE(d.ok());
  CHECK(d.value().body_from_format == Eigen::Matrix3d::Identity());
}

// Export, read the text back, import: metro's constants again.
InterchangeImport RoundTrip(const Calibration& cal, InterchangeFormat fmt, bool sidecar) {
  InterchangeExportOptions o;
  o.format = fmt;
  o.sensor = 3;
  Result<InterchangeExport> e = ExportInterchange(cal, o);
  REQUIRE(e.ok());
  const InterchangeFile f = ReadBack(e.value(), fmt);
  InterchangeImportOptions io;
  io.sensor = 3;
  if (sidecar) {
    io.sidecar_text = InterchangeSidecarJson(e.value(), "exported", "calibration.json", 3);
    io.sidecar_file = "exported.covariance.json";
  }
  Result<InterchangeImport> imp = ImportInterchange(f, io);
  INFO((imp.ok() ? "" : imp.error().ToString()));
  REQUIRE(imp.ok());
  return imp.value();
}

void CheckSame(double a, double b) {
  CHECK(std::fabs(a - b) <= 1e-12 * std::max(std::fabs(a), std::fabs(b)));
}

TEST_CASE("Interchange: export -> import returns metro's constants to 1e-12",
          "[calibration][interchange]") {
  const Calibration cal = Cal(ModelKind::kFull, ModelKind::kFull, "m/s^2", "rad/s");
  for (InterchangeFormat fmt : {InterchangeFormat::kKalibr, InterchangeFormat::kOpenVins,
                                InterchangeFormat::kBasalt, InterchangeFormat::kRealSense}) {
    INFO(InterchangeFormatName(fmt));
    const InterchangeImport imp = RoundTrip(cal, fmt, false);
    const TagCalibration& t = imp.calibration.tags[0];
    for (const auto* pair : {&t.accel, &t.gyro}) {
      const SensorModel& got = (*pair)->model;
      const SensorModel& want = (pair == &t.accel ? cal.tags[0].accel : cal.tags[0].gyro)->model;
      CHECK(got.kind == ModelKind::kFull);
      for (int a = 0; a < 3; ++a) {
        CheckSame(got.scale(a), want.scale(a));
        // Kalibr and OpenVINS carry no bias: 0, named.
        if (fmt == InterchangeFormat::kBasalt || fmt == InterchangeFormat::kRealSense) {
          CheckSame(got.bias(a), want.bias(a));
        } else {
          CHECK(got.bias(a) == 0.0);
        }
      }
      REQUIRE(got.misalignment.size() == want.misalignment.size());
      for (size_t i = 0; i < got.misalignment.size(); ++i)
        CheckSame(got.misalignment[i], want.misalignment[i]);
    }
    // No sidecar: the u are unknown, and the gate of model_rejected says so.
    CHECK_FALSE(imp.uncertainty_known);
    CHECK(t.accel->model_check->model_rejected);
    CHECK_THAT(t.accel->model_check->reason, Catch::Contains("uncertaint"));
    // The import passes on to another format, without a sidecar (its u are not known).
    InterchangeExportOptions again;
    again.format = InterchangeFormat::kBasalt;
    again.sensor = 3;
    const Result<InterchangeExport> onward = ExportInterchange(imp.calibration, again);
    REQUIRE(onward.ok());
    CHECK_FALSE(onward.value().uncertainty_known);
    // calibration.json reads back.
    const Result<Calibration> back =
        CalibrationFromJson(FormatCalibrationJson(imp.calibration), "imported.json");
    INFO((back.ok() ? "" : back.error().ToString()));
    CHECK(back.ok());
  }
}

TEST_CASE("Interchange: PX4 and ArduPilot parameters round trip what they hold",
          "[calibration][interchange]") {
  Calibration cal = Cal(ModelKind::kScale, ModelKind::kBias, "m/s^2", "rad/s");
  cal.tags[0].gyro->model.scale = Eigen::Vector3d::Constant(1.0 / kDeg);
  for (InterchangeFormat fmt : {InterchangeFormat::kPx4, InterchangeFormat::kArduPilot}) {
    INFO(InterchangeFormatName(fmt));
    const InterchangeImport imp = RoundTrip(cal, fmt, true);
    CHECK(imp.uncertainty_known);
    const TagCalibration& t = imp.calibration.tags[0];
    CHECK(t.accel->model.kind == ModelKind::kScale);
    CHECK(t.gyro->model.kind == ModelKind::kBias);
    for (int a = 0; a < 3; ++a) {
      CheckSame(t.accel->model.bias(a), cal.tags[0].accel->model.bias(a));
      CheckSame(t.accel->model.scale(a), cal.tags[0].accel->model.scale(a));
      CheckSame(t.gyro->model.bias(a), cal.tags[0].gyro->model.bias(a));
      CHECK(t.accel->bias_u(a) == Approx(cal.tags[0].accel->bias_u(a)).epsilon(1e-6));
      CHECK(t.accel->scale_u(a) == Approx(cal.tags[0].accel->scale_u(a)).epsilon(1e-6));
    }
  }
}

TEST_CASE("Interchange: the sidecar's covariance agrees with the closed form and a Monte Carlo",
          "[calibration][interchange]") {
  // PX4: offset = b, scale = k c_out / c_in (m/s^2 in, g out): u exactly c_out u(k).
  Calibration lin = Cal(ModelKind::kScale, ModelKind::kBias, "m/s^2", "rad/s");
  lin.tags[0].gyro->model.scale = Eigen::Vector3d::Constant(1.0 / kDeg);
  InterchangeExportOptions o;
  o.format = InterchangeFormat::kPx4;
  o.sensor = 3;
  Result<InterchangeExport> p = ExportInterchange(lin, o);
  REQUIRE(p.ok());
  for (int a = 0; a < 3; ++a) {
    CHECK(p.value().u(a) == Approx(lin.tags[0].accel->bias_u(a)).epsilon(1e-8));
    CHECK(p.value().u(3 + a) == Approx(kGn * lin.tags[0].accel->scale_u(a)).epsilon(1e-8));
    CHECK(p.value().u(6 + a) == Approx(lin.tags[0].gyro->bias_u(a)).epsilon(1e-8));
  }
  // basalt (products and a rotation): J cov J^T against 4000 draws of metro's constants.
  const Calibration cal = Cal(ModelKind::kFull, ModelKind::kFull, "m/s^2", "rad/s");
  o.format = InterchangeFormat::kBasalt;
  Result<InterchangeExport> e = ExportInterchange(cal, o);
  REQUIRE(e.ok());
  const int n = static_cast<int>(e.value().values.size());
  std::mt19937_64 rng(11);
  std::normal_distribution<double> z(0.0, 1.0);
  const int draws = 4000;
  Eigen::MatrixXd samples(draws, n);
  for (int d = 0; d < draws; ++d) {
    Calibration c = cal;
    for (auto* s : {&c.tags[0].accel, &c.tags[0].gyro}) {
      SensorCalibration& sc = **s;
      const Eigen::MatrixXd l = sc.covariance.llt().matrixL();
      Eigen::VectorXd x(l.rows());
      for (Eigen::Index i = 0; i < x.size(); ++i) x(i) = z(rng);
      const Eigen::VectorXd dx = l * x;
      for (Eigen::Index i = 0; i < dx.size(); ++i) {
        const std::string& name = sc.parameter_names[static_cast<size_t>(i)];
        SensorModel& m = sc.model;
        const int axis = name.back() - 'x';
        if (name[0] == 'b')
          m.bias(axis) += dx(i);
        else if (name[0] == 'k')
          m.scale(axis) += dx(i);
        else
          m.misalignment[static_cast<size_t>(i - 6)] += dx(i);
      }
    }
    Result<InterchangeExport> ed = ExportInterchange(c, o);
    REQUIRE(ed.ok());
    for (int k = 0; k < n; ++k) samples(d, k) = ed.value().values[static_cast<size_t>(k)].value;
  }
  const Eigen::RowVectorXd mean = samples.colwise().mean();
  const Eigen::MatrixXd centred = samples.rowwise() - mean;
  const Eigen::MatrixXd mc = centred.transpose() * centred / (draws - 1);
  // The standard error of a standard deviation from 4000 draws is 1.1 %: 5 % is 4.4 of them.
  for (int k = 0; k < n; ++k) {
    INFO(e.value().values[static_cast<size_t>(k)].name);
    CHECK(std::sqrt(mc(k, k)) == Approx(e.value().u(k)).epsilon(0.05));
  }
}

TEST_CASE("Interchange: the sidecar carries the covariance back through the import",
          "[calibration][interchange]") {
  const Calibration cal = Cal(ModelKind::kFull, ModelKind::kFull, "m/s^2", "rad/s");
  for (InterchangeFormat fmt : {InterchangeFormat::kBasalt, InterchangeFormat::kRealSense}) {
    INFO(InterchangeFormatName(fmt));
    const InterchangeImport imp = RoundTrip(cal, fmt, true);
    CHECK(imp.uncertainty_known);
    const TagCalibration& t = imp.calibration.tags[0];
    CHECK_FALSE(t.accel->model_check->model_rejected);
    for (const auto* s : {&t.accel, &t.gyro}) {
      const Eigen::MatrixXd& got = (*s)->covariance;
      const Eigen::MatrixXd& want =
          (s == &t.accel ? cal.tags[0].accel : cal.tags[0].gyro)->covariance;
      REQUIRE(got.rows() == want.rows());
      for (Eigen::Index i = 0; i < got.rows(); ++i) {
        for (Eigen::Index j = 0; j < got.cols(); ++j) {
          CHECK(std::fabs(got(i, j) - want(i, j)) <= 1e-6 * std::sqrt(want(i, i) * want(j, j)));
        }
      }
    }
  }
  // Kalibr carries no bias: with the sidecar the u of the rest are known, the biases' are not.
  const InterchangeImport k = RoundTrip(cal, InterchangeFormat::kKalibr, true);
  CHECK_FALSE(k.uncertainty_known);
  CHECK(k.calibration.tags[0].gyro->misalignment_u[0] ==
        Approx(cal.tags[0].gyro->misalignment_u[0]).epsilon(1e-6));
}

TEST_CASE("Interchange: a sidecar that belongs to another export is refused at its position",
          "[calibration][interchange]") {
  const Calibration cal = Cal(ModelKind::kFull, ModelKind::kFull, "m/s^2", "rad/s");
  InterchangeExportOptions o;
  o.format = InterchangeFormat::kBasalt;
  o.sensor = 3;
  const Result<InterchangeExport> e = ExportInterchange(cal, o);
  REQUIRE(e.ok());
  InterchangeReadOptions ro;
  ro.format = InterchangeFormat::kBasalt;
  Result<InterchangeFile> f = ReadInterchangeFile(e.value().text, ro, "c.json");
  REQUIRE(f.ok());
  InterchangeImportOptions io;
  io.sidecar_text = InterchangeSidecarJson(e.value(), "c.json", "cal.json", 3);
  io.sidecar_file = "c.json.covariance.json";
  // The file edited after the export: its first value no longer the sidecar's.
  f.value().values[0].value += 1e-6;
  Result<InterchangeImport> r = ImportInterchange(f.value(), io);
  REQUIRE_FALSE(r.ok());
  CHECK_THAT(r.error().ToString(), Catch::StartsWith("c.json.covariance.json:"));
  CHECK_THAT(r.error().ToString(), Catch::Contains("values[0].value: expected"));
  CHECK_THAT(r.error().ToString(), Catch::Contains("the sidecar belongs to another export"));
  // Another format's sidecar.
  o.format = ro.format = InterchangeFormat::kRealSense;
  const Result<InterchangeExport> rs = ExportInterchange(cal, o);
  REQUIRE(rs.ok());
  f = ReadInterchangeFile(rs.value().text, ro, "c.json");
  REQUIRE(f.ok());
  r = ImportInterchange(f.value(), io);
  REQUIRE_FALSE(r.ok());
  CHECK_THAT(r.error().ToString(), Catch::Contains("format: expected \"realsense\""));
}

InterchangeFile Read(const std::string& text, InterchangeFormat fmt, Error* error = nullptr) {
  InterchangeReadOptions o;
  o.format = fmt;
  Result<InterchangeFile> r = ReadInterchangeFile(text, o, "in.txt");
  if (error != nullptr) {
    REQUIRE_FALSE(r.ok());
    *error = r.error();
    return {};
  }
  INFO((r.ok() ? "" : r.error().ToString()));
  REQUIRE(r.ok());
  return r.value();
}

std::string ReadError(const std::string& text, InterchangeFormat fmt) {
  Error e;
  Read(text, fmt, &e);
  return e.ToString();
}

const char* const kKalibr334 = R"(imu0:
  T_i_b:
  - [1.0, 0.0, 0.0, 0.0]
  - [0.0, 1.0, 0.0, 0.0]
  - [0.0, 0.0, 1.0, 0.0]
  - [0.0, 0.0, 0.0, 1.0]
  accelerometer_noise_density: 0.0186
  accelerometer_random_walk: 0.000433
  gyroscope_noise_density: 0.00187
  gyroscope_random_walk: 2.66e-05
  model: scale-misalignment
  rostopic: /imu0
  time_offset: 0.0
  update_rate: 200.0
  accelerometers:
    M:
    - [1.002, 0.0, 0.0]
    - [0.001, 0.998, 0.0]
    - [-0.002, 0.003, 1.004]
  gyroscopes:
    A:
    - [0.0, 0.0, 0.0]
    - [0.0, 0.0, 0.0]
    - [0.0, 0.0, 0.0]
    C_gyro_i:
    - [1.0, 0.0, 0.0]
    - [0.0, 1.0, 0.0]
    - [0.0, 0.0, 1.0]
    M:
    - [0.45, 0.0, 0.0]
    - [0.01, 0.47, 0.0]
    - [0.0, 0.02, 0.44]
)";

TEST_CASE("Interchange: a Kalibr result with gyroscope gains 0.45 (Kalibr issue #334) is flagged",
          "[calibration][interchange]") {
  const InterchangeFile f = Read(kKalibr334, InterchangeFormat::kKalibr);
  CHECK(f.model == "scale-misalignment");
  const Result<InterchangeImport> imp = ImportInterchange(f, {});
  REQUIRE(imp.ok());
  std::string flags;
  for (const std::string& s : imp.value().flags) flags += s + "\n";
  INFO(flags);
  // The calibrated gain is 1 / 0.45 = 2.2222 (Kalibr's M is true -> measured).
  CHECK_THAT(flags, Catch::Contains("implausible gyroscope gain: imu0.gyroscopes.M[0][0] = "
                                    "0.45 makes the calibrated gain on x 2.22"));
  CHECK_THAT(flags, Catch::Contains("imu0.gyroscopes.M[2][2] = 0.44"));
  CHECK_THAT(flags, Catch::Contains("Kalibr issue #334"));
  CHECK(flags.find("accelerometer gain") == std::string::npos);
  // The same file with gains 1.01: nothing flagged.
  std::string good = kKalibr334;
  for (const char* g : {"0.45", "0.47", "0.44"}) good.replace(good.find(g), 4, "1.01");
  const Result<InterchangeImport> ok =
      ImportInterchange(Read(good, InterchangeFormat::kKalibr), {});
  REQUIRE(ok.ok());
  CHECK(ok.value().flags.empty());
  // The noise keys are known, not constants: noted.
  bool noted = false;
  for (const std::string& n : ok.value().not_carried) noted |= n.find("gyroscope_random_walk") == 0;
  CHECK(noted);
}

TEST_CASE("Interchange: values outside physical sense are refused at their position",
          "[calibration][interchange]") {
  // basalt s1 = -1.2: the x gain 1 + s1 = -0.2.
  const std::string basalt =
      "{\"value0\": {\"calib_accel_bias\": [0, 0, 0, -1.2, 0, 0, 0, 0, 0],\n"
      "  \"calib_gyro_bias\": [0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0]}}";
  Result<InterchangeImport> r = ImportInterchange(Read(basalt, InterchangeFormat::kBasalt), {});
  REQUIRE_FALSE(r.ok());
  CHECK_THAT(
      r.error().ToString(),
      Catch::StartsWith("in.txt:1:43: value0.calib_accel_bias[3] = -1.2: the accelerometer's "
                        "gain on x is -0.2: expected > 0"));
  // realsense: a gyroscope matrix with two equal rows is singular.
  const std::string rs =
      "{\"imus\": [{\"accelerometer\": {\"bias\": [0, 0, 0], \"scale_and_alignment\": [1, 0, 0, 0, "
      "1, 0, 0, 0, 1]},\n \"gyroscope\": {\"bias\": [0, 0, 0], \"scale_and_alignment\": [1, 0.5, "
      "0, 1, 0.5, 0, 0, 0, 1]}}]}";
  r = ImportInterchange(Read(rs, InterchangeFormat::kRealSense), {});
  REQUIRE_FALSE(r.ok());
  CHECK_THAT(r.error().ToString(), Catch::Contains("in.txt:2:"));
  CHECK_THAT(r.error().ToString(), Catch::Contains("the gyroscope's matrix"));
  CHECK_THAT(r.error().ToString(), Catch::Contains("no physical sense"));
  // A PX4 scale of 0.
  const std::string px4 =
      "1\t1\tCAL_ACC0_XOFF\t0.1\t9\n1\t1\tCAL_ACC0_YOFF\t0\t9\n1\t1\tCAL_ACC0_ZOFF\t0\t9\n"
      "1\t1\tCAL_ACC0_XSCALE\t1\t9\n1\t1\tCAL_ACC0_YSCALE\t0\t9\n1\t1\tCAL_ACC0_ZSCALE\t1\t9\n";
  r = ImportInterchange(Read(px4, InterchangeFormat::kPx4), {});
  REQUIRE_FALSE(r.ok());
  CHECK_THAT(r.error().ToString(), Catch::StartsWith("in.txt:5:21: CAL_ACC0_YSCALE = 0"));
}

TEST_CASE("Interchange: a gain that is the ratio of two units is named as such",
          "[calibration][interchange]") {
  // rs-imu-calibration fitted to data in g while the device gives m/s^2: gains 1/9.80665.
  const std::string rs =
      "{\"imus\": [{\"accelerometer\": {\"bias\": [0, 0, 0], \"scale_and_alignment\": "
      "[0.10197, 0, 0, 0, 0.10197, 0, 0, 0, 0.10197]},\n \"gyroscope\": {\"bias\": [0, 0, 0], "
      "\"scale_and_alignment\": [1, 0, 0, 0, 1, 0, 0, 0, 1]}}]}";
  const Result<InterchangeImport> r =
      ImportInterchange(Read(rs, InterchangeFormat::kRealSense), {});
  REQUIRE(r.ok());
  REQUIRE(r.value().flags.size() == 3);
  CHECK_THAT(r.value().flags[0],
             Catch::StartsWith("implausible accelerometer gain: "
                               "imus[0].accelerometer.scale_and_alignment[0] = 0.10197"));
  CHECK_THAT(r.value().flags[0],
             Catch::Contains("the ratio of m/s^2 to g: data in the wrong unit?"));
}

TEST_CASE("Interchange: malformed files give file:line:column and what was expected",
          "[calibration][interchange]") {
  std::string unknown = kKalibr334;
  unknown.replace(unknown.find("  rostopic"), 0, "  updte_rate: 2\n");
  CHECK(ReadError(unknown, InterchangeFormat::kKalibr) ==
        "in.txt:12:3: imu0.updte_rate: unknown key (nearest: update_rate); expected one of: T_i_b, "
        "accelerometer_noise_density, accelerometer_random_walk, accelerometers, "
        "gyroscope_noise_density, gyroscope_random_walk, gyroscopes, model, rostopic, "
        "time_offset, update_rate");
  std::string missing = kKalibr334;
  missing.erase(missing.find("    C_gyro_i:"),
                missing.find("    M:\n    - [0.45") - missing.find("    C_gyro_i:"));
  CHECK_THAT(ReadError(missing, InterchangeFormat::kKalibr),
             Catch::StartsWith("in.txt:21:5: imu0.gyroscopes.C_gyro_i: missing (a 3 x 3 matrix)"));
  std::string text = kKalibr334;
  text.replace(text.find("0.47"), 4, "x.47");
  CHECK(ReadError(text, InterchangeFormat::kKalibr) ==
        "in.txt:31:14: imu0.gyroscopes.M[1][1]: expected a number, found the string \"x.47\"");
  std::string rot = kKalibr334;
  rot.replace(rot.find("    - [0.0, 1.0, 0.0]\n    - [0.0, 0.0, 1.0]\n    M"), 13, "    - [0.0, 2");
  CHECK_THAT(
      ReadError(rot, InterchangeFormat::kKalibr),
      Catch::StartsWith("in.txt:26:5: imu0.gyroscopes.C_gyro_i: expected a rotation matrix"));
  CHECK_THAT(ReadError("imu0:\n  model: [1, 2\n", InterchangeFormat::kKalibr),
             Catch::StartsWith("in.txt:3:1: invalid YAML"));
  CHECK_THAT(
      ReadError("imu0:\n  model: scale-misalignment\n  Tw: &a [1]\n", InterchangeFormat::kOpenVins),
      Catch::Contains("in.txt:3:7: a YAML anchor"));
  CHECK_THAT(ReadError("imu0:\n  model: kalibr\n", InterchangeFormat::kOpenVins),
             Catch::StartsWith("in.txt:2:3: imu0.Tw: missing (a 3 x 3 matrix)"));
  CHECK_THAT(
      ReadError("{\"value0\": {\"calib_accel_bias\": [1, 2]}}", InterchangeFormat::kBasalt),
      Catch::StartsWith("in.txt:1:33: value0.calib_accel_bias: expected an array of 9 numbers"));
  CHECK_THAT(ReadError("{\"value0\": {\"calib_acel_bias\": []}}", InterchangeFormat::kBasalt),
             Catch::StartsWith(
                 "in.txt:1:32: value0.calib_acel_bias: unknown key (nearest: calib_accel_bias)"));
  CHECK_THAT(ReadError("CAL_ACC0_XOFF,1\n", InterchangeFormat::kPx4),
             Catch::StartsWith("in.txt:1:1: missing parameter CAL_ACC0_YOFF"));
  CHECK(ReadError("INS_ACCOFFS_X,0.1\nINS_ACCOFFS_Y 1e\n", InterchangeFormat::kArduPilot) ==
        "in.txt:2:15: INS_ACCOFFS_Y: expected a number, found \"1e\"");
  CHECK_THAT(ReadError("# header\nINS_ACCOFFS_X 0.1 9 x\n", InterchangeFormat::kArduPilot),
             Catch::StartsWith("in.txt:2:1: expected `NAME,VALUE` (ArduPilot)"));
}

TEST_CASE("Interchange: OpenVINS's %YAML:1.0 header and an rpng model are read",
          "[calibration][interchange]") {
  // rpng: Tw, Ta upper triangular, R_IMUtoGYRO = I; w_I = Tw^-1 w_m, a_I = R^T Ta^-1 a_m.
  const std::string text =
      "%YAML:1.0\n---\nimu0:\n  model: rpng\n"
      "  Tw:\n    - [1.01, 0.002, 0.001]\n    - [0, 0.99, -0.003]\n    - [0, 0, 1.02]\n"
      "  R_IMUtoGYRO:\n    - [1, 0, 0]\n    - [0, 1, 0]\n    - [0, 0, 1]\n"
      "  Ta:\n    - [0.98, 0.004, 0]\n    - [0, 1.01, 0.002]\n    - [0, 0, 1.0]\n"
      "  R_IMUtoACC:\n    - [0.9998000066665778, -0.019998666693333080, 0]\n"
      "    - [0.019998666693333080, 0.9998000066665778, 0]\n    - [0, 0, 1]\n"
      "  Tg:\n    - [0, 0, 0]\n    - [0, 0, 0]\n    - [0, 0, 0]\n";
  const InterchangeFile f = Read(text, InterchangeFormat::kOpenVins);
  CHECK(f.model == "rpng");
  const Result<InterchangeImport> imp = ImportInterchange(f, {});
  REQUIRE(imp.ok());
  // metro's body frame is the accelerometer's: a_B = body_from_format a_I, and metro's
  // accelerometer applied to a sample equals R a_I.
  const SensorModel& a = imp.value().calibration.tags[0].accel->model;
  const SensorModel& g = imp.value().calibration.tags[0].gyro->model;
  const Eigen::Matrix3d r = imp.value().body_from_format;
  Eigen::Matrix3d rot = Eigen::Matrix3d::Identity();
  rot << 0.9998000066665778, -0.019998666693333080, 0, 0.019998666693333080, 0.9998000066665778, 0,
      0, 0, 1;
  Eigen::Matrix3d ta, tw;
  ta << 0.98, 0.004, 0, 0, 1.01, 0.002, 0, 0, 1.0;
  tw << 1.01, 0.002, 0.001, 0, 0.99, -0.003, 0, 0, 1.02;
  const Eigen::Vector3d am(1.0, -9.0, 3.0), wm(0.3, -0.2, 0.1);
  const Eigen::Vector3d a_i = rot.transpose() * ta.lu().solve(am);
  const Eigen::Vector3d w_i = tw.lu().solve(wm);
  CHECK((kGn * a.Apply(am) - r * a_i).norm() <= 1e-12 * a_i.norm());
  CHECK((kDeg * g.Apply(wm) - r * w_i).norm() <= 1e-12 * w_i.norm());
}

}  // namespace
}  // namespace metro
