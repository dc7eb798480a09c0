// Segmentation of the reference into dwell plateaus.
#include "metro/accuracy/plateaus.hpp"

#include <catch2/catch.hpp>
#include <cmath>
#include <limits>

#include "metro/core/angles.hpp"

namespace metro {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// 10 Hz: rest at 0 for 10 s, a 2 s ramp to 10 deg, rest for 10 s, a short 1 s rest at 20,
// 1 s of unknown reference, rest at 30 for 10 s.
struct Series {
  std::vector<double> t, ref, err;
};
Series Steps() {
  Series s;
  auto add = [&](double ref) {
    s.t.push_back(static_cast<double>(s.t.size()) * 0.1);
    s.ref.push_back(ref);
    s.err.push_back(0.0);
  };
  for (int i = 0; i < 100; ++i) add(0.0);
  for (int i = 1; i <= 20; ++i) add(0.5 * i);
  for (int i = 0; i < 100; ++i) add(10.0);
  for (int i = 1; i <= 10; ++i) add(10.0 + i);
  for (int i = 0; i < 10; ++i) add(20.0);
  for (int i = 0; i < 10; ++i) add(kNaN);
  for (int i = 0; i < 100; ++i) add(30.0);
  return s;
}

TEST_CASE("Plateaus are found and motion is excluded with its reason", "[accuracy]") {
  const Series s = Steps();
  PlateauOptions o;
  o.settle_s = 0.0;
  auto seg = FindPlateaus(s.t, s.ref, s.err, o);
  REQUIRE(seg.ok());
  const Segmentation& g = seg.value();
  REQUIRE(g.plateaus.size() == 3);
  CHECK(g.plateaus[0].reference_deg == 0.0);
  CHECK(g.plateaus[0].n() == 100);
  // The ramp's last sample (10 deg) starts the second rest.
  CHECK(g.plateaus[1].reference_deg == 10.0);
  CHECK(g.plateaus[1].n() == 101);
  CHECK(g.plateaus[2].reference_deg == 30.0);
  // The ramp's first 19 samples move; 11..19 deg are 9 more; 20 deg rests 1.1 s (11 samples).
  size_t motion = 0, short_rest = 0, unknown = 0;
  for (const ExcludedSpan& e : g.excluded) {
    if (e.reason == "motion") motion += e.end - e.begin;
    if (e.reason == "rest shorter than min_dwell_s") short_rest += e.end - e.begin;
    if (e.reason == "reference unknown") unknown += e.end - e.begin;
  }
  CHECK(motion == 19 + 9);
  CHECK(short_rest == 11);
  CHECK(unknown == 10);
  CHECK(g.motion_samples == 49);
}

TEST_CASE("Plateau settling drops the first settle_s seconds", "[accuracy]") {
  const Series s = Steps();
  PlateauOptions o;  // Default: 2 s dropped, no MSER-5.
  auto seg = FindPlateaus(s.t, s.ref, s.err, o);
  REQUIRE(seg.ok());
  CHECK(seg.value().plateaus[0].settle_samples == 20);
  CHECK(seg.value().plateaus[0].t_start_s == Approx(2.0));
  CHECK(seg.value().settle_samples == 60);  // 20 per plateau
}

TEST_CASE("A plateau at the wrap averages 359.999 and 0.001 to 0", "[accuracy]") {
  std::vector<double> t, ref, err;
  for (int i = 0; i < 100; ++i) {
    t.push_back(0.1 * i);
    ref.push_back(i % 2 == 0 ? 359.999 : 0.001);
    err.push_back(0.0);
  }
  auto seg = FindPlateaus(t, ref, err);
  REQUIRE(seg.ok());
  REQUIRE(seg.value().plateaus.size() == 1);
  CHECK(WrapDeg180(seg.value().plateaus[0].reference_deg) == Approx(0.0).margin(1e-9));
}

TEST_CASE("MSER-5 settling removes a decaying transient", "[accuracy]") {
  // One 30 s plateau at 10 Hz: error 0.5 exp(-t / 2 s) plus alternating +-0.01 noise.
  std::vector<double> t, ref, err;
  for (int i = 0; i < 300; ++i) {
    t.push_back(0.1 * i);
    ref.push_back(45.0);
    err.push_back(0.5 * std::exp(-0.1 * i / 2.0) + (i % 2 == 0 ? 0.01 : -0.01));
  }
  PlateauOptions o;
  o.settle_s = 0.0;
  o.settle_auto = true;
  auto seg = FindPlateaus(t, ref, err, o);
  REQUIRE(seg.ok());
  const Plateau& p = seg.value().plateaus.at(0);
  // The transient is below the noise (0.01) after 2 ln(50) = 7.8 s; MSER-5 cuts near there.
  CHECK(p.t_start_s > 5.0);
  CHECK(p.t_start_s < 15.0);
  CHECK_FALSE(p.settle_at_limit);
}

TEST_CASE("A departing end is trimmed and listed and a drift is kept", "[accuracy]") {
  // Two 20 s plateaus at 10 Hz, error +-0.02 alternating about 0.3 deg. On the first the tag
  // starts to move 0.3 s before the reference does (errors 0.3 + 0.1, 0.4, 0.9 at its last
  // three observations); on the second the error steps up by 0.5 deg for its last 30 %.
  std::vector<double> t, ref, err;
  for (int i = 0; i < 200; ++i) {
    t.push_back(0.1 * static_cast<double>(t.size()));
    ref.push_back(0.0);
    const double move = i == 197 ? 0.1 : i == 198 ? 0.4 : i == 199 ? 0.9 : 0.0;
    err.push_back(0.3 + (i % 2 == 0 ? 0.02 : -0.02) + move);
  }
  for (int i = 1; i <= 10; ++i) {
    t.push_back(0.1 * static_cast<double>(t.size()));
    ref.push_back(3.0 * i);
    err.push_back(0.3);
  }
  for (int i = 0; i < 200; ++i) {
    t.push_back(0.1 * static_cast<double>(t.size()));
    ref.push_back(30.0);
    err.push_back(0.3 + (i >= 140 ? 0.5 : 0.0) + (i % 2 == 0 ? 0.02 : -0.02));
  }
  PlateauOptions o;
  o.settle_s = 0.0;
  auto seg = FindPlateaus(t, ref, err, o);
  REQUIRE(seg.ok());
  const Segmentation& g = seg.value();
  REQUIRE(g.plateaus.size() == 2);
  // The median is 0.32 (one of the two levels), the MAD 0.04, the limit 5 x 1.4826 x 0.04 =
  // 0.30 deg: the last two depart, and one more observation (0.1 above its level) goes too.
  CHECK(g.plateaus[0].end_trimmed == 3);
  CHECK(g.plateaus[0].n() == 197);
  CHECK(g.plateaus[0].rest_end == 200);
  CHECK(g.plateaus[0].start_trimmed == 0);
  CHECK(g.plateaus[0].t_end_s == Approx(19.6));
  CHECK(g.departure_trimmed_plateaus == 1);
  CHECK(g.departure_trimmed_samples == 3);
  CHECK(g.max_end_trimmed_s == Approx(0.4));  // From 19.6 s to the first moving sample at 20 s.
  bool listed = false;
  for (const ExcludedSpan& e : g.excluded) {
    if (e.reason == "tag moving at the plateau's end") {
      listed = true;
      CHECK(e.end - e.begin == 3);
    }
  }
  CHECK(listed);
  // The step departs for longer than a quarter of the plateau: drift, kept and counted.
  CHECK(g.plateaus[1].n() == 201);  // The ramp's last sample (30 deg) starts the rest.
  CHECK(g.plateaus[1].end_trimmed == 0);
  CHECK(g.plateaus[1].departure_kept);
  CHECK(g.departure_kept_plateaus == 1);
  // Off: nothing trimmed.
  o.trim_departures = false;
  auto kept = FindPlateaus(t, ref, err, o);
  REQUIRE(kept.ok());
  CHECK(kept.value().plateaus[0].n() == 200);
}

TEST_CASE("No plateau is an error naming what to collect", "[accuracy]") {
  std::vector<double> t, ref, err;
  for (int i = 0; i < 300; ++i) {  // A table turning at 10 deg/s throughout.
    t.push_back(0.1 * i);
    ref.push_back(1.0 * i);
    err.push_back(0.0);
  }
  auto seg = FindPlateaus(t, ref, err);
  REQUIRE(!seg.ok());
  CHECK(seg.error().message ==
        "no plateau found: the reference never stayed within 0.005 deg for 3 s with 10 "
        "observations left after settling (300 observations examined); collect a sweep that "
        "dwells at each table angle (e.g. 20 s per step) or lower --min-dwell-s");
  PlateauOptions bad;
  bad.min_dwell_s = 0.0;
  auto invalid = FindPlateaus(t, ref, err, bad);
  REQUIRE(!invalid.ok());
  CHECK(invalid.error().message == "plateau min_dwell_s must be > 0");
  ref.pop_back();
  auto mismatch = FindPlateaus(t, ref, err);
  REQUIRE(!mismatch.ok());
  CHECK(mismatch.error().message ==
        "plateaus: the time, reference and error series differ in length");
}

}  // namespace
}  // namespace metro
