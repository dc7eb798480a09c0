#include "metro/calibration/calibration_io.hpp"

#include <fmt/format.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <fstream>
#include <map>

#include "metro/calibration/simulate.hpp"
#include "metro/core/rounding.hpp"

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
  // issue #21 part 7: every constant in the concise notation of JCGM 100 7.2.2, never
  // "826.6026 (50)" (which reads as u = 0.0050).
  const SensorCalibration& accel = *FitOnce().cal.tags.front().accel;
  CHECK_THAT(text, Catch::Contains(
                       "b_x  = " + ConciseNotation(accel.model.bias[0], accel.bias_u[0]) + " LSB"));
}

}  // namespace
}  // namespace metro

namespace metro {
namespace {

nlohmann::json GoldenCalibrationJson() {
  std::ifstream f(std::string(METRO_SOURCE_DIR) + "/datasets/golden/calibration_sensor2.json");
  return nlohmann::json::parse(f);
}

}  // namespace

TEST_CASE("calibration.json: matrix that disagrees with scale and misalignment is refused",
          "[calibration][security]") {
  // issue #20: `matrix` was never read, so a file whose matrix said something else than its
  // scale and misalignment was accepted (and the blob silently used scale and misalignment).
  nlohmann::json j = GoldenCalibrationJson();
  REQUIRE(CalibrationFromJson(j, "c.json").ok());
  // T K [0][1] = -(-a_yz) k_y = 7.201811526559342e-07; 7.2e-07 is an edit, not a rounding.
  j["tags"][0]["accel"]["matrix"][0][1] = 7.2e-07;
  Result<Calibration> r = CalibrationFromJson(j, "c.json");
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().ToString() ==
        "c.json: 'tags[0].accel.matrix'[0][1] is 7.1999999999999999e-07 but 'scale' and "
        "'misalignment' give T K = 7.2018115265593419e-07 (difference -1.81e-10, tolerance "
        "4.44e-16 relative, the double rounding of both): the redundant fields disagree; "
        "expected matrix = T K (docs/calibration-format.md)");
}

TEST_CASE("calibration.json: the matrix tolerance is the double rounding, 2^-51 relative",
          "[calibration][security]") {
  const nlohmann::json golden = GoldenCalibrationJson();
  const double tk = golden["tags"][0]["gyro"]["matrix"][1][0].get<double>();  // g_xz k_x
  // One unit in the last place (a writer rounding its product differently) is accepted, and
  // M is then the file's value, bit for bit.
  nlohmann::json j = golden;
  const double one_ulp = std::nextafter(tk, 1.0);
  j["tags"][0]["gyro"]["matrix"][1][0] = one_ulp;
  Result<Calibration> ok = CalibrationFromJson(j, "c.json");
  REQUIRE(ok.ok());
  CHECK(ok.value().tags[0].gyro->M()(1, 0) == one_ulp);
  CHECK(ok.value().tags[0].gyro->model.Matrix()(1, 0) == tk);
  // Four units in the last place exceed 2^-51 relative for any value.
  double four_ulp = tk;
  for (int i = 0; i < 4; ++i) four_ulp = std::nextafter(four_ulp, 1.0);
  j["tags"][0]["gyro"]["matrix"][1][0] = four_ulp;
  Result<Calibration> bad = CalibrationFromJson(j, "c.json");
  REQUIRE_FALSE(bad.ok());
  CHECK_THAT(bad.error().message, Catch::StartsWith("'tags[0].gyro.matrix'[1][0] is ") &&
                                      Catch::Contains("but 'scale' and 'misalignment' give T K"));
  // A zero of T K must be written as 0.
  j = golden;
  j["tags"][0]["accel"]["matrix"][2][0] = 1e-300;
  Result<Calibration> zero = CalibrationFromJson(j, "c.json");
  REQUIRE_FALSE(zero.ok());
  CHECK_THAT(zero.error().message, Catch::StartsWith("'tags[0].accel.matrix'[2][0] is 1e-300 but "
                                                     "'scale' and 'misalignment' give T K = 0 "));
}

TEST_CASE("calibration.json: sensitivity that disagrees with scale is refused, matrix required",
          "[calibration][security]") {
  nlohmann::json j = GoldenCalibrationJson();
  j["tags"][0]["accel"]["sensitivity"][1] = 16637.56399613637;
  Result<Calibration> r = CalibrationFromJson(j, "c.json");
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().message ==
        "'tags[0].accel.sensitivity'[1] is 16637.56399613637 but 1 / 'scale'[1] is "
        "16636.56399613637 (tolerance 4.44e-16 relative): the redundant fields disagree; "
        "expected sensitivity = 1 / scale");
  j = GoldenCalibrationJson();
  j["tags"][0]["gyro"].erase("matrix");
  r = CalibrationFromJson(j, "c.json");
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().message == "missing key 'tags[0].gyro.matrix'");
}

TEST_CASE("calibration.json: an uncertainty that is not its covariance's is refused",
          "[calibration][security]") {
  // issue #20: bias_u, scale_u, ... and matrix_u were read as written, so a hand-edited u
  // reached certificates and blobs while the covariance said otherwise.
  nlohmann::json j = GoldenCalibrationJson();
  const double var_b_y = j["tags"][0]["accel"]["covariance"][1][1].get<double>();
  Result<Calibration> ok = CalibrationFromJson(j, "c.json");
  REQUIRE(ok.ok());
  // The derived values are sqrt of the diagonal, and matrix_u matches what the file says.
  CHECK(ok.value().tags[0].accel->bias_u[1] == std::sqrt(var_b_y));
  for (int r = 0; r < 3; ++r) {
    for (int k = 0; k < 3; ++k) {
      CHECK(ok.value().tags[0].accel->matrix_u(r, k) ==
            Approx(j["tags"][0]["accel"]["matrix_u"][r][k].get<double>()).epsilon(1e-6));
    }
  }
  nlohmann::json edited = j;
  edited["tags"][0]["accel"]["bias_u"][1] = 0.5;
  Result<Calibration> r = CalibrationFromJson(edited, "c.json");
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().message ==
        fmt::format("'tags[0].accel.bias_u'[1] is 0.5 but the covariance gives {:.17g}: a "
                    "standard uncertainty must be the square root of its variance "
                    "(docs/calibration-format.md)",
                    std::sqrt(var_b_y)));
  edited = j;
  edited["tags"][0]["accel"]["matrix_u"][0][0] =
      2.0 * j["tags"][0]["accel"]["matrix_u"][0][0].get<double>();
  r = CalibrationFromJson(edited, "c.json");
  REQUIRE_FALSE(r.ok());
  CHECK_THAT(r.error().message, Catch::StartsWith("'tags[0].accel.matrix_u'[0][0] is "));
  // Not a covariance: negative variance, asymmetric, wrong size.
  edited = j;
  edited["tags"][0]["accel"]["covariance"][2][2] = -1.0;
  r = CalibrationFromJson(edited, "c.json");
  REQUIRE_FALSE(r.ok());
  CHECK_THAT(r.error().message,
             Catch::StartsWith("'tags[0].accel.covariance'[2][2] is -1: expected a symmetric"));
  edited = j;
  edited["tags"][0]["accel"]["covariance"][0][3] =
      1.001 * j["tags"][0]["accel"]["covariance"][0][3].get<double>();
  r = CalibrationFromJson(edited, "c.json");
  REQUIRE_FALSE(r.ok());
  CHECK_THAT(r.error().message, Catch::StartsWith("'tags[0].accel.covariance'[0][3] is "));
}

}  // namespace metro
