// A tag's calibration as PX4 and ArduPilot parameters (issue #40 step 4): each form applied to
// the same samples as metro's model agrees to double rounding where the form can hold the
// model, and the stated size of what it cannot hold is the largest difference found.
#include "metro/calibration/autopilot_export.hpp"

#include <Eigen/SVD>
#include <catch2/catch.hpp>
#include <cmath>
#include <map>
#include <random>
#include <sstream>
#include <string>

#include "metro/calibration/calibration_io.hpp"

namespace metro {
namespace {

constexpr double kGn = 9.80665;
constexpr double kRad = 3.14159265358979323846 / 180.0;

SensorCalibration Accel(bool misaligned) {
  SensorCalibration c;
  c.model.sensor = ImuSensor::kAccel;
  c.model.kind = misaligned ? ModelKind::kFull : ModelKind::kScale;
  c.model.input_unit = "LSB";
  c.model.output_unit = "g";
  c.full_scale = 2.0;  // +-2 g: 16384 LSB/g
  c.model.bias = {812.0, -340.5, 1210.25};
  c.model.scale = {1.0 / 16100.0, 1.0 / 16500.0, 1.0 / 16384.0 * 1.01};
  if (misaligned) c.model.misalignment = {0.012, -0.004, 0.007};
  c.bias_u = {2.0, 3.0, 4.0};
  c.scale_u = {1e-9, 2e-9, 3e-9};
  return c;
}

SensorCalibration Gyro() {
  SensorCalibration c;
  c.model.sensor = ImuSensor::kGyro;
  c.model.kind = ModelKind::kScale;
  c.model.input_unit = "deg/s";
  c.model.output_unit = "deg/s";
  c.model.bias = {1.5, -0.75, 0.25};
  c.model.scale = {1.02, 0.99, 1.0};
  c.bias_u = {0.01, 0.02, 0.03};
  return c;
}

std::vector<Eigen::Vector3d> Samples(double range) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-range, range);
  std::vector<Eigen::Vector3d> out;
  for (int i = 0; i < 1000; ++i) out.emplace_back(u(rng), u(rng), u(rng));
  return out;
}

TEST_CASE("PX4/ArduPilot form: the accelerometer's offset and scale agree with metro's model",
          "[calibration][export]") {
  const SensorCalibration c = Accel(false);
  const Result<AutopilotSensorForm> f = AutopilotForm(c);
  REQUIRE(f.ok());
  CHECK(f.value().not_held.empty());
  const double c_in = 2.0 * kGn / 32768.0;  // the driver's m/s^2 per count
  CHECK(f.value().input_to_si == c_in);
  CHECK(f.value().offset(0) == Approx(812.0 * c_in).epsilon(1e-15));
  CHECK(f.value().scale(2) == Approx(1.01).epsilon(1e-14));
  CHECK(f.value().offset_u(1) == Approx(3.0 * c_in).epsilon(1e-15));
  CHECK(f.value().scale_u(2) == Approx(3e-9 * kGn / c_in).epsilon(1e-14));
  for (const Eigen::Vector3d& raw : Samples(32768.0)) {
    const Eigen::Vector3d metro = kGn * c.model.Apply(raw);
    const Eigen::Vector3d autopilot = f.value().Correct(c_in * raw);
    CHECK((metro - autopilot).norm() <= 1e-12 * std::max(1.0, metro.norm()));
  }
}

TEST_CASE("PX4/ArduPilot form: misalignment and gyroscope scale are named with their size",
          "[calibration][export]") {
  // Misalignment: metro = T (form's output), so the largest relative difference over all
  // directions is the spectral norm of T - I, which the warning states.
  const SensorCalibration a = Accel(true);
  const Result<AutopilotSensorForm> f = AutopilotForm(a);
  REQUIRE(f.ok());
  REQUIRE(f.value().not_held.size() == 1);
  const Eigen::Matrix3d t = MisalignmentMatrix(ImuSensor::kAccel, a.model.misalignment.data());
  const double norm =
      Eigen::JacobiSVD<Eigen::Matrix3d>(t - Eigen::Matrix3d::Identity()).singularValues()(0);
  CHECK_THAT(f.value().not_held[0], Catch::Contains(std::to_string(100.0 * norm).substr(0, 4)));
  double worst = 0.0;
  for (const Eigen::Vector3d& raw : Samples(32768.0)) {
    const Eigen::Vector3d metro = kGn * a.model.Apply(raw);
    const Eigen::Vector3d form = f.value().Correct(f.value().input_to_si * raw);
    worst = std::max(worst, (metro - form).norm() / form.norm());
  }
  CHECK(worst <= norm * (1.0 + 1e-12));
  CHECK(worst >= 0.9 * norm);  // 1000 random directions come near the bound
  // Gyroscope: offset only; the scale it cannot hold is max |k - 1| = 2 %.
  const SensorCalibration g = Gyro();
  const Result<AutopilotSensorForm> gf = AutopilotForm(g);
  REQUIRE(gf.ok());
  CHECK_FALSE(gf.value().scale_held);
  CHECK(gf.value().offset(0) == Approx(1.5 * kRad).epsilon(1e-15));
  REQUIRE(gf.value().not_held.size() == 1);
  CHECK_THAT(gf.value().not_held[0], Catch::Contains("up to 2 %"));
  for (const Eigen::Vector3d& raw : Samples(250.0)) {
    const Eigen::Vector3d metro = kRad * g.model.Apply(raw);
    const Eigen::Vector3d form = gf.value().Correct(kRad * raw);
    const Eigen::Vector3d d = kRad * (raw - g.model.bias);
    // metro - form = (K - I)(data - offset), axis by axis.
    for (int i = 0; i < 3; ++i) {
      CHECK(metro(i) - form(i) == Approx((g.model.scale(i) - 1.0) * d(i)).margin(1e-13));
    }
  }
}

// name -> value of a parameter file's lines (PX4: tab-separated, ArduPilot: NAME,VALUE).
std::map<std::string, double> Parameters(const std::string& text, AutopilotFormat format) {
  std::map<std::string, double> out;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    if (format == AutopilotFormat::kPx4) {
      std::istringstream f(line);
      std::string vehicle, component, name, value, type;
      f >> vehicle >> component >> name >> value >> type;
      out[name] = std::stod(value);
    } else {
      const size_t comma = line.find(',');
      out[line.substr(0, comma)] = std::stod(line.substr(comma + 1));
    }
  }
  return out;
}

TEST_CASE("PX4 and ArduPilot parameter files carry the form's values under their names",
          "[calibration][export]") {
  Calibration cal;
  cal.date_utc = "2026-12-03T00:00:00Z";
  TagCalibration tag;
  tag.sensor = 4;
  tag.accel = Accel(false);
  tag.gyro = Gyro();
  cal.tags.push_back(tag);
  const AutopilotSensorForm fa = AutopilotForm(*tag.accel).value();
  const AutopilotSensorForm fg = AutopilotForm(*tag.gyro).value();
  AutopilotExportOptions o;
  o.sensor = 4;
  o.instance = 1;
  o.px4_accel_device_id = 2490378;
  Result<AutopilotExport> px4 = ExportAutopilotParameters(cal, o);
  REQUIRE(px4.ok());
  std::map<std::string, double> p = Parameters(px4.value().text, AutopilotFormat::kPx4);
  CHECK(p.size() == 10);  // ID, 3 offsets, 3 scales; 3 gyro offsets
  CHECK(p["CAL_ACC1_ID"] == 2490378);
  CHECK(p["CAL_ACC1_XOFF"] == fa.offset(0));  // 17 digits: the double itself
  CHECK(p["CAL_ACC1_ZSCALE"] == fa.scale(2));
  CHECK(p["CAL_GYRO1_YOFF"] == fg.offset(1));
  CHECK(px4.value().warnings.size() == 1);  // the gyroscope's scale
  o.format = AutopilotFormat::kArduPilot;
  Result<AutopilotExport> ap = ExportAutopilotParameters(cal, o);
  REQUIRE(ap.ok());
  p = Parameters(ap.value().text, AutopilotFormat::kArduPilot);
  CHECK(p.size() == 9);
  CHECK(p["INS_ACC2OFFS_X"] == fa.offset(0));
  CHECK(p["INS_ACC2SCAL_Y"] == fa.scale(1));
  CHECK(p["INS_GYR2OFFS_Z"] == fg.offset(2));
  o.instance = 0;
  p = Parameters(ExportAutopilotParameters(cal, o).value().text, AutopilotFormat::kArduPilot);
  CHECK(p.count("INS_ACCOFFS_X") == 1);
  CHECK(p.count("INS_GYROFFS_X") == 1);
}

TEST_CASE("Autopilot export refuses what it cannot write", "[calibration][export]") {
  Calibration cal;
  TagCalibration tag;
  tag.sensor = 1;
  tag.accel = Accel(false);
  tag.accel->full_scale.reset();  // counts without their full scale
  cal.tags.push_back(tag);
  AutopilotExportOptions o;
  Result<AutopilotExport> r = ExportAutopilotParameters(cal, o);
  REQUIRE_FALSE(r.ok());
  CHECK_THAT(r.error().message, Catch::Contains("input unit 'LSB'"));
  o.sensor = 7;
  CHECK_FALSE(ExportAutopilotParameters(cal, o).ok());
  o.sensor = 1;
  o.format = AutopilotFormat::kArduPilot;
  o.instance = 3;
  r = ExportAutopilotParameters(cal, o);
  REQUIRE_FALSE(r.ok());
  CHECK_THAT(r.error().message, Catch::Contains("ardupilot has IMU instances 0..2"));
  cal.tags[0].accel->full_scale = 2.0;
  cal.tags[0].accel->model_check.emplace();
  cal.tags[0].accel->model_check->model_rejected = true;
  o.instance = 0;
  r = ExportAutopilotParameters(cal, o);
  REQUIRE_FALSE(r.ok());
  CHECK_THAT(r.error().message, Catch::Contains("model_rejected"));
}

}  // namespace
}  // namespace metro
