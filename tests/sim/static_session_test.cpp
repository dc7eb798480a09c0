#include "metro/sim/static_session.hpp"

#include <catch2/catch.hpp>
#include <cmath>

#include "metro/io/session_io.hpp"
#include "metro/sim/table_session.hpp"
#include "metro/stats/session_type_a.hpp"
#include "support/temp_file.hpp"

namespace metro {
namespace {

using testing::TempFile;

std::string Simulate(const StaticSimulationOptions& o, SessionFormat format,
                     std::vector<StaticTagTruth>* truth) {
  std::string text;
  REQUIRE(SimulateStaticSession(
              o, format,
              [&](std::string_view chunk) {
                text.append(chunk);
                return Status::Ok();
              },
              truth)
              .ok());
  return text;
}

TEST_CASE("Simulated static tag: Type A recovers the true attitude", "[sim]") {
  // No drift, settled transient: the mean pitch/roll must lie within ~3 u of the truth,
  // where u is the autocorrelation-aware standard uncertainty of the mean. With the
  // classical s/sqrt(n) the same check fails often (it is ~4x too small for phi = 0.9).
  StaticSimulationOptions o;
  o.yaw_drift_dps = 0.0;
  o.duration_s = 2000.0;
  o.sensors = {1, 2, 3};
  int within = 0, total = 0;
  for (uint64_t seed = 1; seed <= 8; ++seed) {
    o.seed = seed;
    std::vector<StaticTagTruth> truth;
    TempFile file(Simulate(o, SessionFormat::kCsv, &truth));
    auto session = LoadSession(file.path());
    REQUIRE(session.ok());
    SessionTypeAOptions options;
    options.window.skip_seconds = 100.0;  // 12 time constants of the transient.
    auto r = EvaluateSessionTypeA(session.value(), options);
    REQUIRE(r.ok());
    for (size_t k = 0; k < truth.size(); ++k) {
      for (const QuantityTypeA& q : r.value().tags[k].quantities) {
        double expected;
        if (q.name == "pitch_deg") {
          expected = truth[k].attitude.pitch_deg;
        } else if (q.name == "roll_deg") {
          expected = truth[k].attitude.roll_deg;
        } else {
          continue;
        }
        ++total;
        within += std::abs(q.type_a.mean - expected) < 3.0 * q.type_a.std_of_mean_autocorr;
      }
    }
  }
  // 48 checks at ~99.7 % each: allow 2 misses (binomial tail and the slight
  // underestimate of F by the truncated sum).
  CHECK(total == 48);
  CHECK(within >= 46);
}

TEST_CASE("Simulated receiver capture and session.csv share one truth", "[sim]") {
  StaticSimulationOptions o;
  o.duration_s = 60.0;
  o.sensors = {1, 2};
  o.never_sensors = {3};
  o.packet_loss = 0.1;
  std::vector<StaticTagTruth> t1, t2;
  TempFile csv(Simulate(o, SessionFormat::kCsv, &t1));
  TempFile rx(Simulate(o, SessionFormat::kReceiver, &t2), ".txt");
  auto a = LoadSession(csv.path());
  auto b = LoadSession(rx.path());
  REQUIRE(a.ok());
  REQUIRE(b.ok());
  REQUIRE(b.value().tags.size() == 3);
  CHECK(b.value().tags[2].counts.never == b.value().tags[2].counts.frames);
  for (size_t k = 0; k < 2; ++k) {
    const Tag& ta = a.value().tags[k];
    const Tag& tb = b.value().tags[k];
    // Same packets lost: the csv rows are exactly the receiver's fresh rows.
    REQUIRE(ta.size() == tb.size());
    CHECK(tb.counts.fresh + tb.counts.stale + tb.counts.never == tb.counts.frames);
    // Loss probability 0.1 over 599 frames: 59.9 +- 7.3 expected, allow 5 sigma.
    CHECK(std::abs(static_cast<double>(tb.counts.stale + tb.counts.never) - 59.9) < 37.0);
    for (size_t i = 0; i < ta.size(); i += 37) {
      CHECK(ta.t_s[i] == Approx(tb.t_s[i]).margin(1e-6));
      // csv prints 8 decimals of the quaternion, the receiver sends binary32.
      CHECK(ta.Find("pitch_deg")->values[i] ==
            Approx(tb.Find("pitch_deg")->values[i]).margin(2e-4));
    }
  }
}

TEST_CASE("Simulator options are validated", "[sim]") {
  StaticSimulationOptions o;
  o.sensors = {2, 2};
  std::string why;
  CHECK_FALSE(o.IsValid(&why));
  CHECK(why == "sensor 2 is listed twice");
  o.sensors = {1};
  o.packet_loss = 1.0;
  CHECK_FALSE(o.IsValid(&why));
  CHECK(why == "packet_loss must be in [0, 1)");
}

TEST_CASE("Simulator options beyond their limits are refused", "[sim]") {
  // issue #20: --duration-s 1e12 wrote without limit; --table-step-deg 1e-9 crashed.
  std::string why;
  StaticSimulationOptions o;
  o.duration_s = 1e12;
  CHECK_FALSE(o.IsValid(&why));
  CHECK(why == "duration_s must be in (0, 1e+06] s, got 1e+12");
  o.duration_s = 1e6;
  o.rate_hz = 1000.0;
  o.sensors = {1, 2};  // 2e9 observations.
  CHECK_FALSE(o.IsValid(&why));
  CHECK(why.rfind("2e+09 observations (duration x rate x tags) is more than the simulator "
                  "writes (1e+09)",
                  0) == 0);
  o.sensors = {1};  // 1e9: at the limit.
  CHECK(o.IsValid(&why));
  o.rate_hz = 2e4;
  CHECK_FALSE(o.IsValid(&why));
  CHECK(why.rfind("rate_hz must be in [0, 10000] Hz", 0) == 0);

  TableSimulationOptions t;
  REQUIRE(t.IsValid(&why));
  t.step_deg = 1e-9;
  CHECK_FALSE(t.IsValid(&why));
  CHECK(why == "step_deg must be at least 0.001 deg, got 1e-09");
  t.start_deg = -180.0;
  t.end_deg = 180.0;
  t.step_deg = 0.01;  // 36,001 plateaus.
  CHECK_FALSE(t.IsValid(&why));
  CHECK(why.rfind("36001 plateaus per sweep", 0) == 0);
  t.step_deg = 0.05;  // About 7,200 plateaus of 20 s, 2 sweeps up and down: 576,000 s or more.
  CHECK(t.IsValid(&why));
  t.dwell_s = 100.0;  // 2 x 2 x (7201 x 100 + 360 / 20) = 2.88 M s.
  CHECK_FALSE(t.IsValid(&why));
  CHECK(why.rfind("the sweeps last 2.88e+06 s, more than 1e+06 s", 0) == 0);

  // The loader's receiver frame period (convert --frame-period-s 1e307 wrote t_s = inf).
  LoadOptions load;
  load.frame_period_s = 1e307;
  CHECK_FALSE(load.IsValid(&why));
  CHECK(why == "frame_period_s must be in (0, 60] s, got 1e+307");
}

}  // namespace
}  // namespace metro
