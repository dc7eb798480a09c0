// The stages of CalibrateTag one at a time (src/calibration/calibrate_stages.hpp) and the
// parameter-block layout they share (src/calibration/parameter_blocks.hpp), on small inputs
// whose answers follow by hand.
#include "calibration/calibrate_stages.hpp"

#include <ceres/cost_function.h>

#include <Eigen/Core>
#include <array>
#include <catch2/catch.hpp>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "calibration/parameter_blocks.hpp"
#include "calibration/residuals.hpp"

namespace metro {
namespace {

namespace ci = calibration_internal;
using PB = ci::ParameterBlocks;

const ModelKind kKinds[] = {ModelKind::kBias, ModelKind::kScale, ModelKind::kFull};
const ImuSensor kSensors[] = {ImuSensor::kAccel, ImuSensor::kGyro};

// ---- Parameter blocks ---------------------------------------------------------------------

TEST_CASE("ParameterBlocks: the covariance order of imu_model.hpp for every model",
          "[calibration][stages]") {
  // docs/calibration-model.md, "Parameter order".
  CHECK(PB::FreeNames(ImuSensor::kAccel, ModelKind::kFull, true) ==
        std::vector<std::string>{"b_x", "b_y", "b_z", "k_x", "k_y", "k_z", "a_yz", "a_zy", "a_zx",
                                 "b1_x", "b1_y", "b1_z"});
  CHECK(PB::FreeNames(ImuSensor::kGyro, ModelKind::kFull, true) ==
        std::vector<std::string>{"b_x", "b_y", "b_z", "k_x", "k_y", "k_z", "g_yz", "g_zy", "g_xz",
                                 "g_zx", "g_xy", "g_yx", "b1_x", "b1_y", "b1_z"});
  CHECK(PB::FreeNames(ImuSensor::kGyro, ModelKind::kBias, true) ==
        std::vector<std::string>{"b_x", "b_y", "b_z", "b1_x", "b1_y", "b1_z"});
  CHECK(PB::FreeNames(ImuSensor::kAccel, ModelKind::kScale, false) ==
        std::vector<std::string>{"b_x", "b_y", "b_z", "k_x", "k_y", "k_z"});

  for (ImuSensor s : kSensors) {
    CHECK(PB::Size(s, PB::kMisalignment) == MisalignmentCount(s));
    for (ModelKind kind : kKinds) {
      for (bool temp : {false, true}) {
        INFO(ImuSensorName(s) << " " << ModelKindName(kind) << " temperature " << temp);
        const std::vector<std::string> names = PB::FreeNames(s, kind, temp);
        // b(3) always, k(3) unless bias, t(3 or 6) when full, b1(3) with temperature.
        const int expected = 3 + (kind != ModelKind::kBias ? 3 : 0) +
                             (kind == ModelKind::kFull ? (s == ImuSensor::kAccel ? 3 : 6) : 0) +
                             (temp ? 3 : 0);
        CHECK(PB::FreeCount(s, kind, temp) == expected);
        CHECK(static_cast<int>(names.size()) == expected);
        // Each free role starts where FreeNames has its first name.
        CHECK(names[static_cast<size_t>(PB::FreeOffset(s, kind, temp, PB::kBias))] == "b_x");
        if (kind != ModelKind::kBias) {
          CHECK(names[static_cast<size_t>(PB::FreeOffset(s, kind, temp, PB::kScale))] == "k_x");
        } else {
          CHECK(PB::FreeOffset(s, kind, temp, PB::kScale) == -1);
        }
        if (kind == ModelKind::kFull) {
          CHECK(names[static_cast<size_t>(PB::FreeOffset(s, kind, temp, PB::kMisalignment))] ==
                (s == ImuSensor::kAccel ? "a_yz" : "g_yz"));
        }
        if (temp) {
          CHECK(names[static_cast<size_t>(PB::FreeOffset(s, kind, temp, PB::kBiasPerC))] == "b1_x");
        }
      }
    }
  }
}

TEST_CASE("ParameterBlocks: identity start, blocks in Block order in memory",
          "[calibration][stages]") {
  PB x;
  const std::array<const double*, PB::kBlockCount> all = x.AllConst();
  for (int b = 0; b < PB::kBlockCount; ++b) {
    const bool scale = b == PB::kAccelScale || b == PB::kGyroScale;
    for (int i = 0; i < PB::kSize[static_cast<size_t>(b)]; ++i) {
      CHECK(all[static_cast<size_t>(b)][i] == (scale ? 1.0 : 0.0));
    }
    // Ceres's covariance orders blocks by address: the addresses follow the Block order.
    if (b > 0) {
      CHECK(all[static_cast<size_t>(b)] ==
            all[static_cast<size_t>(b - 1)] + PB::kSize[static_cast<size_t>(b - 1)]);
    }
  }
  CHECK(x.SensorBlocks(ImuSensor::kGyro).front() == x[PB::kGyroBias]);
  CHECK(x.All().size() == 8);
}

TEST_CASE("ParameterBlocks: the residuals take blocks of the table's sizes",
          "[calibration][stages]") {
  auto sizes = [](const ceres::CostFunction& c) {
    std::vector<int> out(c.parameter_block_sizes().begin(), c.parameter_block_sizes().end());
    return out;
  };
  const Eigen::Vector3d v(1, 2, 3);
  std::unique_ptr<ceres::CostFunction> accel(ci::NewAccelNormCost(v, 0, 1, 1));
  std::unique_ptr<ceres::CostFunction> table(ci::NewGyroTableCost(v, 0, 90, 1));
  std::unique_ptr<ceres::CostFunction> statik(ci::NewGyroStaticCost(v, 0, 1));
  std::unique_ptr<ceres::CostFunction> rotation(ci::NewRotationCost(ci::RotationData{}));
  CHECK(sizes(*accel) == std::vector<int>{3, 3, 3, 3});
  CHECK(sizes(*table) == std::vector<int>{3, 3, 6, 3});
  CHECK(sizes(*statik) == std::vector<int>{3, 3});
  CHECK(sizes(*rotation) == std::vector<int>{3, 3, 3, 3, 3, 3, 6, 3});
}

// ---- Temperature decision -------------------------------------------------------------------

std::vector<ci::Pose> PosesAt(const std::vector<double>& temps_c) {
  std::vector<ci::Pose> out;
  for (double t : temps_c) {
    ci::Pose p;
    p.temp_c = t;
    out.push_back(p);
  }
  return out;
}

TEST_CASE("DecideTemperature: auto fits b1 from a 2 degC span, t_ref the pose mean",
          "[calibration][stages]") {
  CalibrationOptions o;  // kAuto, min_temp_span_c = 2.
  const std::vector<ci::Pose> poses = PosesAt({20.0, 23.0, 21.0});
  Result<ci::TemperatureDecision> r = ci::DecideTemperature(true, poses, o, 4);
  REQUIRE(r.ok());
  CHECK(r.value().fit);
  CHECK(r.value().t_ref_c == Approx(64.0 / 3.0).epsilon(1e-15));
  REQUIRE(r.value().pose_range.has_value());
  CHECK(r.value().pose_range->min_c == 20.0);
  CHECK(r.value().pose_range->max_c == 23.0);
  CHECK(r.value().pose_range->mean_c == Approx(64.0 / 3.0).epsilon(1e-15));
  CHECK(r.value().pose_range->poses == 3);

  // 1.5 degC: no term, t_ref 0, the span still reported.
  r = ci::DecideTemperature(true, PosesAt({20.0, 21.5, 21.0}), o, 4);
  REQUIRE(r.ok());
  CHECK_FALSE(r.value().fit);
  CHECK(r.value().t_ref_c == 0.0);
  REQUIRE(r.value().pose_range.has_value());
  CHECK(r.value().pose_range->max_c - r.value().pose_range->min_c == 1.5);

  // Off: never, whatever the span.
  o.temperature = TemperatureMode::kOff;
  r = ci::DecideTemperature(true, poses, o, 4);
  REQUIRE(r.ok());
  CHECK_FALSE(r.value().fit);
  CHECK(r.value().pose_range.has_value());

  // Without temp_c in every input: no term and no span.
  o.temperature = TemperatureMode::kAuto;
  r = ci::DecideTemperature(false, poses, o, 4);
  REQUIRE(r.ok());
  CHECK_FALSE(r.value().fit);
  CHECK_FALSE(r.value().pose_range.has_value());
}

TEST_CASE("DecideTemperature: on needs temp_c and some span", "[calibration][stages]") {
  CalibrationOptions o;
  o.temperature = TemperatureMode::kOn;
  Result<ci::TemperatureDecision> r = ci::DecideTemperature(true, PosesAt({25.0, 25.5}), o, 3);
  REQUIRE(r.ok());
  CHECK(r.value().fit);
  CHECK(r.value().t_ref_c == 25.25);

  r = ci::DecideTemperature(false, PosesAt({25.0, 26.0}), o, 3);
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().message ==
        "sensor 3: a temperature term was requested but not every input has a temp_c column");

  r = ci::DecideTemperature(true, PosesAt({25.0, 25.0}), o, 3);
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().message.find("sensor 3: a temperature term was requested but the static "
                               "poses all have the same temperature") == 0);
}

// ---- Rotations ----------------------------------------------------------------------------

// One record at 100 Hz: static [0, 100), rotation [100, 150), static [150, 250), rotation
// [250, 260), static [260, 360). The accelerometer reads pose i's value i + 1 on every axis in
// pose i, the gyroscope (k, 2k, 3k) at sample k, the temperature 20 + k / 100.
ci::Record ThreePoseRecord() {
  ci::Record r;
  const size_t n = 360;
  for (size_t k = 0; k < n; ++k) {
    const double kd = static_cast<double>(k);
    r.t_s.push_back(kd / 100.0);
    const double pose = k < 150 ? 1.0 : (k < 260 ? 2.0 : 3.0);
    r.accel.push_back(Eigen::Vector3d::Constant(pose));
    r.gyro.push_back(Eigen::Vector3d(kd, 2 * kd, 3 * kd));
    r.temp_c.push_back(20.0 + kd / 100.0);
  }
  r.accel_sat.assign(n, 0);
  r.gyro_sat.assign(n, 0);
  r.saturated.assign(n, 0);
  auto add = [&r](SegmentKind kind, size_t begin, size_t end) {
    Segment s;
    s.kind = kind;
    s.begin = begin;
    s.end = end;
    r.seg.segments.push_back(s);
  };
  add(SegmentKind::kStatic, 0, 100);
  add(SegmentKind::kRotation, 100, 150);
  add(SegmentKind::kStatic, 150, 250);
  add(SegmentKind::kRotation, 250, 260);
  add(SegmentKind::kStatic, 260, 360);
  return r;
}

TEST_CASE("BuildRotations: samples from the end of one pose to the start of the next",
          "[calibration][stages]") {
  const std::vector<ci::Record> records = {ThreePoseRecord()};
  const ci::PoseMeans poses = ci::MeanPoses(records, true);
  REQUIRE(poses.statics.size() == 3);
  CHECK(poses.statics[1].accel == Eigen::Vector3d::Constant(2.0));
  // Mean temperature of samples 150 .. 249: 20 + 1.995.
  CHECK(poses.statics[1].temp_c == Approx(21.995).epsilon(1e-14));

  std::vector<Segment> segments = records.front().seg.segments;
  ci::TemperatureDecision temperature;
  temperature.fit = true;
  temperature.t_ref_c = 21.0;
  const Eigen::Vector3d accel_ref(2, 3, 4);
  const ci::RotationSet set =
      ci::BuildRotations(records, poses.statics, temperature, accel_ref, 60.0, &segments);
  REQUIRE(set.data.size() == 2);
  REQUIRE(set.segments.size() == 2);
  CHECK(set.segments[0] == &segments[1]);
  CHECK(set.segments[1] == &segments[3]);

  const ci::RotationData& a = set.data[0];
  // Samples k = 100 .. 150 (pose end .. next pose begin), each covering (t_{k-1}, t_k].
  REQUIRE(a.gyro.size() == 51);
  CHECK(a.gyro.front() == Eigen::Vector3d(100, 200, 300));
  CHECK(a.gyro.back() == Eigen::Vector3d(150, 300, 450));
  REQUIRE(a.dt_s.size() == 51);
  for (double dt : a.dt_s) CHECK(dt == Approx(0.01).epsilon(1e-9));
  CHECK(a.accel_start == Eigen::Vector3d(2, 3, 4));  // accel_ref * pose 0's mean (1, 1, 1).
  CHECK(a.accel_end == Eigen::Vector3d(4, 6, 8));
  CHECK(a.dtemp_start_c == Approx(20.495 - 21.0).epsilon(1e-12));
  CHECK(a.dtemp_end_c == Approx(21.995 - 21.0).epsilon(1e-12));
  CHECK(a.dtemp_c.front() == Approx(21.0 - 21.0).margin(1e-12));
  CHECK(a.dtemp_c.back() == Approx(21.5 - 21.0).epsilon(1e-12));
  CHECK(set.data[1].gyro.size() == 11);  // 250 .. 260.
  CHECK(segments[1].used);
  CHECK(segments[3].used);
}

TEST_CASE("BuildRotations: saturated or too long rotations are not used", "[calibration][stages]") {
  std::vector<ci::Record> records = {ThreePoseRecord()};
  records[0].gyro_sat[255] = 1;
  const ci::PoseMeans poses = ci::MeanPoses(records, true);
  std::vector<Segment> segments = records.front().seg.segments;
  // The first rotation spans t_150 - t_99 = 0.51 s.
  const ci::RotationSet set = ci::BuildRotations(records, poses.statics, ci::TemperatureDecision{},
                                                 Eigen::Vector3d::Ones(), 0.5, &segments);
  CHECK(set.data.empty());
  CHECK_FALSE(segments[1].used);
  CHECK(segments[1].note == "longer than 0.5 s");
  CHECK_FALSE(segments[3].used);
  CHECK(segments[3].note == "saturated gyroscope samples");

  // Without a temperature term every temperature offset is 0.
  std::vector<Segment> again = records.front().seg.segments;
  const ci::RotationSet kept = ci::BuildRotations(records, poses.statics, ci::TemperatureDecision{},
                                                  Eigen::Vector3d::Ones(), 0.52, &again);
  REQUIRE(kept.data.size() == 1);
  CHECK(kept.data[0].dtemp_start_c == 0.0);
  for (double d : kept.data[0].dtemp_c) CHECK(d == 0.0);
}

TEST_CASE("CheckGyroMotion: 2 per rotation, 1 per table run, parameters + 3 needed",
          "[calibration][stages]") {
  // Full model: 12 - 3 bias parameters = 9 that need motion, so 12 residuals: 6 rotations.
  CHECK(ci::CheckGyroMotion(0, 6, ModelKind::kFull, false, 1).ok());
  CHECK(ci::CheckGyroMotion(12, 0, ModelKind::kFull, true, 1).ok());
  const Status few = ci::CheckGyroMotion(1, 5, ModelKind::kFull, false, 1);
  REQUIRE_FALSE(few.ok());
  CHECK(few.error().message.find("sensor 1: 5 hand rotations between static poses and 1 table "
                                 "runs found; the gyroscope 'full' model needs at least 6 "
                                 "rotations (or 12 table runs") == 0);
  // Scale: 3 parameters need 6 residuals.
  CHECK(ci::CheckGyroMotion(0, 3, ModelKind::kScale, false, 1).ok());
  CHECK_FALSE(ci::CheckGyroMotion(1, 2, ModelKind::kScale, false, 1).ok());
  // Bias: the static poses alone.
  CHECK(ci::CheckGyroMotion(0, 0, ModelKind::kBias, true, 1).ok());
}

// ---- Start values -------------------------------------------------------------------------

// Pose means on an axis-aligned ellipsoid: b + r u over the 26 cube directions u.
std::vector<ci::Pose> EllipsoidPoses(const Eigen::Vector3d& b, const Eigen::Vector3d& r,
                                     bool upper_only = false) {
  std::vector<ci::Pose> out;
  for (int x = -1; x <= 1; ++x) {
    for (int y = -1; y <= 1; ++y) {
      for (int z = -1; z <= 1; ++z) {
        if (x == 0 && y == 0 && z == 0) continue;
        if (upper_only && z < 1) continue;
        ci::Pose p;
        const Eigen::Vector3d u = Eigen::Vector3d(x, y, z).normalized();
        p.accel = b + r.cwiseProduct(u);
        out.push_back(p);
      }
    }
  }
  return out;
}

TEST_CASE("StartAccel: the ellipsoid's centre and radii give bias and scale",
          "[calibration][stages]") {
  const Eigen::Vector3d b(120, -250, 310), r(16000, 16500, 17100);  // LSB
  const std::vector<ci::Pose> poses = EllipsoidPoses(b, r);
  CalibrationOptions o;
  std::vector<std::string> warnings;
  Result<ci::SensorStart> s = ci::StartAccel(poses, 1.0, "LSB", false, o, 1, &warnings);
  REQUIRE(s.ok());
  CHECK(warnings.empty());
  for (int a = 0; a < 3; ++a) {
    CHECK(s.value().bias[a] == Approx(b[a]).margin(1e-6));
    CHECK(s.value().scale[a] == Approx(1.0 / r[a]).epsilon(1e-10));
  }
  // The scaled start: b' = k b, k' = 1; the gyroscope's blocks untouched.
  PB x;
  ci::SetScaledStart(ImuSensor::kAccel, s.value(), &x);
  for (int a = 0; a < 3; ++a) {
    CHECK(x[PB::kAccelBias][a] == Approx(b[a] / r[a]).epsilon(1e-9));
    CHECK(x[PB::kAccelScale][a] == 1.0);
    CHECK(x[PB::kGyroBias][a] == 0.0);
  }

  // Too few poses for the full model with a temperature term: 12 parameters (u from the
  // poses' noise), 3 more with a robust loss (u from the residuals' scatter).
  const std::vector<ci::Pose> few(poses.begin(), poses.begin() + 11);
  s = ci::StartAccel(few, 1.0, "LSB", true, o, 1, &warnings);
  REQUIRE_FALSE(s.ok());
  CHECK(s.error().message.find("sensor 1: 11 static poses found; the accelerometer 'full' model "
                               "with temperature term has 12 parameters and needs at least 12") ==
        0);
  const std::vector<ci::Pose> fourteen(poses.begin(), poses.begin() + 14);
  // (Enough poses with the trivial loss; these 14 have no +X pose, which is the next refusal.)
  s = ci::StartAccel(fourteen, 1.0, "LSB", true, o, 1, &warnings);
  REQUIRE_FALSE(s.ok());
  CHECK(s.error().message.find("do not span the sphere") != std::string::npos);
  o.loss = LossKind::kCauchy;
  s = ci::StartAccel(fourteen, 1.0, "LSB", true, o, 1, &warnings);
  REQUIRE_FALSE(s.ok());
  CHECK(s.error().message.find("needs at least 15") != std::string::npos);
}

TEST_CASE("StartAccel: poses that do not span the sphere", "[calibration][stages]") {
  const std::vector<ci::Pose> upper =
      EllipsoidPoses(Eigen::Vector3d::Zero(), Eigen::Vector3d::Constant(16384), true);
  REQUIRE(upper.size() == 9);
  CalibrationOptions o;
  o.accel_model = ModelKind::kBias;  // 3 parameters, 6 poses needed.
  std::vector<std::string> warnings;
  Result<ci::SensorStart> s = ci::StartAccel(upper, 1.0, "LSB", false, o, 2, &warnings);
  REQUIRE(s.ok());  // A warning for the bias model ...
  // The nominal 16384 LSB/g at +-2 g (the bias model holds K).
  CHECK(s.value().scale == Eigen::Vector3d::Constant(1.0 / 16384));
  REQUIRE(warnings.size() == 1);
  CHECK(warnings[0].find("no pose had the -Z axis within 60 deg of up") != std::string::npos);
  o.accel_model = ModelKind::kScale;  // ... an error for the others.
  warnings.clear();
  s = ci::StartAccel(upper, 1.0, "LSB", false, o, 2, &warnings);
  REQUIRE_FALSE(s.ok());
  CHECK(s.error().message.find("sensor 2: the static poses do not span the sphere") == 0);
}

// ---- Assembly -----------------------------------------------------------------------------

TEST_CASE("Unscale: parameters and covariance back to input units", "[calibration][stages]") {
  const Eigen::Vector3d ref(2, 4, 8);
  PB x;
  for (int a = 0; a < 3; ++a) {
    x[PB::kAccelBias][a] = 10.0;
    x[PB::kAccelScale][a] = 1.5;
    x[PB::kAccelMisalignment][a] = 0.01;
    x[PB::kAccelBiasPerC][a] = 1.0;
  }
  // Full model with temperature: 12 free parameters, unit covariance.
  Eigen::MatrixXd cov = Eigen::MatrixXd::Identity(12, 12);
  cov(0, 3) = cov(3, 0) = 0.5;  // b_x with k_x.
  ci::Unscale(ref, ImuSensor::kAccel, ModelKind::kFull, true, &x, &cov);
  for (int a = 0; a < 3; ++a) {
    CHECK(x[PB::kAccelBias][a] == 10.0 / ref[a]);
    CHECK(x[PB::kAccelScale][a] == 1.5 * ref[a]);
    CHECK(x[PB::kAccelMisalignment][a] == 0.01);
    CHECK(x[PB::kAccelBiasPerC][a] == 1.0 / ref[a]);
    CHECK(cov(a, a) == 1.0 / (ref[a] * ref[a]));          // b = b' / ref
    CHECK(cov(3 + a, 3 + a) == ref[a] * ref[a]);          // k = k' ref
    CHECK(cov(6 + a, 6 + a) == 1.0);                      // t unchanged
    CHECK(cov(9 + a, 9 + a) == 1.0 / (ref[a] * ref[a]));  // b1 = b1' / ref
  }
  CHECK(cov(0, 3) == 0.5);  // (1 / 2) * 0.5 * 2
  CHECK(x[PB::kGyroScale][0] == 1.0);

  // Bias model without temperature: 3 rows.
  Eigen::MatrixXd small = Eigen::MatrixXd::Identity(3, 3);
  ci::Unscale(ref, ImuSensor::kGyro, ModelKind::kBias, false, &x, &small);
  CHECK(small(2, 2) == 1.0 / 64);
}

TEST_CASE("MakeSensorCalibration: the sensor's blocks and FreeNames", "[calibration][stages]") {
  PB x;
  for (int i = 0; i < 6; ++i) x[PB::kGyroMisalignment][i] = 0.001 * (i + 1);
  for (int a = 0; a < 3; ++a) {
    x[PB::kGyroBias][a] = a + 1.0;
    x[PB::kGyroScale][a] = 1.0 / 131;
  }
  const int p = PB::FreeCount(ImuSensor::kGyro, ModelKind::kFull, false);
  const SensorCalibration c =
      ci::MakeSensorCalibration(ImuSensor::kGyro, ModelKind::kFull, false, 0.0, "LSB", x,
                                Eigen::MatrixXd::Identity(p, p) * 1e-12);
  CHECK(c.model.bias == Eigen::Vector3d(1, 2, 3));
  CHECK(c.model.scale == Eigen::Vector3d::Constant(1.0 / 131));
  CHECK(c.model.misalignment == std::vector<double>{0.001, 0.002, 0.003, 0.004, 0.005, 0.006});
  CHECK(c.model.output_unit == "deg/s");
  CHECK(c.parameter_names == PB::FreeNames(ImuSensor::kGyro, ModelKind::kFull, false));
  CHECK(c.bias_u[1] == Approx(1e-6));
  CHECK(c.misalignment_u[5] == Approx(1e-6));
}

}  // namespace
}  // namespace metro
