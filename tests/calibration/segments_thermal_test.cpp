// Issue #36 (6): a temperature ramp during a calibration session moves the gyroscope bias by
// several deg/s; the steady-rotation test of the segmenter (segments.hpp) must follow it in
// temperature, so that no static stop is taken for a turn, while turns about the vertical (the
// only turns that keep the accelerometer still) are still found. Simulated tags with known
// truth (simulate.hpp): the truth says which samples are still (true rate 0) and which turn.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "metro/calibration/segments.hpp"
#include "metro/sim/calibration_session.hpp"

namespace metro {
namespace {

struct ThermalCase {
  std::vector<double> run_rates_dps = {90.0};  // Table runs at every pose.
  bool table_column = true;  // False: the runs' rate is not given (steady rotations).
  bool give_temperature = true;
  double temp_start_c = 15.0;
  double temp_end_c = 45.0;
  // > 0: every gyroscope axis gets this |b1| [deg/s/degC] with a random sign (the simulator
  // draws uniform in +-0.16); 0: the simulator's draw.
  double gyro_per_c_dps = 0;
  double move_s = 2.0;
};

// What the detector did against the truth, summed over tags.
struct ThermalTally {
  int tags = 0;
  int true_stops = 0;      // Still stretches of the truth (rate 0 for >= 2 s).
  int dropped = 0;         // True stops no static segment lies in.
  int true_turns = 0;      // Table runs of the truth (constant rate for >= 2 s).
  int turns_missed = 0;    // True turns not found as table or steady rotation.
  int static_turning = 0;  // Static segments whose mean true rate is above 0.5 deg/s.
  std::vector<int> dropped_per_tag;
  int max_abs_per_c_error_mdps = 0;  // max |fitted b1 - true b1| [mdeg/s/degC].
};

ThermalTally RunThermalCase(const ThermalCase& c, uint64_t first_seed, int tags) {
  ThermalTally tally;
  for (int i = 0; i < tags; ++i) {
    SimulationOptions o;
    o.seed = first_seed + static_cast<uint64_t>(i);
    o.table_rates_dps = c.run_rates_dps;
    o.temperature = true;
    o.temp_start_c = c.temp_start_c;
    o.temp_end_c = c.temp_end_c;
    o.move_s = c.move_s;
    if (c.gyro_per_c_dps > 0) {
      o.random_truth = false;
      o.truth = DrawImuTruth(o.seed, o.accel_fs_g, o.gyro_fs_dps, true);
      std::mt19937 signs(static_cast<unsigned>(o.seed));
      for (int a = 0; a < 3; ++a) {
        const double sign = (signs() & 1u) ? 1.0 : -1.0;
        o.truth.gyro.bias_per_c[a] = sign * c.gyro_per_c_dps / o.truth.gyro.scale[a];
      }
    }
    const SimulatedSession sim = SimulateCalibrationSession(o).value();
    const Tag& tag = sim.session.tags.front();
    const size_t n = tag.size();
    std::vector<Eigen::Vector3d> accel(n), gyro(n);
    for (size_t k = 0; k < n; ++k) {
      for (int a = 0; a < 3; ++a) {
        accel[k][a] = tag.quantities[static_cast<size_t>(a)].values[k];
        gyro[k][a] = tag.quantities[static_cast<size_t>(3 + a)].values[k];
      }
    }
    REQUIRE(tag.quantities[6].name == "temp_c");
    REQUIRE(tag.quantities[7].name == "table_rate_dps");
    SegmentationInput in;
    in.t_s = &tag.t_s;
    in.accel = &accel;
    in.gyro = &gyro;
    if (c.give_temperature) in.temp_c = &tag.quantities[6].values;
    if (c.table_column) in.table_rate_dps = &tag.quantities[7].values;
    SegmentationOptions so;
    so.gyro_units_per_dps = 131.0;  // +-250 deg/s, as calibrate fit converts raw counts.
    const SegmentationSummary s = DetectSegments(in, so);

    // The truth: stretches of >= 2 s at rate 0 (stops) or at a constant non-zero rate (turns).
    const size_t min_n = static_cast<size_t>(2.0 * o.rate_hz);
    std::vector<std::pair<size_t, size_t>> stops, turns;
    size_t k = 1;
    while (k < n) {
      const double w = sim.true_gyro_dps[k].norm();
      size_t e = k + 1;
      while (e < n && std::abs(sim.true_gyro_dps[e].norm() - w) < 1e-3) ++e;
      if (e - k >= min_n) (w < 1e-3 ? stops : turns).push_back({k, e});
      k = e;
    }
    // Most of the segment in the stretch (a segment may take a sample of the slow end of a
    // minimum-jerk turn).
    auto inside = [](const Segment& seg, const std::pair<size_t, size_t>& r) {
      const size_t lo = std::max(seg.begin, r.first), hi = std::min(seg.end, r.second);
      return hi > lo && 2 * (hi - lo) > seg.end - seg.begin;
    };
    int dropped = 0;
    for (const auto& stop : stops) {
      bool found = false;
      for (const Segment& seg : s.segments) {
        if (seg.kind == SegmentKind::kStatic && inside(seg, stop)) found = true;
      }
      if (!found) ++dropped;
    }
    for (const auto& turn : turns) {
      bool found = false;
      for (const Segment& seg : s.segments) {
        if ((seg.kind == SegmentKind::kSteady || seg.kind == SegmentKind::kTable) &&
            inside(seg, turn)) {
          found = true;
        }
      }
      if (!found) ++tally.turns_missed;
    }
    for (const Segment& seg : s.segments) {
      if (seg.kind != SegmentKind::kStatic) continue;
      double sum = 0;
      for (size_t j = seg.begin; j < seg.end; ++j) sum += sim.true_gyro_dps[j].norm();
      if (sum / static_cast<double>(seg.end - seg.begin) > 0.5) ++tally.static_turning;
    }
    if (s.gyro_bias_temperature) {
      for (int a = 0; a < 3; ++a) {
        const double err_dps =
            std::abs(s.gyro_bias_per_c[a] - sim.truth.gyro.bias_per_c[a]) * sim.truth.gyro.scale[a];
        tally.max_abs_per_c_error_mdps =
            std::max(tally.max_abs_per_c_error_mdps, static_cast<int>(std::ceil(err_dps * 1e3)));
      }
    }
    ++tally.tags;
    tally.true_stops += static_cast<int>(stops.size());
    tally.true_turns += static_cast<int>(turns.size());
    tally.dropped += dropped;
    tally.dropped_per_tag.push_back(dropped);
  }
  return tally;
}

double MedianOf(std::vector<int> v) {
  std::sort(v.begin(), v.end());
  const size_t m = v.size() / 2;
  return v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
}

std::string Describe(const char* name, const ThermalTally& t) {
  const int max_dropped = *std::max_element(t.dropped_per_tag.begin(), t.dropped_per_tag.end());
  const int tags_dropping = static_cast<int>(std::count_if(
      t.dropped_per_tag.begin(), t.dropped_per_tag.end(), [](int d) { return d > 0; }));
  char line[400];
  std::snprintf(line, sizeof line,
                "%s: %d tags, %d true stops, %d dropped (median %.1f per tag, max %d, %d tags "
                "dropping); %d true turns, %d missed; %d static segments turning; max |b1 "
                "error| %d mdps/degC",
                name, t.tags, t.true_stops, t.dropped, MedianOf(t.dropped_per_tag), max_dropped,
                tags_dropping, t.true_turns, t.turns_missed, t.static_turning,
                t.max_abs_per_c_error_mdps);
  return line;
}

// The default calibration session (26 poses, a 90 deg/s table run at each with its rate in
// table_rate_dps) ramped 15 -> 45 degC with the simulator's gyroscope temperature
// coefficients (uniform in +-0.16 deg/s/degC): without the temperature the median bias of the
// still periods is that of the middle of the ramp, and the stops near either end of it lie
// more than 2 deg/s from it.
TEST_CASE("A thermal ramp drops no static stop", "[calibration][segments]") {
  ThermalCase c;
  const ThermalTally with = RunThermalCase(c, 3601, 12);
  INFO(Describe("with temp_c", with));
  CHECK(with.true_stops == 12 * 52);
  CHECK(with.dropped == 0);
  CHECK(with.static_turning == 0);
  CHECK(with.turns_missed == 0);
  // The fitted b1 against the truth: the means of 3 s stops over a 30 degC span give it to a few
  // mdeg/s/degC.
  CHECK(with.max_abs_per_c_error_mdps <= 5);
  c.give_temperature = false;
  const ThermalTally without = RunThermalCase(c, 3601, 12);
  INFO(Describe("without temp_c", without));
  CHECK(without.dropped > 0);  // What the temperature fit repairs.
}

// The upper end: every axis at 0.16 deg/s/degC (4.8 deg/s over the ramp, 8.3 deg/s as a
// norm), and beyond it at 0.3 deg/s/degC.
TEST_CASE("A thermal ramp at the largest coefficients drops no static stop",
          "[calibration][segments]") {
  for (double per_c : {0.16, 0.3}) {
    ThermalCase c;
    c.gyro_per_c_dps = per_c;
    const ThermalTally t = RunThermalCase(c, 3701, 8);
    INFO(Describe(per_c == 0.16 ? "0.16 deg/s/degC" : "0.3 deg/s/degC", t));
    CHECK(t.dropped == 0);
    CHECK(t.static_turning == 0);
    CHECK(t.turns_missed == 0);
    CHECK(t.max_abs_per_c_error_mdps <= 5);
  }
}

// Turns about the vertical whose rate the record does not give (no table_rate_dps): the 90
// deg/s runs and slow 3 deg/s turns (as slow as the thermal bias shift) are steady rotations,
// never static, and the stops between them are all kept. Slow hand rotations (10 s for each
// turn between poses) move the accelerometer and are never static either.
TEST_CASE("Under a thermal ramp turns about the vertical stay steady rotations",
          "[calibration][segments]") {
  ThermalCase c;
  c.table_column = false;
  c.run_rates_dps = {90.0, -3.0};
  c.gyro_per_c_dps = 0.16;
  c.move_s = 10.0;
  const ThermalTally t = RunThermalCase(c, 3801, 8);
  INFO(Describe("no table column", t));
  CHECK(t.true_turns == 8 * 26 * 2);
  CHECK(t.turns_missed == 0);
  CHECK(t.dropped == 0);
  CHECK(t.static_turning == 0);
}

// The counts docs/calibration-model.md states: 200 tags per case.
TEST_CASE("Thermal-ramp segmentation counts over 200 tags", "[.][coverage][calibration]") {
  struct Named {
    const char* name;
    ThermalCase c;
  };
  std::vector<Named> cases(5);
  cases[0].name = "simulator b1, table column, with temp_c";
  cases[1].name = "simulator b1, table column, without temp_c";
  cases[1].c.give_temperature = false;
  cases[2].name = "b1 0.16 deg/s/degC, with temp_c";
  cases[2].c.gyro_per_c_dps = 0.16;
  cases[3].name = "b1 0.3 deg/s/degC, with temp_c";
  cases[3].c.gyro_per_c_dps = 0.3;
  cases[4].name = "b1 0.16, runs 90 and -3 deg/s, no table column, 10 s moves, with temp_c";
  cases[4].c.gyro_per_c_dps = 0.16;
  cases[4].c.table_column = false;
  cases[4].c.run_rates_dps = {90.0, -3.0};
  cases[4].c.move_s = 10.0;
  for (const Named& n : cases) {
    const ThermalTally t = RunThermalCase(n.c, 5001, 200);
    std::printf("%s\n", Describe(n.name, t).c_str());
    if (n.c.give_temperature) {
      CHECK(t.dropped == 0);
      CHECK(t.turns_missed == 0);
      CHECK(t.static_turning == 0);
    }
  }
}

}  // namespace
}  // namespace metro
