#include "metro/calibration/segments.hpp"

#include <catch2/catch.hpp>
#include <cmath>
#include <random>

#include "metro/calibration/simulate.hpp"

namespace metro {
namespace {

// 8 poses of 4 s at 100 Hz with distinct means, separated by 1 s of motion (a large swing);
// noise sd 0.01. The truth is the pose intervals.
TEST_CASE("Static detector finds every pose inside its true interval", "[calibration]") {
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 0.01);
  std::vector<double> t;
  std::vector<Eigen::Vector3d> accel, gyro;
  std::vector<std::pair<double, double>> truth;
  double now = 0;
  for (int pose = 0; pose < 8; ++pose) {
    const Eigen::Vector3d mean(std::cos(pose), std::sin(pose), 0.3 * pose - 1.0);
    truth.push_back({now, now + 4.0});
    for (int k = 0; k < 400; ++k, now += 0.01) {
      t.push_back(now);
      accel.push_back(mean + Eigen::Vector3d(noise(rng), noise(rng), noise(rng)));
      gyro.push_back(Eigen::Vector3d(noise(rng), noise(rng), noise(rng)));
    }
    if (pose == 7) break;
    for (int k = 0; k < 100; ++k, now += 0.01) {
      t.push_back(now);
      const double s = std::sin(3.14159 * k / 100.0);
      accel.push_back(mean + Eigen::Vector3d(s, -s, 0.5 * s));
      gyro.push_back(Eigen::Vector3d(50 * s, 20 * s, -30 * s));
    }
  }
  SegmentationInput in;
  in.t_s = &t;
  in.accel = &accel;
  in.gyro = &gyro;
  const SegmentationSummary s = DetectSegments(in, SegmentationOptions());
  REQUIRE(s.static_count == 8);
  CHECK(s.rotation_count == 7);
  CHECK(s.table_count == 0);
  int i = 0;
  for (const Segment& seg : s.segments) {
    if (seg.kind != SegmentKind::kStatic) continue;
    // Inside the true pose, shortened by at most one window (1 s) plus a sample at each end.
    CHECK(seg.start_s >= truth[static_cast<size_t>(i)].first - 1e-9);
    CHECK(seg.end_s <= truth[static_cast<size_t>(i)].second + 1e-9);
    CHECK(seg.end_s - seg.start_s >= 4.0 - 1.0 - 0.05);
    ++i;
  }
  // The noise floor of 3 axes of sd 0.01: about 3e-4.
  CHECK(s.accel_floor == Approx(3e-4).epsilon(0.2));
}

TEST_CASE("Table runs are found from table_rate_dps and trimmed", "[calibration]") {
  SimulationOptions o;
  o.poses = 3;
  o.table_rates_dps = {60.0, -60.0};
  o.table_run_s = 4.0;
  const SimulatedSession sim = SimulateCalibrationSession(o).value();
  const Tag& tag = sim.session.tags.front();
  std::vector<Eigen::Vector3d> accel(tag.size()), gyro(tag.size());
  for (size_t k = 0; k < tag.size(); ++k) {
    for (int a = 0; a < 3; ++a) {
      accel[k][a] = tag.quantities[static_cast<size_t>(a)].values[k];
      gyro[k][a] = tag.quantities[static_cast<size_t>(3 + a)].values[k];
    }
  }
  const std::vector<double>& rate = tag.quantities[6].values;
  REQUIRE(tag.quantities[6].name == "table_rate_dps");
  SegmentationInput in;
  in.t_s = &tag.t_s;
  in.accel = &accel;
  in.gyro = &gyro;
  in.table_rate_dps = &rate;
  const SegmentationSummary s = DetectSegments(in, SegmentationOptions());
  CHECK(s.table_count == 6);
  // Each pose: the still period and a stop after each run are separate static intervals.
  CHECK(s.static_count == 9);
  for (const Segment& seg : s.segments) {
    if (seg.kind != SegmentKind::kTable) continue;
    CHECK(std::abs(seg.table_rate_dps) == 60.0);
    // 4 s run less 0.5 s at each end.
    CHECK(seg.end_s - seg.start_s == Approx(3.0).margin(0.02));
  }
}

TEST_CASE("Segmentation options are validated", "[calibration]") {
  SegmentationOptions o;
  std::string why;
  CHECK(o.IsValid(&why));
  o.threshold_factors = {0.5};
  CHECK_FALSE(o.IsValid(&why));
  CHECK(why == "every threshold factor must be > 1");
}

}  // namespace
}  // namespace metro
