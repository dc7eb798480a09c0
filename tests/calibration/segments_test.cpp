#include "metro/calibration/segments.hpp"

#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>

#include "metro/calibration/segment_file.hpp"
#include "metro/sim/calibration_session.hpp"

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

// A record built piece by piece at 100 Hz: still stretches (accelerometer mean, gyroscope
// rate), smooth swings between them, noise sd 0.01 on both sensors.
struct Builder {
  std::mt19937 rng{11};
  std::normal_distribution<double> noise{0.0, 0.01};
  std::vector<double> t;
  std::vector<Eigen::Vector3d> accel, gyro;
  double now = 0;
  void Still(const Eigen::Vector3d& a, const Eigen::Vector3d& rate_dps, double s) {
    for (int k = 0; k < static_cast<int>(std::lround(s * 100)); ++k, now += 0.01) {
      t.push_back(now);
      accel.push_back(a + Eigen::Vector3d(noise(rng), noise(rng), noise(rng)));
      gyro.push_back(rate_dps + Eigen::Vector3d(noise(rng), noise(rng), noise(rng)));
    }
  }
  void Swing(const Eigen::Vector3d& a, double s) {
    const int n = static_cast<int>(std::lround(s * 100));
    for (int k = 0; k < n; ++k, now += 0.01) {
      const double x = std::sin(3.14159 * k / n);
      t.push_back(now);
      accel.push_back(a + Eigen::Vector3d(x, -x, 0.5 * x));
      gyro.push_back(Eigen::Vector3d(50 * x, 20 * x, -30 * x));
    }
  }
  SegmentationSummary Detect(const SegmentationOptions& o) {
    SegmentationInput in;
    in.t_s = &t;
    in.accel = &accel;
    in.gyro = &gyro;
    return DetectSegments(in, o);
  }
};

Eigen::Vector3d PoseMean(int pose) {
  return Eigen::Vector3d(std::cos(pose), std::sin(pose), 0.3 * pose - 1.0);
}

// Issue #23: a turntable turn at a steady -30 deg/s about the vertical keeps the accelerometer
// as quiet as a pose; the gyroscope mean (30 deg/s from the bias of 0.5 deg/s) is not a bias.
TEST_CASE("A steady rotation is never a static pose", "[calibration]") {
  Builder b;
  const Eigen::Vector3d bias(0.5, -0.2, 0.1);
  for (int pose = 0; pose < 6; ++pose) {
    b.Still(PoseMean(pose), bias, 4.0);
    if (pose == 2) {  // then turn at -30 deg/s about body z for 6 s in the same orientation
      b.Swing(PoseMean(pose), 0.5);
      b.Still(PoseMean(pose), bias + Eigen::Vector3d(0, 0, -30), 6.0);
    }
    b.Swing(PoseMean(pose), 1.0);
  }
  for (double units : {1.0, 0.0}) {
    INFO("gyro_units_per_dps " << units);
    SegmentationOptions o;
    o.gyro_units_per_dps = units;
    const SegmentationSummary s = b.Detect(o);
    CHECK(s.static_count == 6);
    CHECK(s.pose_count == 6);
    REQUIRE(s.steady_count == 1);
    for (const Segment& seg : s.segments) {
      if (seg.kind != SegmentKind::kSteady) continue;
      CHECK_FALSE(seg.used);
      CHECK(seg.steady_rate == Approx(30.0).margin(0.05));
      // Pose 3 is still from 10 to 14 s, then swings for 0.5 s and turns from 14.5 to 20.5 s.
      CHECK(seg.start_s >= 14.5 - 1e-9);
      CHECK(seg.end_s <= 20.5 + 1e-9);
      if (units > 0) CHECK(seg.steady_rate_dps == Approx(30.0).margin(0.05));
      CHECK(seg.note.find("steady rotation") != std::string::npos);
    }
  }
}

// A 0.2 s knock in the middle of a 6 s pose: the two still periods are one pose but two static
// segments, and the knock's samples are in neither.
TEST_CASE("A knock inside a pose is cut out and named", "[calibration]") {
  Builder b;
  for (int pose = 0; pose < 6; ++pose) {
    if (pose == 3) {
      b.Still(PoseMean(pose), Eigen::Vector3d::Zero(), 3.0);
      const double knock_start = b.now;
      for (int k = 0; k < 20; ++k, b.now += 0.01) {  // 0.2 s, 0.5 g spikes
        b.t.push_back(b.now);
        b.accel.push_back(PoseMean(pose) + Eigen::Vector3d(0.5, -0.5, 0.5) * ((k % 2) ? 1 : -1));
        b.gyro.push_back(Eigen::Vector3d(5, -5, 5) * ((k % 2) ? 1 : -1));
      }
      b.Still(PoseMean(pose), Eigen::Vector3d::Zero(), 3.0);
      INFO("knock at " << knock_start);
    } else {
      b.Still(PoseMean(pose), Eigen::Vector3d::Zero(), 4.0);
    }
    b.Swing(PoseMean(pose), 1.0);
  }
  const SegmentationSummary s = b.Detect(SegmentationOptions());
  CHECK(s.pose_count == 6);
  CHECK(s.static_count == 7);
  CHECK(s.disturbed_poses == 1);
  const double knock_begin = 3 * 5.0 + 3.0, knock_end = knock_begin + 0.2;
  int parts = 0;
  bool named = false;
  for (const Segment& seg : s.segments) {
    if (seg.kind == SegmentKind::kStatic && seg.pose == 3) {
      ++parts;
      CHECK((seg.end_s < knock_begin || seg.start_s >= knock_end));
    }
    if (seg.kind == SegmentKind::kRotation && seg.note.find("disturbance inside pose 4") == 0) {
      named = true;
      CHECK(seg.start_s < knock_begin);
      CHECK(seg.end_s >= knock_end - 0.01);
    }
  }
  CHECK(parts == 2);
  CHECK(named);
}

// Poses of 1 s among poses of 4 s: with the 1 s window they leave no still period of 1 s; they
// are counted with their dwell, and the suggested min_static_s finds them.
TEST_CASE("Short poses are counted with the min_static_s that accepts them", "[calibration]") {
  Builder b;
  for (int pose = 0; pose < 9; ++pose) {
    b.Still(PoseMean(pose), Eigen::Vector3d::Zero(), pose < 6 ? 4.0 : 1.0);
    b.Swing(PoseMean(pose), 1.0);
  }
  const SegmentationSummary s = b.Detect(SegmentationOptions());
  CHECK(s.pose_count == 6);
  CHECK(s.short_static_count == 3);
  CHECK(s.short_static_min_s > 0.7);
  CHECK(s.short_static_max_s < 1.05);
  REQUIRE(s.suggested_min_static_s > 0.0);
  CHECK(s.suggested_min_static_s <= 0.5);
  SegmentationOptions shorter;
  shorter.min_static_s = s.suggested_min_static_s;
  const SegmentationSummary t = b.Detect(shorter);
  CHECK(t.pose_count == 9);
  CHECK(t.short_static_count == 0);
}

std::string WriteTemp(const std::string& name, const std::string& text) {
  const std::string path = std::string(METRO_BINARY_DIR) + "/" + name;
  std::FILE* f = std::fopen(path.c_str(), "wb");
  REQUIRE(f != nullptr);
  std::fwrite(text.data(), 1, text.size(), f);
  std::fclose(f);
  return path;
}

TEST_CASE("Annotated segments replace the detector", "[calibration]") {
  Builder b;
  for (int pose = 0; pose < 3; ++pose) {
    b.Still(PoseMean(pose), Eigen::Vector3d::Zero(), 4.0);
    b.Swing(PoseMean(pose), 1.0);
  }
  const std::string path = WriteTemp("segments_ok.csv",
                                     "# poses of the three-pose record\n"
                                     "kind,start_s,end_s\n"
                                     "static,0.5,3.5\n"
                                     "static,5.5,8.5\n"
                                     "static,10.5,13.5\n");
  Result<std::vector<AnnotatedSegment>> a = ReadSegmentsFile(path);
  REQUIRE(a.ok());
  REQUIRE(a.value().size() == 3);
  SegmentationInput in;
  in.t_s = &b.t;
  in.accel = &b.accel;
  in.gyro = &b.gyro;
  Result<SegmentationSummary> s = SegmentsFromAnnotations(in, a.value(), path);
  REQUIRE(s.ok());
  CHECK(s.value().static_count == 3);
  CHECK(s.value().pose_count == 3);
  CHECK(s.value().rotation_count == 2);  // between the statics, as the detector makes them
  const Segment& first = s.value().segments.front();
  CHECK(first.kind == SegmentKind::kStatic);
  // Samples 50 .. 350 (t = 0.50 .. 3.50 s inclusive), at 100 Hz from t = 0.
  CHECK(first.begin == 50);
  CHECK(first.end == 351);
  // An annotation outside the record names its line.
  const std::string late = WriteTemp("segments_late.csv", "kind,start_s,end_s\nstatic,90,95\n");
  Result<SegmentationSummary> bad =
      SegmentsFromAnnotations(in, ReadSegmentsFile(late).value(), late);
  REQUIRE_FALSE(bad.ok());
  CHECK(bad.error().line == 2);
  CHECK(bad.error().message.find("expected at least 2") != std::string::npos);
}

TEST_CASE("A segments file with a bad field names line and column", "[calibration]") {
  struct Case {
    const char* text;
    int line, column;
    const char* words;
  };
  const Case cases[] = {
      {"kind,start_s,end_s\nstatic,1,x\n", 2, 3, "end_s 'x' is not a number"},
      {"kind,start_s,end_s\npose,1,2\n", 2, 1, "expected static, rotation or table"},
      {"kind,start_s,end_s\ntable,1,2\n", 2, 1, "needs a non-zero table_rate_dps"},
      {"kind,begin,end_s\n", 1, 2, "unknown column 'begin'"},
      {"kind,start_s,end_s\nstatic,2,1\n", 2, 3, "is not after start_s"},
      {"kind,start_s,end_s,input\nstatic,1,2,0\n", 2, 4, "1-based index"},
  };
  for (const Case& c : cases) {
    INFO(c.text);
    const std::string path = WriteTemp("segments_bad.csv", c.text);
    Result<std::vector<AnnotatedSegment>> r = ReadSegmentsFile(path);
    REQUIRE_FALSE(r.ok());
    CHECK(r.error().line == c.line);
    CHECK(r.error().column == c.column);
    CHECK(r.error().message.find(c.words) != std::string::npos);
  }
}

}  // namespace
}  // namespace metro
