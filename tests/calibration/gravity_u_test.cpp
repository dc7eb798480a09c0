// The gravity value's uncertainty in the accelerometer's calibration (issue #36 point 7):
// gravity_u.hpp's u(g) per source, its share in the scale factors, sensitivities and M in closed
// form, and calibration.json's keys for it (written, read back, refused when edited).
#include "metro/calibration/gravity_u.hpp"

#include <catch2/catch.hpp>
#include <cmath>
#include <nlohmann/json.hpp>

#include "metro/calibration/calibrate.hpp"
#include "metro/calibration/calibration_io.hpp"
#include "metro/sim/calibration_session.hpp"

namespace metro {
namespace {

TEST_CASE("Gravity u: stated, a given value's rounding, standard gravity's range",
          "[calibration][gravity]") {
  const GravityUncertainty stated = GravityUncertaintyOf(9.81, "given", 0.004);
  CHECK(stated.u_mps2 == 0.004);
  CHECK(stated.basis == "stated");
  CHECK(stated.Relative() == Approx(0.004 / 9.81).epsilon(1e-15));
  // 9.81 read as rounded to its last digit: +-0.005 m/s^2, rectangular: 0.005 / sqrt(3).
  const GravityUncertainty given = GravityUncertaintyOf(9.81, "given", std::nullopt);
  CHECK(given.u_mps2 == Approx(0.005 / std::sqrt(3.0)).epsilon(1e-15));
  CHECK(given.basis == "given_value_rounding");
  CHECK(GravityUncertaintyOf(9.81744, "given", std::nullopt).u_mps2 ==
        Approx(0.000005 / std::sqrt(3.0)).epsilon(1e-12));
  // Standard gravity for a local value within +-0.03 m/s^2: 0.03 / sqrt(3) = 0.01732 m/s^2.
  const GravityUncertainty standard = GravityUncertaintyOf(kStandardGravityMps2, "standard", {});
  CHECK(standard.u_mps2 == Approx(0.03 / std::sqrt(3.0)).epsilon(1e-15));
  CHECK(standard.basis == "standard_gravity_range");
  CHECK(standard.statement.rfind("u(g) = 0.0173 m/s^2: standard gravity 9.80665", 0) == 0);
}

// An accelerometer fitted on a simulated tag, through CalibrateSessions (gravity as given).
Calibration Fitted(double gravity_mps2, std::optional<double> gravity_u_mps2) {
  SimulationOptions so;
  so.seed = 77;
  so.gravity_mps2 = gravity_mps2;
  const SimulatedSession sim = SimulateCalibrationSession(so).value();
  CalibrationOptions o;
  o.fit_gyro = false;
  o.gravity_mps2 = gravity_mps2;
  o.gravity_given = true;
  o.gravity_u_mps2 = gravity_u_mps2;
  Result<Calibration> cal = CalibrateSessions({&sim.session}, o);
  REQUIRE(cal.ok());
  return cal.value();
}

TEST_CASE("Gravity's share of the scale factors' u in closed form", "[calibration][gravity]") {
  const Calibration cal = Fitted(9.81, 0.02);
  SensorCalibration a = *cal.tags.front().accel;
  const GravityUncertainty g = GravityUncertaintyOf(cal);
  // From gravity alone (the fit's own u negligible, 1e-12 of it): u(k) / k = u(g) / g, and so
  // for the sensitivities and every element of M = T K.
  a.scale_u *= 1e-12;
  a.sensitivity_u *= 1e-12;
  a.matrix_u *= 1e-12;
  const GravityShare alone = GravityShareOf(a, g);
  const Eigen::Matrix3d m = a.M();
  for (int i = 0; i < 3; ++i) {
    CHECK(alone.scale_u[i] / a.model.scale[i] == Approx(0.02 / 9.81).epsilon(1e-9));
    CHECK(alone.sensitivity_u[i] / a.sensitivity[i] == Approx(0.02 / 9.81).epsilon(1e-9));
    for (int c = 0; c < 3; ++c) {
      CHECK(alone.matrix_u(i, c) == Approx(std::abs(m(i, c)) * 0.02 / 9.81).epsilon(1e-9));
    }
  }
  // With the fit's own: sqrt(u^2 + (k u(g) / g)^2); a held constant (u = 0) stays held.
  const SensorCalibration& fit = *cal.tags.front().accel;
  const GravityShare both = GravityShareOf(fit, g);
  for (int i = 0; i < 3; ++i) {
    CHECK(both.scale_u[i] == Approx(std::sqrt(fit.scale_u[i] * fit.scale_u[i] +
                                              std::pow(fit.model.scale[i] * 0.02 / 9.81, 2)))
                                 .epsilon(1e-12));
  }
  SensorCalibration held = fit;
  held.scale_u.setZero();
  CHECK(GravityShareOf(held, g).scale_u == Eigen::Vector3d::Zero());
}

TEST_CASE("calibration.json states gravity's u beside the fit's; an edit is refused",
          "[calibration][gravity]") {
  const Calibration cal = Fitted(9.81, 0.02);
  const std::string text = FormatCalibrationJson(cal);
  const nlohmann::json j = nlohmann::json::parse(text);
  const nlohmann::json& a = j["tags"][0]["accel"];
  CHECK(a["gravity_uncertainty"]["u_mps2"] == 0.02);
  CHECK(a["gravity_uncertainty"]["basis"] == "stated");
  CHECK(a["gravity_uncertainty"]["u_relative"].get<double>() == Approx(0.02 / 9.81));
  for (int i = 0; i < 3; ++i) {
    const double k = a["scale"][i], u = a["scale_u"][i], ug = a["scale_u_with_gravity"][i];
    CHECK(ug == Approx(std::hypot(u, k * 0.02 / 9.81)).epsilon(1e-14));
    CHECK(ug > u);
  }
  // The fit's covariance and scale_u stay the fit's alone (their keys unchanged).
  CHECK(a["scale_u"][0].get<double>() == cal.tags.front().accel->scale_u[0]);
  CHECK_FALSE(j["tags"][0].contains("gyro"));  // fit_gyro false: no gyroscope here.
  Result<Calibration> back = CalibrationFromJson(text, "c.json");
  REQUIRE(back.ok());
  CHECK(FormatCalibrationJson(back.value()) == text);
  // A u(g) or a u with gravity that the file's own values do not give is refused.
  nlohmann::json edited = j;
  edited["tags"][0]["accel"]["scale_u_with_gravity"][1] = 1e-3;
  Result<Calibration> r = CalibrationFromJson(edited.dump(2), "c.json");
  REQUIRE_FALSE(r.ok());
  CHECK_THAT(r.error().message, Catch::Contains("tags[0].accel.scale_u_with_gravity[1]"));
  edited = j;
  edited["gravity_u_mps2"] = 0.05;
  r = CalibrationFromJson(edited.dump(2), "c.json");
  REQUIRE_FALSE(r.ok());
  CHECK_THAT(r.error().message, Catch::Contains("tags[0].accel.gravity_uncertainty.u_mps2"));
  // A file written before metro stated it (without the keys) still reads.
  edited = j;
  for (const char* key : {"gravity_uncertainty", "scale_u_with_gravity",
                          "sensitivity_u_with_gravity", "matrix_u_with_gravity"}) {
    edited["tags"][0]["accel"].erase(key);
  }
  CHECK(CalibrationFromJson(edited.dump(2), "c.json").ok());
}

}  // namespace
}  // namespace metro
