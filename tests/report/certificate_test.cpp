// Calibration certificate: recovery (residuals shrink after calibration), content that
// ISO/IEC 17025 7.8 asks for, the reload of inputs and bad input.
#include "metro/report/certificate.hpp"

#include <fmt/format.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <fstream>
#include <string>

#include "metro/calibration/calibration_io.hpp"
#include "metro/calibration/simulate.hpp"
#include "metro/core/file.hpp"
#include "metro/core/rounding.hpp"
#include "metro/io/session_io.hpp"
#include "metro/report/html_report.hpp"
#include "support/temp_file.hpp"

namespace metro {
namespace {

struct Fitted {
  SimulatedSession sim;
  Calibration cal;
};

const Fitted& Fit() {
  static const Fitted fitted = [] {
    SimulationOptions so;
    so.seed = 7;
    so.temperature = true;
    so.temp_start_c = 22.0;
    so.temp_end_c = 31.0;
    Fitted f;
    Result<SimulatedSession> sim = SimulateCalibrationSession(so);
    METRO_CHECK(sim.ok());
    f.sim = std::move(sim).value();
    Result<Calibration> cal = CalibrateSessions({&f.sim.session}, CalibrationOptions{});
    METRO_CHECK(cal.ok());
    f.cal = std::move(cal).value();
    return f;
  }();
  return fitted;
}

double Rms(const std::vector<double>& v) {
  double s = 0.0;
  for (double x : v) s += x * x;
  return std::sqrt(s / static_cast<double>(v.size()));
}

TEST_CASE("Static residuals shrink to the noise after calibration", "[report][certificate]") {
  const Fitted& f = Fit();
  const TagCalibration& t = f.cal.tags.front();
  REQUIRE(t.accel);
  REQUIRE(t.gyro);
  Result<StaticResiduals> acc =
      ComputeStaticResiduals(*t.accel, t.sensor, {&f.sim.session}, f.cal.gravity_mps2);
  REQUIRE(acc.ok());
  CHECK(acc.value().unit == "g");
  // Datasheet tolerances of the simulated truth (+-3 % scale, up to 80 mg offsets) give
  // gravity-norm errors of the order of 10 mg before; after, the pose means carry only the
  // noise of a 3 s pose (400 ug/sqrt(Hz) * sqrt(50 Hz) / sqrt(300) ~ 0.2 mg per axis).
  CHECK(Rms(acc.value().before) > 5e-3);
  CHECK(Rms(acc.value().after) < 1e-3);
  Result<StaticResiduals> gyr =
      ComputeStaticResiduals(*t.gyro, t.sensor, {&f.sim.session}, f.cal.gravity_mps2);
  REQUIRE(gyr.ok());
  CHECK(gyr.value().unit == "deg/s");
  // Zero-rate offsets up to 20 deg/s before; after, the static rate is the noise.
  CHECK(Rms(gyr.value().before) > 1.0);
  CHECK(Rms(gyr.value().after) < 0.05);
}

TEST_CASE("Certificate states identification results with U and k and conditions",
          "[report][certificate]") {
  const Fitted& f = Fit();
  Result<std::string> html =
      RenderCalibrationCertificate(f.cal, {&f.sim.session}, "inputs in memory");
  REQUIRE(html.ok());
  const std::string& h = html.value();
  CHECK(h.find("<title>Calibration certificate</title>") != std::string::npos);
  for (const char* section :
       {"1. Identification", "2. Method and model", "3. Results", "4. Conditions", "5. Validity"}) {
    INFO(section);
    CHECK(h.find(section) != std::string::npos);
  }
  CHECK(h.find(f.sim.session.sha256) != std::string::npos);
  CHECK(h.find("k = 2") != std::string::npos);
  // U = 2 u of b0_x, rounded per GUM 7.2.6.
  const TagCalibration& t = f.cal.tags.front();
  const RoundedResult r = RoundForStatement(t.accel->model.bias[0], 2.0 * t.accel->bias_u[0]);
  CHECK(h.find("<td>bias b0_x</td><td>LSB</td><td class=\"num\">" + r.value + "</td>") !=
        std::string::npos);
  // The temperature range of the record, from the simulated ramp 22 -> 31 degC.
  const Quantity* temp = f.sim.session.tags.front().Find("temp_c");
  REQUIRE(temp != nullptr);
  const double lo = *std::min_element(temp->values.begin(), temp->values.end());
  const double hi = *std::max_element(temp->values.begin(), temp->values.end());
  CHECK(lo == Approx(22.0).margin(0.1));
  CHECK(hi == Approx(31.0).margin(0.1));
  char range[64];
  std::snprintf(range, sizeof range, "%.2f .. %.2f degC", lo, hi);
  CHECK(h.find(range) != std::string::npos);
  // Before/after residual plots for both sensors.
  CHECK(std::count(h.begin(), h.end(), '\n') > 0);
  size_t svgs = 0;
  for (size_t at = h.find("<svg"); at != std::string::npos; at = h.find("<svg", at + 1)) ++svgs;
  CHECK(svgs == 2);
  CHECK(h.find("http") == std::string::npos);
}

TEST_CASE("Certificate from calibration.json reloads matching inputs", "[report][certificate]") {
  const Fitted& f = Fit();
  // The input record on disk, and the calibration naming it.
  testing::TempFile session_file(FormatSessionCsv(f.sim.session, false), ".csv");
  Result<Session> reloaded = LoadSession(session_file.path());
  REQUIRE(reloaded.ok());
  Calibration cal = f.cal;
  cal.inputs = {{session_file.path(), reloaded.value().sha256}};
  testing::TempFile json(FormatCalibrationJson(cal), ".json");
  Result<std::string> html = RenderJsonFileHtml(json.path());
  REQUIRE(html.ok());
  CHECK(html.value().find("reloaded (SHA-256 match)") != std::string::npos);
  CHECK(html.value().find("degC</td>") != std::string::npos);

  // A changed input is not used: no residual plots, and the page says so.
  cal.inputs = {{session_file.path(), std::string(64, '0')}};
  testing::TempFile changed(FormatCalibrationJson(cal), ".json");
  html = RenderJsonFileHtml(changed.path());
  REQUIRE(html.ok());
  CHECK(html.value().find("not found or changed since the fit: " + session_file.path()) !=
        std::string::npos);
  CHECK(html.value().find("<svg") == std::string::npos);
  // The static poses' temperatures still come from calibration.json itself.
  const PoseTemperatureRange& poses = *f.cal.tags.front().accel->static_pose_temperature;
  CHECK(poses.min_c > 22.0);
  CHECK(poses.max_c < 31.0);
  CHECK(html.value().find(fmt::format("sensor 1: the {} static poses were at {:.2f} .. {:.2f} degC",
                                      poses.poses, poses.min_c, poses.max_c)) != std::string::npos);
}

TEST_CASE("Certificate bad input is refused with a message", "[report][certificate]") {
  const Fitted& f = Fit();
  CertificateOptions o;
  o.coverage_factor = 0.5;
  Result<std::string> r = RenderCalibrationCertificate(f.cal, {}, "", o);
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().message == "certificate: coverage factor k = 0.5 is outside [1, 10]");
  r = RenderCalibrationCertificate(f.cal, {&f.sim.session, &f.sim.session}, "");
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().message == "certificate: 2 sessions given for 1 calibration inputs");
  Result<StaticResiduals> none =
      ComputeStaticResiduals(*f.cal.tags.front().accel, 99, {&f.sim.session}, 9.80665);
  REQUIRE_FALSE(none.ok());
  CHECK(none.error().message == "no static segment of the fit found in the input records");
}

}  // namespace
}  // namespace metro
