// calibration.json -> blob: the mapping in closed form, recovery of a simulated truth through
// the tag firmware's own loader and apply, and firmware (float32) vs calibrate apply (double).
#include "metro/blob/from_calibration.hpp"

#include <fmt/format.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <tuple>

#include "metro/calibration/calibration_io.hpp"
#include "metro/core/file.hpp"
#include "metro/io/session_io.hpp"
#include "metro/sim/calibration_session.hpp"
#include "metro_fw/blob.h"
#include "metro_fw/fixed.h"
#include "support/run_program.hpp"
#include "tests/test_support.hpp"

namespace metro::blob {
namespace {

using RamFlash = fwtest::FakeFlash;  // The firmware tests' RAM flash (nRF51 semantics).

constexpr double kPi = 3.14159265358979323846;
constexpr uint64_t kId = 0x0011223344556677ull;

struct Fitted {
  SimulatedSession sim;
  Calibration cal;
};

// A tag with a temperature ramp (so b1 is fitted), calibrated by the calibrator.
const Fitted& FitOnce() {
  static const Fitted f = [] {
    SimulationOptions so;
    so.seed = 41;
    so.sensor = 2;
    so.temperature = true;
    so.temp_start_c = 22.0;
    so.temp_end_c = 34.0;
    Fitted out{SimulateCalibrationSession(so).value(), {}};
    Result<Calibration> c = CalibrateSessions({&out.sim.session}, {});
    REQUIRE(c.ok());
    out.cal = c.value();
    return out;
  }();
  return f;
}

BlobFromCalibrationOptions Options() {
  BlobFromCalibrationOptions o;
  o.sensor = 2;
  o.device_id = kId;
  o.seq = 5;
  return o;
}

// The blob loaded by the firmware from slot A of a RAM flash, on a tag configured as the blob.
metro_fw_calibration LoadOnTag(const std::vector<uint8_t>& blob, uint8_t accel_fs, uint8_t gyro_fs,
                               uint8_t dlpf) {
  RamFlash flash;
  flash.Program(METRO_FW_SLOT_A_ADDR, blob);
  const metro_fw_flash f = flash.Interface();
  metro_fw_config cfg{};
  cfg.device_id[0] = static_cast<uint32_t>(kId & 0xFFFFFFFFu);
  cfg.device_id[1] = static_cast<uint32_t>(kId >> 32);
  cfg.accel_fs_sel = accel_fs;
  cfg.gyro_fs_sel = gyro_fs;
  cfg.dlpf_cfg = dlpf;
  metro_fw_calibration out{};
  REQUIRE(metro_fw_load(&f, &cfg, &out) == METRO_FW_OK);
  return out;
}

// A hand-made calibration of known constants (input LSB, output g / deg/s).
SensorCalibration MakeSensor(ImuSensor sensor, double k_nominal) {
  SensorCalibration c;
  c.model.sensor = sensor;
  c.model.kind = ModelKind::kFull;
  c.model.input_unit = "LSB";
  c.model.output_unit = sensor == ImuSensor::kAccel ? "g" : "deg/s";
  c.model.bias = {100.0, -50.0, 25.0};
  c.model.scale = {1.02 * k_nominal, 0.99 * k_nominal, 1.01 * k_nominal};
  c.model.misalignment.assign(static_cast<size_t>(MisalignmentCount(sensor)), 0.003);
  c.model.has_temperature = true;
  c.model.t_ref_c = 27.5;
  c.model.bias_per_c = {0.5, -0.25, 1.0};
  c.bias_u = {1.5, 2.5, 3.5};
  c.bias_per_c_u = {0.01, 0.02, 0.03};
  c.matrix_u = Eigen::Matrix3d::Constant(1e-3 * k_nominal);
  c.matrix_u(1, 2) = 2e-3 * k_nominal;
  c.coverage_factor_95 = 2.03;
  c.residual_rms = 0.002;
  c.residual_unit = sensor == ImuSensor::kAccel ? "g" : "deg";
  c.groups.push_back({"static_pose_norm", 26, 0.002, "g"});
  c.groups.push_back({"static_rate", 26, 0.04, "deg/s"});
  return c;
}

}  // namespace

TEST_CASE("Mapping: M in SI per LSB and biases in LSB and uncertainties scaled exactly", "[blob]") {
  const SensorCalibration a = MakeSensor(ImuSensor::kAccel, 1.0 / 16384.0);
  Result<SensorConstants> s = SensorConstantsFromCalibration(a, Options());
  REQUIRE(s.ok());
  const SensorConstants& c = s.value();
  const Eigen::Matrix3d m = a.model.Matrix();
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      CHECK(c.m[static_cast<size_t>(3 * i + j)] == Approx(9.80665 * m(i, j)).epsilon(1e-15));
      CHECK(c.u_m[static_cast<size_t>(3 * i + j)] ==
            Approx(9.80665 * a.matrix_u(i, j)).epsilon(1e-15));
    }
  }
  CHECK(c.fs_sel == 0);
  CHECK(c.dlpf_cfg == 3);
  CHECK(c.model_bits == (kModelBias | kModelFullMatrix | kModelLinearT));
  CHECK(c.t_ref_c == 27.5);
  CHECK(c.b0_lsb == std::array<double, 3>{100.0, -50.0, 25.0});
  CHECK(c.b1_lsb_per_c == std::array<double, 3>{0.5, -0.25, 1.0});
  CHECK(c.b2_lsb_per_c2 == std::array<double, 3>{0.0, 0.0, 0.0});
  CHECK(c.u_b0_lsb == std::array<double, 3>{1.5, 2.5, 3.5});
  CHECK(c.u_b1_lsb_per_c == std::array<double, 3>{0.01, 0.02, 0.03});
  CHECK(c.resid_rms_si == Approx(0.002 * 9.80665));
  CHECK(c.t_valid_min_c == -40.0);
  CHECK(c.t_valid_max_c == 85.0);

  // Gyroscope at +-1000 deg/s: deg -> rad, fs_sel 2 (32.8 LSB/(deg/s)).
  const SensorCalibration g = MakeSensor(ImuSensor::kGyro, 1.0 / 32.8);
  Result<SensorConstants> gs = SensorConstantsFromCalibration(g, Options());
  REQUIRE(gs.ok());
  CHECK(gs.value().fs_sel == 2);
  CHECK(gs.value().m[5] == Approx(kPi / 180.0 * g.model.Matrix()(1, 2)).epsilon(1e-15));
  CHECK(gs.value().u_m[5] == Approx(kPi / 180.0 * 2e-3 / 32.8).epsilon(1e-15));
  CHECK(gs.value().resid_rms_si == Approx(0.04 * kPi / 180.0));

  // Bias and scale models: diagonal M only, no temperature bits, t_ref 25 degC.
  SensorCalibration b = MakeSensor(ImuSensor::kAccel, 1.0 / 4096.0);
  b.model.kind = ModelKind::kScale;
  b.model.misalignment.clear();
  b.model.has_temperature = false;
  Result<SensorConstants> bs = SensorConstantsFromCalibration(b, Options());
  REQUIRE(bs.ok());
  CHECK(bs.value().fs_sel == 2);
  CHECK(bs.value().model_bits == kModelBias);
  CHECK(bs.value().t_ref_c == 25.0);
  CHECK(bs.value().b1_lsb_per_c == std::array<double, 3>{0.0, 0.0, 0.0});
}

TEST_CASE("Mapping: fs_sel follows the sensitivity for every full-scale setting", "[blob]") {
  const double accel_lsb_per_g[4] = {16384, 8192, 4096, 2048};
  const double gyro_lsb_per_dps[4] = {131, 65.5, 32.8, 16.4};
  for (int fs = 0; fs < 4; ++fs) {
    Eigen::Matrix3d ma = Eigen::Matrix3d::Identity() * (1.07 / accel_lsb_per_g[fs]);
    Eigen::Matrix3d mg = Eigen::Matrix3d::Identity() * (0.94 / gyro_lsb_per_dps[fs]);
    CHECK(InferFsSel(ImuSensor::kAccel, ma).value() == fs);
    CHECK(InferFsSel(ImuSensor::kGyro, mg).value() == fs);
  }
  // 1.5 x nominal at fs 0 is 0.75 x nominal at fs 1: neither within 10 %.
  const Eigen::Matrix3d off = Eigen::Matrix3d::Identity() * (1.5 / 16384.0);
  CHECK(InferFsSel(ImuSensor::kAccel, off).error().message ==
        "the accel sensitivity 10922.7 LSB/g matches no MPU6050 full-scale setting within 10 % "
        "(16384, 8192, 4096 or 2048 LSB/g)");
}

TEST_CASE("Mapping: bad input is refused with its reason", "[blob]") {
  SensorCalibration a = MakeSensor(ImuSensor::kAccel, 1.0);
  a.model.input_unit = "g";
  CHECK(SensorConstantsFromCalibration(a, Options()).error().message ==
        "accel: input_unit is 'g'; the tag applies the constants to raw counts, so the "
        "calibration must be fitted on LSB data");
  SensorCalibration u = MakeSensor(ImuSensor::kGyro, 1.0 / 131.0);
  u.matrix_u.setZero();
  CHECK(SensorConstantsFromCalibration(u, Options()).error().message ==
        "gyro: 'matrix_u' is missing or zero; the blob stores the uncertainty of every element "
        "of M");

  Calibration cal;
  cal.date_utc = "2024-05-01T12:00:00Z";
  TagCalibration t;
  t.sensor = 2;
  t.accel = MakeSensor(ImuSensor::kAccel, 1.0 / 16384.0);
  cal.tags.push_back(t);
  BlobFromCalibrationOptions o = Options();
  o.sensor = 3;
  CHECK(BlobContentsFromCalibration(cal, o).error().message ==
        "calibration has no sensor 3 (it has: 2); expected --sensor 2");
  o = Options();
  o.seq = 0;
  CHECK(BlobContentsFromCalibration(cal, o).error().message ==
        "blob options: seq 0 is outside 1..4294967294");
  o = Options();
  o.dlpf_cfg = 7;
  CHECK(BlobContentsFromCalibration(cal, o).error().message ==
        "blob options: dlpf_cfg 7 is not 0..6");
  o = Options();
  o.t_valid_min_c = 30;
  o.t_valid_max_c = 20;
  CHECK(BlobContentsFromCalibration(cal, o).error().message ==
        "blob options: the temperature validity range 30 .. 20 degC must satisfy -40 <= min < "
        "max <= 85");
  o = Options();
  o.reference_id = "A-REFERENCE-ID-LONGER-THAN-16";
  CHECK(BlobContentsFromCalibration(cal, o).error().message ==
        "blob options: reference_id 'A-REFERENCE-ID-LONGER-THAN-16' must be printable ASCII of "
        "at most 16 characters");
  o = Options();
  o.sensor = 0;
  CHECK(BlobContentsFromCalibration(cal, o).error().message ==
        "blob options: sensor 0 must be >= 1");
  Calibration bad_date = cal;
  bad_date.date_utc = "May 1st";
  CHECK(BlobContentsFromCalibration(bad_date, Options()).error().message ==
        "'date_utc' is 'May 1st'; expected ISO 8601 UTC like 2024-05-01T12:00:00Z");
  Calibration bad_scale = cal;
  bad_scale.tags[0].accel->model.scale *= 1.5;
  CHECK(BlobContentsFromCalibration(bad_scale, Options())
            .error()
            .message.rfind("sensor 2 accel: the accel sensitivity", 0) == 0);
}

TEST_CASE("Mapping: an implausible temperature coefficient is refused with the limit", "[blob]") {
  SensorCalibration a = MakeSensor(ImuSensor::kAccel, 1.0 / 16384.0);
  a.model.bias_per_c = {0.5, 80.0, -1.0};  // 80 LSB/degC: the limit at fs_sel 0, accepted
  CHECK(SensorConstantsFromCalibration(a, Options()).ok());
  a.model.bias_per_c[1] = -81.0;
  CHECK(SensorConstantsFromCalibration(a, Options()).error().message ==
        "accel: the temperature coefficient b1_y = -81 LSB/degC (-4.94 mg/degC) exceeds the "
        "plausibility limit 80 LSB/degC (4.88 mg/degC at fs_sel 0; docs/calibration-blob.md "
        "3.1); expected |b1| <= 80 LSB/degC: no MPU6050 drifts that fast, check the fit");
  // The gyroscope at +-1000 deg/s (fs_sel 2): 88 >> 2 = 22 LSB/degC = 0.67 deg/s/degC.
  SensorCalibration g = MakeSensor(ImuSensor::kGyro, 1.0 / 32.8);
  g.model.bias_per_c = {0.0, 0.0, 22.5};
  CHECK(SensorConstantsFromCalibration(g, Options()).error().message ==
        "gyro: the temperature coefficient b1_z = 22.5 LSB/degC (0.687 deg/s/degC) exceeds the "
        "plausibility limit 22 LSB/degC (0.671 deg/s/degC at fs_sel 2; docs/calibration-blob.md "
        "3.1); expected |b1| <= 22 LSB/degC: no MPU6050 drifts that fast, check the fit");
  // A validity range narrower than 2 degC is refused before the firmware would refuse it.
  BlobFromCalibrationOptions o = Options();
  o.t_valid_min_c = 25.0;
  o.t_valid_max_c = 25.01;
  Calibration cal;
  cal.date_utc = "2024-05-01T12:00:00Z";
  TagCalibration t;
  t.sensor = 2;
  t.accel = MakeSensor(ImuSensor::kAccel, 1.0 / 16384.0);
  cal.tags.push_back(t);
  CHECK(BlobContentsFromCalibration(cal, o).error().message ==
        "blob options: the temperature validity range 25 .. 25.01 degC is 0.01 degC wide; "
        "expected at least 2 degC (twice the +-1 degC linearity of the MPU6050 temperature "
        "sensor)");
}

TEST_CASE("Mapping: META carries time and version and inputs and coverage factor", "[blob]") {
  Calibration cal;
  cal.date_utc = "2024-05-01T12:00:00Z";
  cal.tool_version = "metro 1.2.3";
  cal.gravity_mps2 = 9.8101;
  const std::string sha(64, 'a');
  cal.inputs.push_back({"cal.csv", sha});
  TagCalibration t;
  t.sensor = 2;
  t.accel = MakeSensor(ImuSensor::kAccel, 1.0 / 16384.0);
  cal.tags.push_back(t);
  Result<BlobContents> r = BlobContentsFromCalibration(cal, Options());
  REQUIRE(r.ok());
  const MetaConstants& m = r.value().meta;
  CHECK(m.cal_time_utc_s == 1714564800u);  // 2024-05-01T00:00Z = 19844 days * 86400 s, + 12 h
  CHECK(m.due_time_utc_s == 1714564800u + 365u * 86400u);
  CHECK(m.tool_version == 0x010203u);
  CHECK(m.raw_data_sha256[0] == 0xAA);
  CHECK(m.raw_data_sha256[31] == 0xAA);
  CHECK((m.session_uuid[6] >> 4) == 8);       // RFC 9562 version 8
  CHECK((m.session_uuid[8] & 0xC0) == 0x80);  // variant 10
  CHECK(m.g_local_mps2 == 9.8101);
  CHECK(m.temp_mean_c == 27.5);
  CHECK(m.unc_k_x10 == 20);
  CHECK(m.procedure_id == kProcedureCalibrateFit);
  CHECK(m.tag_label == "tag2");
  CHECK_FALSE(r.value().gyro.has_value());
  REQUIRE(r.value().accel.has_value());
  CHECK(WriteBlob(r.value()).ok());
}

TEST_CASE("Mapping: META temperatures are the static poses' and the validity range their span",
          "[blob]") {
  // The fitted ramp tag: its calibration.json records the temperatures of its poses.
  const Fitted& f = FitOnce();
  const SensorCalibration& accel = *f.cal.FindTag(2)->accel;
  REQUIRE(accel.static_pose_temperature.has_value());
  const PoseTemperatureRange& range = *accel.static_pose_temperature;
  // The ramp runs 22 -> 34 degC; pose means lie inside it, and t_ref is their mean.
  CHECK(range.min_c > 22.0);
  CHECK(range.max_c < 34.0);
  CHECK(range.max_c - range.min_c > 8.0);
  CHECK(range.poses == static_cast<int>(accel.segments.size()));
  CHECK(range.mean_c == Approx(accel.model.t_ref_c).epsilon(1e-12));
  Result<BlobContents> r = BlobContentsFromCalibration(f.cal, Options());
  REQUIRE(r.ok());
  CHECK(r.value().meta.temp_min_c == range.min_c);
  CHECK(r.value().meta.temp_mean_c == range.mean_c);
  CHECK(r.value().meta.temp_max_c == range.max_c);
  // issue #23: the default is the span the fit used, 5 degC wider on each side.
  CHECK(r.value().accel->t_valid_min_c == range.min_c - 5.0);
  CHECK(r.value().accel->t_valid_max_c == range.max_c + 5.0);
  CHECK(r.value().gyro->t_valid_min_c == range.min_c - 5.0);
  BlobFromCalibrationOptions o = Options();
  o.t_valid_min_c = 20.0;
  o.t_valid_max_c = 36.0;
  std::vector<std::string> warnings;
  r = BlobContentsFromCalibration(f.cal, o, &warnings);
  REQUIRE(r.ok());
  CHECK(r.value().accel->t_valid_min_c == 20.0);
  CHECK(r.value().gyro->t_valid_max_c == 36.0);
  CHECK(warnings.empty());  // within the span + 5 degC
  // The operating range: accepted, with the temperature term the tag then applies at the
  // ends, M b1 (T - t_ref) on the largest axis, in mg and deg/s.
  o.t_valid_min_c = -40.0;
  o.t_valid_max_c = 85.0;
  r = BlobContentsFromCalibration(f.cal, o, &warnings);
  REQUIRE(r.ok());
  REQUIRE(warnings.size() == 2);
  const SensorCalibration& gyro = *f.cal.FindTag(2)->gyro;
  const auto term = [](const SensorCalibration& c, double t) {
    return (c.M() * c.model.bias_per_c * (t - c.model.t_ref_c)).cwiseAbs().maxCoeff();
  };
  CHECK(warnings[0] ==
        fmt::format("sensor 2 accel: the validity range -40.00 .. 85.00 degC reaches beyond the "
                    "fitted span {:.2f} .. {:.2f} degC plus the 5 degC margin ({:.2f} .. {:.2f} "
                    "degC); the temperature term is extrapolated there: the tag applies {:.1f} mg "
                    "at -40.00 degC and {:.1f} mg at 85.00 degC (largest axis, 0 at t_ref_c "
                    "{:.2f} degC)",
                    range.min_c, range.max_c, range.min_c - 5, range.max_c + 5,
                    1000 * term(accel, -40.0), 1000 * term(accel, 85.0), accel.model.t_ref_c));
  CHECK_THAT(warnings[1],
             Catch::StartsWith("sensor 2 gyro: the validity range -40.00 .. 85.00 degC") &&
                 Catch::Contains(fmt::format("the tag applies {:.2f} deg/s at -40.00 degC",
                                             term(gyro, -40.0))));
  CHECK(r.value().accel->t_valid_min_c == -40.0);
  CHECK(r.value().accel->t_valid_max_c == 85.0);
  // And the range survives the calibration.json round trip.
  Result<Calibration> back = CalibrationFromJson(ToJson(f.cal), "cal.json");
  REQUIRE(back.ok());
  const auto& again = back.value().FindTag(2)->gyro->static_pose_temperature;
  REQUIRE(again.has_value());
  CHECK(again->min_c == range.min_c);
  CHECK(again->max_c == range.max_c);
  CHECK(again->poses == range.poses);
}

TEST_CASE("Blob from a fitted calibration and applied by the firmware and recovers the truth",
          "[blob][slow]") {
  const Fitted& f = FitOnce();
  Result<BlobContents> contents = BlobContentsFromCalibration(f.cal, Options());
  REQUIRE(contents.ok());
  Result<std::vector<uint8_t>> blob = WriteBlob(contents.value());
  REQUIRE(blob.ok());
  const uint8_t afs = contents.value().accel->fs_sel, gfs = contents.value().gyro->fs_sel;
  CHECK(afs == 0);
  CHECK(gfs == 0);
  const metro_fw_calibration cal = LoadOnTag(blob.value(), afs, gfs, 3);
  REQUIRE(cal.slot == 0);
  REQUIRE(cal.accel.status == METRO_FW_SENSOR_OK);
  REQUIRE(cal.gyro.status == METRO_FW_SENSOR_OK);

  // A fresh session of the same tag (same truth, new noise and poses).
  SimulationOptions so;
  so.seed = 42;
  so.sensor = 2;
  so.temperature = true;
  so.temp_start_c = 24.0;
  so.temp_end_c = 32.0;
  so.random_truth = false;
  so.truth = f.sim.truth;
  so.pose_set = PoseSet::kSphere;
  so.poses = 10;
  const SimulatedSession fresh = SimulateCalibrationSession(so).value();
  const Tag& tag = fresh.session.tags.front();
  const Quantity* col[7] = {tag.Find("ax_lsb"), tag.Find("ay_lsb"), tag.Find("az_lsb"),
                            tag.Find("gx_lsb"), tag.Find("gy_lsb"), tag.Find("gz_lsb"),
                            tag.Find("temp_c")};
  for (const Quantity* q : col) REQUIRE(q != nullptr);
  double ea = 0, eg = 0;
  const size_t n = tag.size();
  for (size_t k = 0; k < n; ++k) {
    int16_t ra[3], rg[3];
    for (int a = 0; a < 3; ++a) {
      ra[a] = static_cast<int16_t>(col[a]->values[k]);
      rg[a] = static_cast<int16_t>(col[3 + a]->values[k]);
    }
    float ya[3], yg[3];
    const float temp_c = static_cast<float>(col[6]->values[k]);
    REQUIRE(metro_fw_apply(&cal.accel, ra, temp_c, ya) == METRO_FW_OK);
    REQUIRE(metro_fw_apply(&cal.gyro, rg, temp_c, yg) == METRO_FW_OK);
    for (int a = 0; a < 3; ++a) {
      const double da = ya[a] - fresh.true_accel_g[k][a] * 9.80665;
      const double dg = yg[a] - fresh.true_gyro_dps[k][a] * kPi / 180.0;
      ea += da * da;
      eg += dg * dg;
    }
  }
  // Sensor noise per sample: 400 ug/sqrt(Hz) and 0.005 deg/s/sqrt(Hz) over 50 Hz; the
  // calibration error and quantisation add far less: the RMS stays within 10 % of the noise.
  const double rms_a = std::sqrt(ea / (3.0 * static_cast<double>(n)));
  const double rms_g = std::sqrt(eg / (3.0 * static_cast<double>(n)));
  CHECK(rms_a < 1.1 * 400e-6 * 9.80665 * std::sqrt(50.0));
  CHECK(rms_g < 1.1 * 0.005 * kPi / 180.0 * std::sqrt(50.0));

  // The stored uncertainties are the calibrator's, converted.
  const SensorCalibration& ca = *f.cal.FindTag(2)->accel;
  CHECK(contents.value().accel->u_b0_lsb[2] == ca.bias_u[2]);
  CHECK(contents.value().accel->u_m[4] == Approx(9.80665 * ca.matrix_u(1, 1)));
  CHECK(contents.value().accel->model_bits == (kModelBias | kModelFullMatrix | kModelLinearT));
}

// Firmware apply (binary32) against calibrate apply (double) on the same raw samples.
//
// Error bound, unit roundoff u = 2^-24 (IEEE 754 binary32), first order (Higham, Accuracy and
// Stability of Numerical Algorithms, 2nd ed., sec. 2.2 and 3.1): storing M, b0, b1, t_ref and
// T in binary32 errs by u times each; dT = T - t_ref then errs by
//   dT_err <= 2u (|T| + |t_ref| + |dT|);
// d_j = (r_j - b0_j) - b1_j*dT (r_j is exact) errs by at most 5u D_j + |b1_j| dT_err with
// D_j = |r_j| + |b0_j| + |b1_j||dT|; the 3-term dot product adds gamma_3 ~ 3u, and storing M
// u: |y_fw,i - y_i| <= sum_j |M_ij| (9u D_j + |b1_j| dT_err). The test uses 10u for the
// second-order terms.
TEST_CASE("Firmware apply equals calibrate apply within the binary32 bound", "[blob][slow]") {
  const Fitted& f = FitOnce();
  Result<BlobContents> contents = BlobContentsFromCalibration(f.cal, Options());
  REQUIRE(contents.ok());
  const metro_fw_calibration fw = LoadOnTag(WriteBlob(contents.value()).value(), 0, 0, 3);
  REQUIRE(fw.accel.status == METRO_FW_SENSOR_OK);

  Session session = f.sim.session;
  REQUIRE(ApplyCalibration(f.cal, &session).ok());
  const Tag& tag = session.tags.front();
  const double u = std::ldexp(1.0, -24);
  for (const auto& [sensor, prefix, out_suffix, si, fwcal] :
       {std::tuple{ImuSensor::kAccel, 'a', "_g", 9.80665, &fw.accel},
        std::tuple{ImuSensor::kGyro, 'g', "_dps", kPi / 180.0, &fw.gyro}}) {
    const SensorCalibration& c =
        sensor == ImuSensor::kAccel ? *f.cal.FindTag(2)->accel : *f.cal.FindTag(2)->gyro;
    const Eigen::Matrix3d m = si * c.model.Matrix();
    const Quantity* raw[3];
    const Quantity* cal[3];
    for (int a = 0; a < 3; ++a) {
      raw[a] = tag.Find(std::string(1, prefix) + "xyz"[a] + "_lsb");
      cal[a] = tag.Find(std::string(1, prefix) + "xyz"[a] + out_suffix);
      REQUIRE(raw[a] != nullptr);
      REQUIRE(cal[a] != nullptr);
    }
    const Quantity* temp = tag.Find("temp_c");
    REQUIRE(temp != nullptr);
    double worst_ratio = 0, worst_rel = 0;
    for (size_t k = 0; k < tag.size(); ++k) {
      int16_t r[3];
      for (int a = 0; a < 3; ++a) r[a] = static_cast<int16_t>(raw[a]->values[k]);
      const double t = temp->values[k];
      float y[3];
      REQUIRE(metro_fw_apply(fwcal, r, static_cast<float>(t), y) == METRO_FW_OK);
      const double dt = t - c.model.t_ref_c;
      const double dt_err = 2 * u * (std::fabs(t) + std::fabs(c.model.t_ref_c) + std::fabs(dt));
      for (int i = 0; i < 3; ++i) {
        double bound = 0;
        for (int j = 0; j < 3; ++j) {
          const double b1 = c.model.bias_per_c[j];
          const double dj = std::fabs(r[j]) + std::fabs(c.model.bias[j]) + std::fabs(b1 * dt);
          bound += std::fabs(m(i, j)) * (10 * u * dj + std::fabs(b1) * dt_err);
        }
        const double err = std::fabs(y[i] - si * cal[i]->values[k]);
        worst_ratio = std::max(worst_ratio, err / bound);
        worst_rel = std::max(worst_rel, bound / (32768.0 * m.row(i).norm()));
      }
    }
    INFO(ImuSensorName(sensor) << " worst error / bound " << worst_ratio);
    CHECK(worst_ratio <= 1.0);
    CHECK(worst_ratio > 0.0);  // binary32 does differ from double: the comparison is real
    // The bound is below 1 ppm of full scale (32768 LSB): it means binary32, not "close". Near
    // zero output the relative error is larger: r - b0 cancels (a 20 deg/s gyro bias is
    // 2600 LSB), which the bound accounts for through D_j.
    CHECK(worst_rel < 1e-6);
  }
}

// issue #23: `calibrate apply` (ApplyCalibration, double, on calibration.json) and the tag's own
// applies (metro_fw_apply_fixed, metro_fw_apply on the blob the firmware loaded) on one session
// whose temperature sweeps -40 ... 85 degC, far beyond the fitted 22 ... 34 degC: the host clamps
// to the validity range as the tag does, so they agree within 0.1 LSB at every sample. The
// temperatures are Q12 values (what the tag reads, metro_fw_mpu6050_temp_q12), so both sides
// see the same temperature. Before the clamp, the host extrapolated the temperature term where
// the tag held it at the range's end.
TEST_CASE("calibrate apply agrees with the firmware across and beyond the validity range",
          "[blob][slow]") {
  const Fitted& f = FitOnce();
  for (const bool wide : {false, true}) {
    BlobFromCalibrationOptions o = Options();
    ApplyCalibrationOptions ao;
    if (wide) {  // the same explicit ends on both sides
      o.t_valid_min_c = ao.validity.t_valid_min_c = -10.0;
      o.t_valid_max_c = ao.validity.t_valid_max_c = 60.0;
    }
    Result<BlobContents> contents = BlobContentsFromCalibration(f.cal, o);
    REQUIRE(contents.ok());
    const metro_fw_calibration fw = LoadOnTag(WriteBlob(contents.value()).value(), 0, 0, 3);
    REQUIRE(fw.accel.status == METRO_FW_SENSOR_OK);
    REQUIRE(fw.gyro.status == METRO_FW_SENSOR_OK);
    metro_fw_sensor_fixed fx_accel, fx_gyro;
    REQUIRE(metro_fw_fixed_from_cal(&fw.accel, &fx_accel) == METRO_FW_OK);
    REQUIRE(metro_fw_fixed_from_cal(&fw.gyro, &fx_gyro) == METRO_FW_OK);

    Session session = f.sim.session;
    Tag& tag = session.tags.front();
    Quantity* temp = tag.Find("temp_c");
    REQUIRE(temp != nullptr);
    const size_t n = tag.size();
    std::vector<int32_t> temp_q12(n);
    int64_t below = 0, above = 0;
    const double lo = contents.value().accel->t_valid_min_c,
                 hi = contents.value().accel->t_valid_max_c;
    for (size_t k = 0; k < n; ++k) {
      const double t = -40.0 + 125.0 * static_cast<double>(k) / static_cast<double>(n - 1);
      temp_q12[k] = static_cast<int32_t>(std::lround(t * 4096.0));
      temp->values[k] = temp_q12[k] / 4096.0;
      below += temp->values[k] < lo;
      above += temp->values[k] > hi;
    }
    Result<ApplySummary> summary = ApplyCalibration(f.cal, &session, ao);
    REQUIRE(summary.ok());
    REQUIRE(summary.value().temperature.size() == 2);
    for (const SensorTemperatureCount& c : summary.value().temperature) {
      CHECK(c.samples == static_cast<int64_t>(n));
      CHECK(c.below == below);
      CHECK(c.above == above);
      CHECK(c.validity.min_c == lo);
      CHECK(c.validity.max_c == hi);
    }
    CHECK(below > static_cast<int64_t>(n) / 10);  // the sweep reaches well beyond both ends
    CHECK(above > static_cast<int64_t>(n) / 10);
    for (const auto& [prefix, out_suffix, si, fwcal, fx] :
         {std::tuple{'a', "_g", 9.80665, &fw.accel, &fx_accel},
          std::tuple{'g', "_dps", kPi / 180.0, &fw.gyro, &fx_gyro}}) {
      const Quantity* raw[3];
      const Quantity* host[3];
      double row[3];
      for (int a = 0; a < 3; ++a) {
        raw[a] = tag.Find(std::string(1, prefix) + "xyz"[a] + "_lsb");
        host[a] = tag.Find(std::string(1, prefix) + "xyz"[a] + out_suffix);
        REQUIRE(raw[a] != nullptr);
        REQUIRE(host[a] != nullptr);
        row[a] = std::sqrt(double{fwcal->m[3 * a]} * fwcal->m[3 * a] +
                           double{fwcal->m[3 * a + 1]} * fwcal->m[3 * a + 1] +
                           double{fwcal->m[3 * a + 2]} * fwcal->m[3 * a + 2]);  // SI per LSB
      }
      double worst_fixed = 0, worst_float = 0;
      for (size_t k = 0; k < n; ++k) {
        int16_t r[3];
        for (int a = 0; a < 3; ++a) r[a] = static_cast<int16_t>(raw[a]->values[k]);
        int32_t y_q20[3];
        float y_f[3];
        REQUIRE(metro_fw_apply_fixed(fx, r, temp_q12[k], y_q20) == METRO_FW_OK);
        REQUIRE(metro_fw_apply(fwcal, r, static_cast<float>(temp->values[k]), y_f) == METRO_FW_OK);
        for (int i = 0; i < 3; ++i) {
          const double y_host = si * host[i]->values[k];
          worst_fixed =
              std::max(worst_fixed, std::fabs(std::ldexp(y_q20[i], -20) - y_host) / row[i]);
          worst_float = std::max(worst_float, std::fabs(y_f[i] - y_host) / row[i]);
        }
      }
      INFO(prefix << (wide ? " wide" : " default") << " range: worst fixed " << worst_fixed
                  << " LSB, float " << worst_float << " LSB");
      CHECK(worst_fixed < 0.1);
      CHECK(worst_float < 0.1);
      WARN(prefix << (wide ? " -10 .. 60 degC" : " default") << " range " << lo << " .. " << hi
                  << ": calibrate apply vs firmware fixed " << worst_fixed << " LSB, float "
                  << worst_float << " LSB");
    }
  }
  // What the clamp changes: at -40 degC the extrapolated term exceeds the clamped one by
  // M b1 (t_valid_min - (-40)) (the disagreement before issue #23 when the blob held the span).
  const SensorCalibration& accel = *f.cal.FindTag(2)->accel;
  const SensorCalibration& gyro = *f.cal.FindTag(2)->gyro;
  const double lo = accel.static_pose_temperature->min_c - 5.0;
  const double da = (accel.M() * accel.model.bias_per_c * (lo + 40.0)).cwiseAbs().maxCoeff();
  const double dg = (gyro.M() * gyro.model.bias_per_c * (lo + 40.0)).cwiseAbs().maxCoeff();
  WARN("without the clamp calibrate apply would differ from the tag at -40 degC by "
       << 1000 * da << " mg and " << dg << " deg/s");
  CHECK(1000 * da > 1.0);  // a real difference, far above 0.1 LSB (0.006 mg)
}

#ifdef METRO_CALIBRATE_EXE
TEST_CASE("calibrate blob and apply say the validity range and the samples outside it",
          "[blob][apps][slow]") {
  const Fitted& f = FitOnce();
  const std::string cal = "metro_validity_cal.json", csv = "metro_validity_session.csv";
  REQUIRE(WriteFileAtomically(cal, FormatCalibrationJson(f.cal)).ok());
  Session session = f.sim.session;
  Quantity* temp = session.tags.front().Find("temp_c");
  REQUIRE(temp != nullptr);
  const size_t n = temp->values.size();
  for (size_t k = 0; k < n; ++k) temp->values[k] = k < n / 4 ? 0.0 : 30.0;  // a quarter at 0
  REQUIRE(WriteFileAtomically(csv, FormatSessionCsv(session, false)).ok());
  const PoseTemperatureRange& span = *f.cal.FindTag(2)->accel->static_pose_temperature;

  testing::ProgramRun b = testing::RunProgram(
      METRO_CALIBRATE_EXE,
      "blob " + cal + " --sensor 2 --device-id 0011223344556677 -o metro_validity.bin");
  REQUIRE(b.exit_code == 0);
  CHECK_THAT(b.err, Catch::Contains(fmt::format("accel: the tag clamps the temperature to {:.2f} "
                                                "..",
                                                span.min_c - 5)));
  CHECK(b.err.find("warning") == std::string::npos);
  testing::ProgramRun w = testing::RunProgram(
      METRO_CALIBRATE_EXE, "blob " + cal +
                               " --sensor 2 --device-id 0011223344556677 -o metro_validity.bin "
                               "--t-valid-min-c -40");
  REQUIRE(w.exit_code == 0);
  CHECK_THAT(w.err, Catch::Contains("warning: sensor 2 accel: the validity range -40.00 .. ") &&
                        Catch::Contains("mg at -40.00 degC") &&
                        Catch::Contains("warning: sensor 2 gyro: the validity range -40.00 .. ") &&
                        Catch::Contains("deg/s at -40.00 degC"));

  testing::ProgramRun a = testing::RunProgram(
      METRO_CALIBRATE_EXE, "apply " + cal + " " + csv + " -o metro_validity_out.csv");
  REQUIRE(a.exit_code == 0);
  CHECK_THAT(a.err, Catch::Contains(fmt::format(
                        "sensor 2 accel: {} of {} samples outside the validity range {:.2f} .. "
                        "{:.2f} degC ({} below, 0 above; from the static poses' span",
                        n / 4, n, span.min_c - 5, span.max_c + 5, n / 4)));
  CHECK_THAT(a.err, Catch::Contains("their temperature clamped to the range, as the tag does"));
  testing::ProgramRun same = testing::RunProgram(
      METRO_CALIBRATE_EXE,
      "apply " + cal + " " + csv + " -o metro_validity_out.csv --t-valid-min-c -40 --quiet");
  REQUIRE(same.exit_code == 0);
  CHECK_THAT(same.err, Catch::Contains("warning: sensor 2 accel: the validity range -40.00 .. "));
  CHECK(same.err.find("outside") == std::string::npos);
  testing::ProgramRun bad = testing::RunProgram(
      METRO_CALIBRATE_EXE, "apply " + cal + " " + csv +
                               " -o metro_validity_out.csv --t-valid-min-c 20 --t-valid-max-c 21");
  CHECK(bad.exit_code == 2);
  CHECK_THAT(bad.err, Catch::Contains("is 1 degC wide; expected at least 2 degC"));
  for (const std::string& p :
       {cal, csv, std::string("metro_validity.bin"), std::string("metro_validity_out.csv")}) {
    std::remove(p.c_str());
  }
}
#endif

}  // namespace metro::blob

namespace metro::blob {

TEST_CASE("Mapping: the blob's M is calibration.json's matrix (section 10)", "[blob][security]") {
  // issue #20: `calibrate blob` built M from scale and misalignment and ignored `matrix`.
  const std::string path = std::string(METRO_SOURCE_DIR) + "/datasets/golden/";
  std::ifstream f(path + "calibration_sensor2.json");
  nlohmann::json j = nlohmann::json::parse(f);
  // One unit in the last place: within the reader's tolerance, so the file is accepted, and
  // only a blob built from `matrix` carries this value.
  const double tk = j["tags"][0]["accel"]["matrix"][1][2].get<double>();
  const double file_value = std::nextafter(tk, 0.0);
  j["tags"][0]["accel"]["matrix"][1][2] = file_value;
  Result<Calibration> cal = CalibrationFromJson(j.dump(2), "calibration_sensor2.json");
  REQUIRE(cal.ok());
  BlobFromCalibrationOptions o;
  o.sensor = 2;
  o.device_id = kId;
  o.seq = 3;
  Result<BlobContents> c = BlobContentsFromCalibration(cal.value(), o);
  REQUIRE(c.ok());
  CHECK(c.value().accel->m[5] == 9.80665 * file_value);
  CHECK(c.value().accel->m[5] != 9.80665 * tk);
}

}  // namespace metro::blob
