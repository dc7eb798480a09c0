// Aligning a separate reference log on t_s.
#include "metro/accuracy/alignment.hpp"

#include <catch2/catch.hpp>
#include <cmath>

#include "metro/core/angles.hpp"

namespace metro {
namespace {

// A table stepping by 30 deg every 10 s at 20 deg/s, as a function of true time.
double Table(double t) {
  const double cycle = 10.0, move = 1.5;
  const int k = static_cast<int>(std::floor(t / cycle));
  const double into = t - k * cycle;
  const double base = 30.0 * k;
  return into < move ? base + 20.0 * into : base + 30.0;
}

struct Logs {
  std::vector<double> tag_t, tag_a, ref_t, ref_a;
};
// Tag at 10 Hz reading the table angle wrapped to (-180, 180]; reference at 20 Hz on a clock
// `offset` s ahead.
Logs Make(double offset, double ref_start) {
  Logs l;
  for (int i = 0; i < 1200; ++i) {
    const double t = 0.1 * i;
    l.tag_t.push_back(t);
    l.tag_a.push_back(WrapDeg180(Table(t) + 0.2));
  }
  for (int i = 0; i < 2600; ++i) {
    const double t = ref_start + 0.05 * i;
    l.ref_t.push_back(t + offset);
    l.ref_a.push_back(Table(t));
  }
  return l;
}

TEST_CASE("Reference clock offset is estimated from the motion", "[accuracy]") {
  const Logs l = Make(1.234, -5.0);
  auto a = AlignReference(l.tag_t, l.tag_a, l.ref_t, l.ref_a);
  REQUIRE(a.ok());
  CHECK(a.value().estimated);
  CHECK(a.value().offset_s == Approx(1.234).margin(0.01));
  // Aligned, the residual is the constant 0.2 deg error: its std is ~0.
  CHECK(a.value().residual_std_deg < 0.05);
  CHECK(a.value().residual_std_at_zero_deg > 1.0);
  CHECK(a.value().overlap_samples == 1200);
  // Wrap-safe: 210 deg on the table against -149.8 on the tag is an error of 0.2.
  const size_t k = 750;  // t = 75 s: the table rests at 7 * 30 + 30 = 240 deg
  CHECK(WrapDeg180(l.tag_a[k] - a.value().reference_deg[k]) == Approx(0.2).margin(1e-3));
}

TEST_CASE("A given offset is used as is", "[accuracy]") {
  const Logs l = Make(0.5, -5.0);
  AlignmentOptions o;
  o.offset_s = 0.5;
  auto a = AlignReference(l.tag_t, l.tag_a, l.ref_t, l.ref_a, o);
  REQUIRE(a.ok());
  CHECK_FALSE(a.value().estimated);
  CHECK(a.value().offset_s == 0.5);
  CHECK(a.value().residual_std_deg == Approx(0.0).margin(1e-9));
  CHECK(a.value().method.find("given offset") != std::string::npos);
}

TEST_CASE("Reference logs that do not overlap or cannot be aligned are errors", "[accuracy]") {
  const Logs far = Make(0.0, 1000.0);
  auto a = AlignReference(far.tag_t, far.tag_a, far.ref_t, far.ref_a);
  REQUIRE(!a.ok());
  CHECK(a.error().message ==
        "the reference log (t_s 1000 .. 1129.95 s) does not overlap the tag log (t_s 0 .. 119.9 "
        "s) within +-5 s: record the reference during the same sweep on the same clock, or give "
        "the clock offset with --reference-offset-s");
  const Logs late = Make(1.234, -5.0);  // Best offset beyond a +-1 s search.
  AlignmentOptions narrow;
  narrow.max_offset_s = 1.0;
  auto edge = AlignReference(late.tag_t, late.tag_a, late.ref_t, late.ref_a, narrow);
  REQUIRE(!edge.ok());
  CHECK(edge.error().message.find("at the edge of the searched range") != std::string::npos);
  std::vector<double> one = {0.0};
  auto tiny = AlignReference(far.tag_t, far.tag_a, one, one);
  REQUIRE(!tiny.ok());
  CHECK(tiny.error().message == "the reference log has fewer than 2 samples");
}

}  // namespace
}  // namespace metro
