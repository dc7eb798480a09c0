#include "metro/calibration/calibration_io.hpp"

#include <fmt/format.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>

#include "metro/core/rounding.hpp"
#include "metro/io/session_io.hpp"
#include "metro/sim/calibration_session.hpp"
#include "support/text_position.hpp"

namespace metro {
namespace {

struct Fitted {
  SimulatedSession sim;
  Calibration cal;
};

// calibration.json's reader on a document edited as JSON (written with a 2-space indent).
Result<Calibration> FromJson(const nlohmann::json& j) {
  return CalibrationFromJson(j.dump(2), "c.json");
}

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
  const nlohmann::json j = nlohmann::json::parse(ToJson(cal));
  CHECK(j["schema"] == "metro.calibration/1");
  CHECK(j["tags"][0]["accel"]["matrix"].size() == 3);
  CHECK(j["tags"][0]["gyro"]["misalignment"].size() == 6);
  CHECK(j["tags"][0]["accel"]["correlation"][0][0] == Approx(1.0));
  Result<Calibration> back = FromJson(j);
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

TEST_CASE("calibration.json round trip keeps the identification of the certificate",
          "[calibration]") {
  Calibration cal = FitOnce().cal;
  // What the fit records itself: the gravity source and each record's format and span.
  CHECK(cal.gravity_source == "standard");
  REQUIRE(cal.inputs.size() == 1);
  CHECK(cal.inputs[0].format == "csv");
  const std::vector<double>& t = FitOnce().sim.session.tags.front().t_s;
  REQUIRE(cal.inputs[0].duration_s);
  CHECK(*cal.inputs[0].duration_s == t.back() - t.front());
  CHECK(cal.inputs[0].start_utc.empty());  // relative times: no date
  // Raw counts: the full-scale settings the fit took the nominal sensitivity from (defaults).
  CHECK(cal.tags[0].accel->full_scale == 2.0);
  CHECK(cal.tags[0].gyro->full_scale == 250.0);
  // What the tags file adds, and a dated record.
  cal.gravity_mps2 = 9.81744;
  cal.gravity_source = "given";
  cal.inputs[0].start_utc = "2026-01-01T00:00:00Z";
  cal.inputs[0].end_utc = "2026-01-01T00:05:13Z";
  cal.tags[0].device_id = 0x9ABCDEF012345678ull;
  cal.tags[0].name = "Chest";
  cal.tags[0].profile = "mpu6050";
  const nlohmann::json j = nlohmann::json::parse(ToJson(cal));
  CHECK(j["gravity_source"] == "given");
  CHECK(j["inputs"][0]["format"] == "csv");
  CHECK(j["inputs"][0]["start_utc"] == "2026-01-01T00:00:00Z");
  CHECK(j["tags"][0]["name"] == "Chest");
  CHECK(j["tags"][0]["profile"] == "mpu6050");
  Result<Calibration> back = FromJson(j);
  REQUIRE(back.ok());
  const Calibration& b = back.value();
  CHECK(b.gravity_mps2 == 9.81744);
  CHECK(b.gravity_source == "given");
  CHECK(b.inputs[0].format == "csv");
  CHECK(b.inputs[0].duration_s == cal.inputs[0].duration_s);
  CHECK(b.inputs[0].start_utc == "2026-01-01T00:00:00Z");
  CHECK(b.inputs[0].end_utc == "2026-01-01T00:05:13Z");
  CHECK(b.tags[0].device_id == cal.tags[0].device_id);
  CHECK(b.tags[0].name == "Chest");
  CHECK(b.tags[0].profile == "mpu6050");
  CHECK(b.tags[0].accel->full_scale == 2.0);
  CHECK(b.tags[0].gyro->full_scale == 250.0);
  // A file without them (written before metro recorded them) reads with them unset.
  nlohmann::json old = j;
  old.erase("gravity_source");
  old["inputs"][0] = {{"path", "s.csv"}, {"sha256", "00"}};
  old["tags"][0].erase("name");
  old["tags"][0].erase("profile");
  for (const char* key : {"gravity_uncertainty", "scale_u_with_gravity",
                          "sensitivity_u_with_gravity", "matrix_u_with_gravity"}) {
    old["tags"][0]["accel"].erase(key);  // Derived from gravity_source too (issue #36).
  }
  back = FromJson(old);
  REQUIRE(back.ok());
  CHECK(back.value().gravity_source.empty());
  CHECK(back.value().inputs[0].format.empty());
  CHECK_FALSE(back.value().inputs[0].duration_s);
  CHECK(back.value().tags[0].name.empty());
  // Malformed values are refused naming the key.
  nlohmann::json bad = j;
  bad["gravity_source"] = "local";
  CHECK(FromJson(bad).error().message ==
        "gravity_source: expected \"standard\" or \"given\", found the string \"local\"");
  bad = j;
  bad["inputs"][0]["start_utc"] = "1 Jan 2026";
  CHECK(FromJson(bad).error().message ==
        "inputs[0].start_utc: expected an ISO 8601 UTC time such as \"2026-05-01T12:00:00Z\", "
        "found the string \"1 Jan 2026\"");
  bad = j;
  bad["inputs"][0]["duration_s"] = -1.0;
  CHECK(FromJson(bad).error().message ==
        "inputs[0].duration_s: expected a number >= 0, found the number -1.0");
  bad = j;
  bad["tags"][0]["accel"]["full_scale"] = 0;
  CHECK(FromJson(bad).error().message ==
        "tags[0].accel.full_scale: expected a number > 0 (the full-scale setting of raw input: "
        "for input_unit LSB only), found the number 0");
  bad = j;
  bad["tags"][0]["name"] = 7;
  CHECK(FromJson(bad).error().message ==
        "tags[0].name: expected a string or null, found the number 7");
}

TEST_CASE("calibration.json errors name the key", "[calibration]") {
  nlohmann::json j = nlohmann::json::parse(ToJson(FitOnce().cal));
  nlohmann::json bad = j;
  bad["schema"] = "metro.calibration/9";
  CHECK(FromJson(bad).error().message ==
        "schema: expected \"metro.calibration/1\", found the string \"metro.calibration/9\"");
  bad = j;
  bad["tags"][0]["gyro"].erase("bias");
  CHECK(FromJson(bad).error().message ==
        "tags[0].gyro.bias: expected an array of 3 numbers, found nothing (the member is missing)");
  bad = j;
  bad["tags"][0]["accel"]["scale"] = {1, 2};
  CHECK(FromJson(bad).error().message ==
        "tags[0].accel.scale: expected an array of 3 numbers, found an array");
  bad = j;
  bad["tags"][0]["accel"]["model"] = "affine";
  CHECK(FromJson(bad).error().message ==
        "tags[0].accel.model: expected bias, scale or full, found the string \"affine\"");
  bad = j;
  bad["tags"][0]["accel"]["input_unit"] = "deg/s";
  CHECK(FromJson(bad).error().message ==
        "tags[0].accel.input_unit: expected a unit of the accel, found the string \"deg/s\"");
  bad = j;
  bad["tags"][0]["accel"]["static_pose_temperature"] = {
      {"min_c", 30.0}, {"mean_c", 25.0}, {"max_c", 35.0}, {"poses", 4}};
  CHECK(FromJson(bad).error().message ==
        "tags[0].accel.static_pose_temperature: expected finite min_c <= mean_c <= max_c and "
        "poses >= 1, found an object");
  bad["tags"][0]["accel"]["static_pose_temperature"] = {{"min_c", 30.0}};
  CHECK(FromJson(bad).error().message ==
        "tags[0].accel.static_pose_temperature.mean_c: expected a number, found nothing (the "
        "member is missing)");
  bad = j;
  bad["tags"] = nlohmann::json::array();
  CHECK(FromJson(bad).error().message ==
        "tags: expected a non-empty array of tag calibrations, found an array");
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
  CHECK_THAT(p.error().message,
             Catch::StartsWith("sensor 1: the accel calibration takes LSB input (_lsb columns) "
                               "but the session has no ax_lsb column; it has ax_g (unit "));
  CHECK_THAT(p.error().message,
             Catch::EndsWith("instead: expected the columns the calibration takes, ax_lsb, "
                             "ay_lsb, az_lsb (a session in the unit of the calibration's "
                             "records)"));
  CHECK(p.error().line == 0);  // A session built in memory has no header line to point at.
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
  REQUIRE(FromJson(j).ok());
  // T K [0][1] = -(-a_yz) k_y = 7.201811526559342e-07; 7.2e-07 is an edit, not a rounding.
  j["tags"][0]["accel"]["matrix"][0][1] = 7.2e-07;
  Result<Calibration> r = FromJson(j);
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().message ==
        "tags[0].accel.matrix[0][1]: expected T K = 7.2018115265593419e-07 from 'scale' and "
        "'misalignment' (difference -1.81e-10, tolerance 4.44e-16 relative, the double rounding "
        "of both: the redundant fields disagree, docs/calibration-format.md), found the number "
        "7.2e-07");
}

TEST_CASE("calibration.json: a date_utc that is no ISO 8601 time is refused at its position",
          "[calibration][security][issue37]") {
  // issue #37: it was refused only when a blob was made, without line and column.
  std::string text = GoldenCalibrationJson().dump(2);
  const std::string key = "\"date_utc\": \"";
  const size_t at = text.find(key);
  REQUIRE(at != std::string::npos);
  text.replace(at + key.size(), text.find('"', at + key.size()) - at - key.size(), "May 1st");
  Result<Calibration> r = CalibrationFromJson(text, "c.json");
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().ToString() ==
        "c.json:" + testing::LineColumn(text, at + key.size() - 1) +
            ": date_utc: expected an ISO 8601 UTC time such as \"2026-05-01T12:00:00Z\", found "
            "the string \"May 1st\"");
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
  Result<Calibration> ok = FromJson(j);
  REQUIRE(ok.ok());
  CHECK(ok.value().tags[0].gyro->M()(1, 0) == one_ulp);
  CHECK(ok.value().tags[0].gyro->model.Matrix()(1, 0) == tk);
  // Four units in the last place exceed 2^-51 relative for any value.
  double four_ulp = tk;
  for (int i = 0; i < 4; ++i) four_ulp = std::nextafter(four_ulp, 1.0);
  j["tags"][0]["gyro"]["matrix"][1][0] = four_ulp;
  Result<Calibration> bad = FromJson(j);
  REQUIRE_FALSE(bad.ok());
  CHECK_THAT(bad.error().message, Catch::StartsWith("tags[0].gyro.matrix[1][0]: expected T K = ") &&
                                      Catch::Contains("from 'scale' and 'misalignment'"));
  // A zero of T K must be written as 0.
  j = golden;
  j["tags"][0]["accel"]["matrix"][2][0] = 1e-300;
  Result<Calibration> zero = FromJson(j);
  REQUIRE_FALSE(zero.ok());
  CHECK_THAT(zero.error().message,
             Catch::StartsWith("tags[0].accel.matrix[2][0]: expected T K = 0 from 'scale'") &&
                 Catch::EndsWith("found the number 1e-300"));
}

TEST_CASE("calibration.json: sensitivity that disagrees with scale is refused, matrix required",
          "[calibration][security]") {
  nlohmann::json j = GoldenCalibrationJson();
  j["tags"][0]["accel"]["sensitivity"][1] = 16637.56399613637;
  Result<Calibration> r = FromJson(j);
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().message ==
        "tags[0].accel.sensitivity[1]: expected 1 / scale[1] = 16636.56399613637 (tolerance "
        "4.44e-16 relative: the redundant fields disagree), found the number 16637.56399613637");
  j = GoldenCalibrationJson();
  j["tags"][0]["gyro"].erase("matrix");
  r = FromJson(j);
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().message ==
        "tags[0].gyro.matrix: expected a square matrix (an array of rows of numbers), found "
        "nothing (the member is missing)");
}

TEST_CASE("calibration.json: an uncertainty that is not its covariance's is refused",
          "[calibration][security]") {
  // issue #20: bias_u, scale_u, ... and matrix_u were read as written, so a hand-edited u
  // reached certificates and blobs while the covariance said otherwise.
  nlohmann::json j = GoldenCalibrationJson();
  const double var_b_y = j["tags"][0]["accel"]["covariance"][1][1].get<double>();
  Result<Calibration> ok = FromJson(j);
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
  Result<Calibration> r = FromJson(edited);
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().message ==
        fmt::format("tags[0].accel.bias_u[1]: expected {:.17g}, the square root of its variance "
                    "in the covariance (docs/calibration-format.md), found the number 0.5",
                    std::sqrt(var_b_y)));
  edited = j;
  edited["tags"][0]["accel"]["matrix_u"][0][0] =
      2.0 * j["tags"][0]["accel"]["matrix_u"][0][0].get<double>();
  r = FromJson(edited);
  REQUIRE_FALSE(r.ok());
  CHECK_THAT(r.error().message, Catch::StartsWith("tags[0].accel.matrix_u[0][0]: expected "));
  // Not a covariance: negative variance, asymmetric, wrong size.
  edited = j;
  edited["tags"][0]["accel"]["covariance"][2][2] = -1.0;
  r = FromJson(edited);
  REQUIRE_FALSE(r.ok());
  CHECK_THAT(r.error().message,
             Catch::StartsWith("tags[0].accel.covariance[2][2]: expected an element of a "
                               "symmetric covariance matrix"));
  edited = j;
  edited["tags"][0]["accel"]["covariance"][0][3] =
      1.001 * j["tags"][0]["accel"]["covariance"][0][3].get<double>();
  r = FromJson(edited);
  REQUIRE_FALSE(r.ok());
  CHECK_THAT(r.error().message, Catch::StartsWith("tags[0].accel.covariance[0][3]: expected "));
}

}  // namespace metro

namespace metro {
namespace {

// A hand-made accelerometer calibration of known constants (LSB in, g out) with a temperature
// term b1 and, when `span` is set, the static poses' temperatures.
SensorCalibration HandAccel(std::optional<PoseTemperatureRange> span, bool temperature = true) {
  SensorCalibration c;
  c.model.sensor = ImuSensor::kAccel;
  c.model.kind = ModelKind::kBias;
  c.model.input_unit = "LSB";
  c.model.output_unit = "g";
  c.model.bias = {100.0, -50.0, 25.0};
  c.model.scale = Eigen::Vector3d::Constant(1.0 / 16384.0);
  c.model.has_temperature = temperature;
  c.model.t_ref_c = 28.0;
  if (temperature) c.model.bias_per_c = {2.0, -4.0, 8.0};  // 0.12, 0.24, 0.49 mg/degC
  c.static_pose_temperature = span;
  return c;
}

PoseTemperatureRange Span(double lo, double hi) { return {lo, (lo + hi) / 2, hi, 26}; }

}  // namespace

TEST_CASE("Validity range: the fitted span plus 5 degC within the operating range",
          "[calibration][validity]") {
  const auto range = [](double lo, double hi) {
    Result<TemperatureValidity> v = TemperatureValidityRange(HandAccel(Span(lo, hi)));
    REQUIRE(v.ok());
    CHECK(v.value().warnings.empty());
    return std::pair{v.value().min_c, v.value().max_c};
  };
  CHECK(range(22.0, 34.0) == std::pair{17.0, 39.0});
  CHECK(range(-38.0, -30.0) == std::pair{-40.0, -25.0});  // cut at the operating range
  CHECK(range(82.0, 84.5) == std::pair{77.0, 85.0});
  CHECK(range(25.0, 25.0) == std::pair{20.0, 30.0});  // one temperature: 10 degC wide
  // Without a temperature term the range is the poses' span plus the margin too.
  Result<TemperatureValidity> bias_only =
      TemperatureValidityRange(HandAccel(Span(20.0, 21.0), false));
  REQUIRE(bias_only.ok());
  CHECK(bias_only.value().min_c == 15.0);
  CHECK(bias_only.value().max_c == 26.0);
  CHECK(bias_only.value().warnings.empty());
  // Poses recorded far above the operating range give no range of 2 degC within it.
  CHECK(TemperatureValidityRange(HandAccel(Span(90.0, 95.0))).error().message ==
        "accel: the temperature validity range 85.00 .. 85.00 degC (from the static poses' span "
        "90.00 .. 95.00 degC + 5 degC) is not a range of at least 2 degC within -40 .. 85 degC; "
        "expected t_valid_min_c + 2 <= t_valid_max_c");
  // Poses at 88 degC: 83 .. 85 is still 2 degC wide.
  Result<TemperatureValidity> hot = TemperatureValidityRange(HandAccel(Span(88.0, 88.0)));
  REQUIRE(hot.ok());
  CHECK(hot.value().min_c == 83.0);
}

TEST_CASE("Validity range: no recorded span gives the operating range with a warning",
          "[calibration][validity]") {
  Result<TemperatureValidity> v = TemperatureValidityRange(HandAccel(std::nullopt));
  REQUIRE(v.ok());
  CHECK(v.value().min_c == -40.0);
  CHECK(v.value().max_c == 85.0);
  REQUIRE(v.value().warnings.size() == 1);
  CHECK(v.value().warnings[0] ==
        "accel: calibration.json records no static_pose_temperature, so the span the "
        "temperature term was fitted on is unknown; the validity range is -40.00 .. 85.00 degC "
        "(from the MPU6050 operating range: no temperature span recorded), where the term may be "
        "extrapolated (refit with temp_c to record the span, or give --t-valid-min-c and "
        "--t-valid-max-c)");
  Result<TemperatureValidity> plain = TemperatureValidityRange(HandAccel(std::nullopt, false));
  REQUIRE(plain.ok());
  REQUIRE(plain.value().warnings.size() == 1);
  CHECK(plain.value().warnings[0] ==
        "accel: no temperature of the static poses recorded (no temp_c in the calibration data): "
        "the validity range is the MPU6050 operating range -40.00 .. 85.00 degC; the calibration "
        "has no temperature term, so the tag applies the same bias at every temperature");
  // Both ends given: the range is the user's; the unknown span is still said.
  ValidityOptions both;
  both.t_valid_min_c = 10.0;
  both.t_valid_max_c = 40.0;
  Result<TemperatureValidity> given = TemperatureValidityRange(HandAccel(std::nullopt), both);
  REQUIRE(given.ok());
  CHECK(given.value().min_c == 10.0);
  REQUIRE(given.value().warnings.size() == 1);
  CHECK_THAT(given.value().warnings[0],
             Catch::Contains("the validity range is 10.00 .. 40.00 degC (as given; the default"));
  CHECK(TemperatureValidityRange(HandAccel(std::nullopt, false), both).value().warnings.empty());
}

TEST_CASE("Validity range: explicit ends narrower silently and wider with the extrapolated bias",
          "[calibration][validity]") {
  const SensorCalibration c = HandAccel(Span(22.0, 34.0));  // default 17 .. 39
  ValidityOptions narrow;
  narrow.t_valid_min_c = 20.0;
  Result<TemperatureValidity> n = TemperatureValidityRange(c, narrow);
  REQUIRE(n.ok());
  CHECK(n.value().min_c == 20.0);
  CHECK(n.value().max_c == 39.0);
  CHECK(n.value().warnings.empty());
  CHECK(n.value().Describe() ==
        "minimum as given, the other end from the static poses' span 22.00 .. 34.00 degC + 5 "
        "degC");

  ValidityOptions wide;
  wide.t_valid_min_c = -40.0;
  wide.t_valid_max_c = 85.0;
  Result<TemperatureValidity> w = TemperatureValidityRange(c, wide);
  REQUIRE(w.ok());
  // The temperature term M b1 (T - t_ref) on its largest axis z: 8 LSB/degC / 16384 LSB/g
  // times (85 - 28) = 27.83 mg, times (-40 - 28) = -33.20 mg.
  REQUIRE(w.value().warnings.size() == 1);
  CHECK(w.value().warnings[0] ==
        fmt::format("accel: the validity range -40.00 .. 85.00 degC reaches beyond the fitted "
                    "span 22.00 .. 34.00 degC plus the 5 degC margin (17.00 .. 39.00 degC); the "
                    "temperature term is extrapolated there: the tag applies {:.1f} mg at -40.00 "
                    "degC and {:.1f} mg at 85.00 degC (largest axis, 0 at t_ref_c 28.00 degC)",
                    8.0 * 68.0 / 16.384, 8.0 * 57.0 / 16.384));
  CHECK(w.value().warnings[0].find("33.2 mg at -40.00 degC and 27.8 mg at 85.00") !=
        std::string::npos);

  // Only the end that reaches beyond is named; a gyroscope term in deg/s.
  SensorCalibration g = c;
  g.model.sensor = ImuSensor::kGyro;
  g.model.output_unit = "deg/s";
  g.model.scale = Eigen::Vector3d::Constant(1.0 / 131.072);
  g.model.misalignment.clear();
  ValidityOptions hot;
  hot.t_valid_max_c = 60.0;
  Result<TemperatureValidity> gw = TemperatureValidityRange(g, hot);
  REQUIRE(gw.ok());
  REQUIRE(gw.value().warnings.size() == 1);
  CHECK_THAT(gw.value().warnings[0],
             Catch::EndsWith(fmt::format("the tag applies {:.2f} deg/s at 60.00 degC (largest "
                                         "axis, 0 at t_ref_c 28.00 degC)",
                                         8.0 * 32.0 / 131.072)));

  // Errors say what was expected.
  ValidityOptions inverted;
  inverted.t_valid_min_c = 45.0;  // above the default maximum 39
  CHECK(TemperatureValidityRange(c, inverted).error().message ==
        "accel: the temperature validity range 45.00 .. 39.00 degC (minimum as given, the other "
        "end from the static poses' span 22.00 .. 34.00 degC + 5 degC) is not a range of at "
        "least 2 degC within -40 .. 85 degC; expected t_valid_min_c + 2 <= t_valid_max_c");
  ValidityOptions thin;
  thin.t_valid_min_c = 25.0;
  thin.t_valid_max_c = 25.01;
  std::string why;
  CHECK_FALSE(thin.IsValid(&why));
  CHECK(why ==
        "the temperature validity range 25 .. 25.01 degC is 0.01 degC wide; expected at least 2 "
        "degC (twice the +-1 degC linearity of the MPU6050 temperature sensor)");
  ValidityOptions cold;
  cold.t_valid_min_c = -50.0;
  CHECK_FALSE(cold.IsValid(&why));
  CHECK(why == "t_valid_min_c -50 degC is outside the MPU6050 operating range; expected -40 .. 85");
}

TEST_CASE("Apply clamps the temperature to the validity range as the tag does and counts",
          "[calibration][validity]") {
  Calibration cal;
  TagCalibration t;
  t.sensor = 3;
  t.accel = HandAccel(Span(22.0, 34.0));  // validity 17 .. 39 degC
  cal.tags.push_back(t);
  Session session;
  session.path = "s.csv";
  Tag tag;
  tag.sensor = 3;
  const std::vector<double> temps = {-40.0, 0.0, 16.9, 17.0, 28.0, 39.0, 39.5, 85.0, std::nan("")};
  for (size_t k = 0; k < temps.size(); ++k) tag.t_s.push_back(0.01 * static_cast<double>(k));
  for (const char* name : {"ax_lsb", "ay_lsb", "az_lsb"}) {
    tag.quantities.push_back({name, "LSB", QuantityOrigin::kFile, std::vector<double>(9, 1000.0)});
  }
  tag.quantities.push_back({"temp_c", "degC", QuantityOrigin::kFile, temps});
  session.tags.push_back(tag);
  Result<ApplySummary> r = ApplyCalibration(cal, &session);
  REQUIRE(r.ok());
  const Tag& out = session.tags.front();
  const Quantity* az = out.Find("az_g");
  REQUIRE(az != nullptr);
  // Closed form on z: (1000 - 25 - 8 (T' - 28)) / 16384, T' = clamp(T, 17, 39), NaN -> 28.
  const double clamped[] = {17.0, 17.0, 17.0, 17.0, 28.0, 39.0, 39.0, 39.0, 28.0};
  for (size_t k = 0; k < temps.size(); ++k) {
    INFO("sample " << k);
    CHECK(az->values[k] == Approx((975.0 - 8.0 * (clamped[k] - 28.0)) / 16384.0).epsilon(1e-14));
  }
  REQUIRE(r.value().temperature.size() == 1);
  const SensorTemperatureCount& c = r.value().temperature.front();
  CHECK(c.samples == 9);
  CHECK(c.below == 3);
  CHECK(c.above == 2);
  CHECK(c.missing == 1);
  CHECK(c.Describe() ==
        "sensor 3 accel: 5 of 9 samples outside the validity range 17.00 .. 39.00 degC (3 "
        "below, 2 above; from the static poses' span 22.00 .. 34.00 degC + 5 degC): their "
        "temperature clamped to the range, as the tag does; 1 samples without a temperature "
        "(NaN temp_c): t_ref_c 28.00 degC applied, as the tag does");
  CHECK(r.value().warnings.empty());

  // The same ends as `calibrate blob --t-valid-min-c -40 --t-valid-max-c 85`: no clamp inside,
  // and the warning of the wider range, naming the sensor.
  Session again = session;
  ApplyCalibrationOptions wide;
  wide.validity.t_valid_min_c = -40.0;
  wide.validity.t_valid_max_c = 85.0;
  Result<ApplySummary> w = ApplyCalibration(cal, &again, wide);
  REQUIRE(w.ok());
  CHECK(again.tags.front().Find("az_g")->values[0] ==
        Approx((975.0 - 8.0 * (-40.0 - 28.0)) / 16384.0).epsilon(1e-14));
  CHECK(w.value().temperature.front().outside() == 0);
  CHECK(w.value().temperature.front().Describe() ==
        "sensor 3 accel: all 8 samples with a temperature within the validity range -40.00 .. "
        "85.00 degC (as given; the default is the static poses' span 22.00 .. 34.00 degC + 5 "
        "degC); 1 samples without a temperature (NaN temp_c): t_ref_c 28.00 degC applied, as the "
        "tag does");
  REQUIRE(w.value().warnings.size() == 1);
  CHECK(w.value().warnings[0].rfind("sensor 3 accel: the validity range -40.00 .. 85.00", 0) == 0);
  ApplyCalibrationOptions bad;
  bad.validity.t_valid_min_c = 30.0;
  bad.validity.t_valid_max_c = 31.0;
  CHECK(ApplyCalibration(cal, &again, bad).error().message ==
        "the temperature validity range 30 .. 31 degC is 1 degC wide; expected at least 2 degC "
        "(twice the +-1 degC linearity of the MPU6050 temperature sensor)");
}

}  // namespace metro

namespace metro {

TEST_CASE("calibration.json text read back writes the same bytes", "[calibration]") {
  // What metro writes is a contract: ToJson(CalibrationFromJson(text)) == text, with the keys
  // the fit adds for the certificate (record_conditions, static_residuals) and without them.
  Calibration full = FitOnce().cal;
  full.gravity_mps2 = 9.81744;
  full.gravity_source = "given";
  full.inputs[0].start_utc = "2026-01-01T00:00:00Z";
  full.inputs[0].end_utc = "2026-01-01T00:05:13Z";
  full.tags[0].device_id = 0x9ABCDEF012345678ull;
  full.tags[0].name = "Chest";
  full.tags[0].profile = "mpu6050";
  CalibrationOptions accel_only;
  accel_only.fit_gyro = false;
  Result<Calibration> accel = CalibrateSessions({&FitOnce().sim.session}, accel_only);
  REQUIRE(accel.ok());
  for (const Calibration* cal :
       std::vector<const Calibration*>{&FitOnce().cal, &full, &accel.value()}) {
    const std::string text = FormatCalibrationJson(*cal);
    Result<Calibration> back = CalibrationFromJson(text, "c.json");
    REQUIRE(back.ok());
    CHECK(FormatCalibrationJson(back.value()) == text);
    CHECK(ToJson(back.value()) + "\n" == text);
  }
  // The bundled multi-pose session under several option sets.
  Result<Session> bundled =
      LoadSession(std::string(METRO_SOURCE_DIR) + "/datasets/calibration_session.csv");
  REQUIRE(bundled.ok());
  std::vector<CalibrationOptions> option_sets(4);
  option_sets[1].accel_model = ModelKind::kBias;
  option_sets[1].gyro_model = ModelKind::kScale;
  option_sets[2].temperature = TemperatureMode::kOff;
  option_sets[2].gravity_mps2 = 9.81;
  option_sets[3].loss = LossKind::kHuber;
  option_sets[3].accel_fs_g = 4.0;
  for (const CalibrationOptions& o : option_sets) {
    Result<Calibration> fitted = CalibrateSessions({&bundled.value()}, o);
    REQUIRE(fitted.ok());
    const std::string text = FormatCalibrationJson(fitted.value());
    Result<Calibration> back = CalibrationFromJson(text, "c.json");
    REQUIRE(back.ok());
    CHECK(FormatCalibrationJson(back.value()) == text);
  }
  // The new keys sit beside the old ones (keys sorted, as calibration.json always had them).
  const nlohmann::json j = nlohmann::json::parse(ToJson(FitOnce().cal));
  const nlohmann::json& residuals = j["tags"][0]["accel"]["static_residuals"];
  CHECK(residuals["unit"] == "g");
  CHECK(residuals["before"].size() == residuals["after"].size());
  const nlohmann::json& records = j["tags"][0]["record_conditions"];
  REQUIRE(records.size() == 1);
  CHECK(records[0]["input"] == 0);
  CHECK(records[0]["samples"] == FitOnce().sim.session.tags.front().size());
}

TEST_CASE("calibration.json reader names the line and column of a wrong type deep inside",
          "[calibration]") {
  // Line 11 is `        "bias": [1.5, -2.0, "x"]`: 8 spaces, "bias" at columns 9-14, ':' at
  // 15, '[' at 17, 1.5 at 18-20, -2.0 at 23-26, "x" from column 29.
  const std::string text =
      "{\n"
      "  \"schema\": \"metro.calibration/1\",\n"
      "  \"gravity_mps2\": 9.80665,\n"
      "  \"tags\": [\n"
      "    {\n"
      "      \"sensor\": 2,\n"
      "      \"accel\": {\n"
      "        \"model\": \"full\",\n"
      "        \"input_unit\": \"LSB\",\n"
      "        \"output_unit\": \"g\",\n"
      "        \"bias\": [1.5, -2.0, \"x\"]\n"
      "      }\n"
      "    }\n"
      "  ]\n"
      "}\n";
  Result<Calibration> r = CalibrationFromJson(text, "c.json");
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().ToString() ==
        "c.json:11:29: tags[0].accel.bias[2]: expected a number, found the string \"x\"");
  // Line 6 `      "sensor": 2,` with the number as a string: "sensor" at 7-14, the value at 17.
  std::string sensor = text;
  sensor.replace(sensor.find("\"sensor\": 2"), 11, "\"sensor\": \"2\"");
  r = CalibrationFromJson(sensor, "c.json");
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().ToString() ==
        "c.json:6:17: tags[0].sensor: expected an integer, found the string \"2\"");
  // Not JSON at all: the parser's position (line 3, after `9.80665`, a ',' is missing).
  std::string broken = text;
  broken.replace(broken.find("9.80665,"), 8, "9.80665");
  r = CalibrationFromJson(broken, "c.json");
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().file == "c.json");
  CHECK(r.error().line == 4);
}

}  // namespace metro
