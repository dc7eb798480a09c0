#include "metro/calibration/calibration_io.hpp"

#include <catch2/catch.hpp>
#include <cmath>
#include <map>

#include "metro/calibration/simulate.hpp"

namespace metro {
namespace {

struct Fitted {
  SimulatedSession sim;
  Calibration cal;
};

const Fitted& FitOnce() {
  static const Fitted f = [] {
    SimulationOptions so;
    so.seed = 31;
    Fitted out{SimulateCalibrationSession(so).value(), {}};
    Result<Calibration> c = CalibrateSessions({&out.sim.session}, {});
    REQUIRE(c.ok());
    out.cal = c.value();
    return out;
  }();
  return f;
}

TEST_CASE("calibration.json round trip keeps every constant", "[calibration]") {
  const Calibration& cal = FitOnce().cal;
  const nlohmann::json j = CalibrationToJson(cal);
  CHECK(j["schema"] == "metro.calibration/1");
  CHECK(j["tags"][0]["accel"]["matrix"].size() == 3);
  CHECK(j["tags"][0]["gyro"]["misalignment"].size() == 6);
  CHECK(j["tags"][0]["accel"]["correlation"][0][0] == Approx(1.0));
  Result<Calibration> back = CalibrationFromJson(nlohmann::json::parse(j.dump()), "c.json");
  REQUIRE(back.ok());
  const TagCalibration& a = cal.tags.front();
  const TagCalibration& b = back.value().tags.front();
  for (const auto& [x, y] : {std::pair{&*a.accel, &*b.accel}, std::pair{&*a.gyro, &*b.gyro}}) {
    CHECK(x->model.bias == y->model.bias);
    CHECK(x->model.scale == y->model.scale);
    CHECK(x->model.misalignment == y->model.misalignment);
    CHECK(x->bias_u == y->bias_u);
    CHECK(x->covariance == y->covariance);
    CHECK(x->model.Matrix() == y->model.Matrix());
    CHECK(x->model.input_unit == y->model.input_unit);
  }
}

TEST_CASE("calibration.json errors name the key", "[calibration]") {
  nlohmann::json j = CalibrationToJson(FitOnce().cal);
  nlohmann::json bad = j;
  bad["schema"] = "metro.calibration/9";
  CHECK(CalibrationFromJson(bad, "c.json").error().ToString() ==
        "c.json: schema is 'metro.calibration/9'; expected 'metro.calibration/1'");
  bad = j;
  bad["tags"][0]["gyro"].erase("bias");
  CHECK(CalibrationFromJson(bad, "c.json").error().message == "missing key 'tags[0].gyro.bias'");
  bad = j;
  bad["tags"][0]["accel"]["scale"] = {1, 2};
  CHECK(CalibrationFromJson(bad, "c.json").error().message ==
        "'tags[0].accel.scale' must be an array of 3 numbers");
  bad = j;
  bad["tags"][0]["accel"]["model"] = "affine";
  CHECK(CalibrationFromJson(bad, "c.json").error().message ==
        "'tags[0].accel.model' is 'affine'; expected bias, scale or full");
  bad = j;
  bad["tags"][0]["accel"]["input_unit"] = "deg/s";
  CHECK(CalibrationFromJson(bad, "c.json").error().message ==
        "'tags[0].accel.input_unit' 'deg/s' is not a unit of the accel");
  bad = j;
  bad["tags"][0]["accel"]["static_pose_temperature"] = {
      {"min_c", 30.0}, {"mean_c", 25.0}, {"max_c", 35.0}, {"poses", 4}};
  CHECK(CalibrationFromJson(bad, "c.json").error().message ==
        "'tags[0].accel.static_pose_temperature' must have finite min_c <= mean_c <= max_c and "
        "poses >= 1");
  bad["tags"][0]["accel"]["static_pose_temperature"] = {{"min_c", 30.0}};
  CHECK(CalibrationFromJson(bad, "c.json").error().message ==
        "missing key 'tags[0].accel.static_pose_temperature.mean_c'");
  bad = j;
  bad["tags"] = nlohmann::json::array();
  CHECK(CalibrationFromJson(bad, "c.json").error().message == "'tags' must be a non-empty array");
}

TEST_CASE("Apply after fit recovers the true specific force and rate", "[calibration]") {
  const Fitted& f = FitOnce();
  // A new session of the same tag (same truth), calibrated with the fitted constants.
  SimulationOptions so;
  so.seed = 32;
  so.random_truth = false;
  so.truth = f.sim.truth;
  so.pose_set = PoseSet::kSphere;
  so.poses = 10;
  SimulatedSession fresh = SimulateCalibrationSession(so).value();
  Session session = fresh.session;
  Result<ApplySummary> s = ApplyCalibration(f.cal, &session);
  REQUIRE(s.ok());
  CHECK(s.value().rows == static_cast<int64_t>(fresh.true_accel_g.size()));
  const Tag& tag = session.tags.front();
  // Original columns kept, calibrated added.
  std::map<std::string, const Quantity*> q;
  for (const Quantity& x : tag.quantities) q[x.name] = &x;
  REQUIRE(q.count("ax_lsb") == 1);
  REQUIRE(q.count("ax_g") == 1);
  REQUIRE(q.count("gz_dps") == 1);
  CHECK(q["ax_g"]->unit == "g");
  CHECK(q["gz_dps"]->unit == "deg/s");
  // The error is the sensor noise (2.83 mg, 0.035 deg/s per sample) plus quantisation and a
  // calibration error far below it: the RMS stays within 10 % of the noise.
  double ea = 0, eg = 0;
  const size_t n = tag.size();
  for (size_t k = 0; k < n; ++k) {
    const char* axes[3] = {"x", "y", "z"};
    for (int a = 0; a < 3; ++a) {
      const double da = q[std::string("a") + axes[a] + "_g"]->values[k] - fresh.true_accel_g[k][a];
      const double dg =
          q[std::string("g") + axes[a] + "_dps"]->values[k] - fresh.true_gyro_dps[k][a];
      ea += da * da;
      eg += dg * dg;
    }
  }
  const double rms_a = std::sqrt(ea / (3.0 * static_cast<double>(n)));
  const double rms_g = std::sqrt(eg / (3.0 * static_cast<double>(n)));
  CHECK(rms_a < 1.1 * 400e-6 * std::sqrt(50.0));
  CHECK(rms_g < 1.1 * 0.005 * std::sqrt(50.0));
}

TEST_CASE("Apply refuses a tag without calibration or without the input columns", "[calibration]") {
  const Fitted& f = FitOnce();
  Session other = f.sim.session;
  other.path = "other.csv";
  other.tags.front().sensor = 7;
  Result<ApplySummary> r = ApplyCalibration(f.cal, &other);
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().ToString() ==
        "other.csv: sensor 7 has no calibration (the calibration file has sensors 1)");
  Session physical = f.sim.session;
  physical.path = "p.csv";
  physical.tags.front().quantities.front().name = "ax_g";
  Result<ApplySummary> p = ApplyCalibration(f.cal, &physical);
  REQUIRE_FALSE(p.ok());
  CHECK(p.error().message ==
        "sensor 1: the accel calibration takes LSB input (_lsb columns) but the session has no "
        "ax_lsb column");
}

TEST_CASE("The report names every constant with its uncertainty", "[calibration]") {
  const std::string text = FormatCalibrationReport(FitOnce().cal);
  CHECK_THAT(text, Catch::Contains("accel: model full, LSB -> g"));
  CHECK_THAT(text, Catch::Contains("gyro: model full, LSB -> deg/s"));
  CHECK_THAT(text, Catch::Contains("g_yx = "));
  CHECK_THAT(text, Catch::Contains("rotation_gravity"));
  CHECK_THAT(text, Catch::Contains("segments used: 26 static"));
}

}  // namespace
}  // namespace metro
