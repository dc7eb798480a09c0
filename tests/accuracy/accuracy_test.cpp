// Accuracy against a rotation table: recovery of simulated truth (offset, scale, mounting
// harmonics, hysteresis, tilt) within the stated uncertainties, the reference-log path, the
// wrap at +-180 deg, the budgets, and every bad-input class with its message.
#include "metro/accuracy/accuracy.hpp"

#include <fmt/format.h>

#include <catch2/catch.hpp>
#include <cmath>

#include "accuracy/accuracy_report_json.hpp"
#include "metro/accuracy/accuracy_report.hpp"
#include "metro/core/angles.hpp"
#include "metro/io/session_io.hpp"
#include "metro/sim/table_session.hpp"
#include "support/session_text.hpp"
#include "support/temp_file.hpp"

namespace metro {
namespace {

using testing::Into;
using testing::Load;
using testing::TempFile;

struct Simulated {
  Session session;
  TableTruth truth;
};
Simulated Simulate(const TableSimulationOptions& o) {
  std::string text;
  Simulated s;
  REQUIRE(SimulateTableSession(o, SessionFormat::kCsv, Into(&text), nullptr, &s.truth).ok());
  s.session = Load(text);
  return s;
}

AccuracyResult Evaluate(const Session& session, const AccuracyOptions& o = {},
                        const Session* reference = nullptr) {
  auto r = EvaluateAccuracy(session, reference, o);
  if (!r.ok()) FAIL(r.error().ToString());
  return r.value();
}

TEST_CASE("Accuracy recovers offset, scale and mounting harmonics within their u",
          "[accuracy][slow]") {
  // No hysteresis, so the truth lies in the fitted model: c0 = 0.5, s = 0.002, a1 = 0.3,
  // b1 = -0.2, a2 = b2 = 0. Over 6 seeds x 6 parameters, |estimate - truth| <= 2 u in most
  // cases and <= 4 u in all.
  TableSimulationOptions o;
  o.hysteresis_deg = 0.0;
  const double truth[6] = {0.5, 0.002, 0.3, -0.2, 0.0, 0.0};
  int within2 = 0, total = 0;
  for (uint64_t seed = 1; seed <= 6; ++seed) {
    o.seed = seed;
    const AccuracyResult r = Evaluate(Simulate(o).session);
    REQUIRE(r.model == ErrorModel::kHarmonic2);
    REQUIRE(r.points.size() == 45);
    for (int j = 0; j < 6; ++j) {
      const double z = std::fabs(r.fit.params[j] - truth[j]) / r.fit.u[j];
      CHECK(z < 4.0);
      within2 += z <= 2.0;
      ++total;
    }
  }
  CHECK(within2 >= 0.8 * total);
}

TEST_CASE("Accuracy per-plateau errors, hysteresis, repeatability and cross-axis", "[accuracy]") {
  TableSimulationOptions o;  // hysteresis 0.15 deg, tilt 0.4 deg
  o.seed = 11;
  const Simulated sim = Simulate(o);
  AccuracyOptions opt;
  opt.reference.u_deg = 0.01;
  opt.reference.source = "--reference-u";
  const AccuracyResult r = Evaluate(sim.session, opt);
  REQUIRE(r.points.size() == sim.truth.plateaus.size());
  int within = 0;
  for (size_t i = 0; i < r.points.size(); ++i) {
    const AccuracyPoint& p = r.points[i];
    const TablePlateauTruth& t = sim.truth.plateaus[i];
    CHECK(p.reference_deg == Approx(t.reference_deg).margin(1e-9));
    CHECK(p.direction == t.direction);
    CHECK(std::fabs(p.error_deg - t.error_deg) < 5.0 * p.type_a.u_deg);
    within += std::fabs(p.error_deg - t.error_deg) <= 2.0 * p.type_a.u_deg;
    CHECK(WrapDeg180(p.mean_deg - p.reference_deg - p.error_deg) == Approx(0.0).margin(1e-9));
  }
  CHECK(within >= 0.85 * r.points.size());
  // Hysteresis: 0.15 deg at every angle visited both ways (30..300: 10 angles).
  REQUIRE(r.hysteresis.available);
  CHECK(r.hysteresis.pairs.size() == 10);
  CHECK(std::fabs(r.hysteresis.mean_deg - 0.15) < 3.0 * r.hysteresis.u_mean_deg);
  for (const HysteresisPair& h : r.hysteresis.pairs) {
    CHECK(std::fabs(h.hysteresis_deg - 0.15) < 4.0 * h.u_deg);
  }
  // Repeatability from two sweeps: only the plateau means' noise separates them, so s_r^2
  // is about the mean plateau u^2 (chi-square with the pooled dof; loose bounds).
  REQUIRE(r.repeatability.available);
  CHECK(r.repeatability.sweeps == 2);
  double mean_u2 = 0.0;
  for (const AccuracyPoint& p : r.points) mean_u2 += p.type_a.u_deg * p.type_a.u_deg;
  mean_u2 /= static_cast<double>(r.points.size());
  const double ratio = r.repeatability.s_r_deg * r.repeatability.s_r_deg / mean_u2;
  CHECK(ratio > 0.3);
  CHECK(ratio < 3.0);
  // Cross-axis: pitch = 1 + 0.4 sin(theta), roll = -2 + 0.4 cos(theta).
  REQUIRE(r.cross_axis[0].quantity == "pitch_deg");
  REQUIRE(r.cross_axis[1].quantity == "roll_deg");
  for (const CrossAxis& x : r.cross_axis) {
    REQUIRE(x.fitted);
    CHECK(std::fabs(x.amplitude_deg - 0.4) < 4.0 * x.u_amplitude_deg);
  }
  CHECK(r.cross_axis[0].fit.params[2] == Approx(0.4).margin(0.03));  // b1 of pitch
  CHECK(r.cross_axis[1].fit.params[1] == Approx(0.4).margin(0.03));  // a1 of roll
  CHECK(r.cross_axis[0].mean_deg == Approx(1.0).margin(0.05));
}

TEST_CASE("Accuracy budgets combine their inputs and cover single readings", "[accuracy]") {
  TableSimulationOptions o;
  o.seed = 5;
  const Simulated sim = Simulate(o);
  AccuracyOptions opt;
  opt.reference.u_deg = 0.02;
  const AccuracyResult r = Evaluate(sim.session, opt);
  // u_c^2 = sum of the squared inputs (all sensitivities 1, independent; JCGM 100 5.1.2).
  const double q = 0.01 * 0.01 / 12.0;
  // The hysteresis term: +-h/2 for a reading of unknown direction, u = sqrt(h^2 + u(h)^2)/2;
  // the fit residual beyond the plateaus' own u: sqrt(max(0, s_res^2 - mean u_i^2)).
  REQUIRE(r.fit_hysteresis_term);
  REQUIRE(r.fit.terms.back() == ErrorTerm::kHysteresis);
  const double h = r.fit.params.back(), uh = r.fit.u.back();
  double mean_u2 = 0.0;
  for (const AccuracyPoint& p : r.points) mean_u2 += p.type_a.u_deg * p.type_a.u_deg;
  mean_u2 /= static_cast<double>(r.points.size());
  const double lack2 = std::max(0.0, std::pow(r.fit.residual_rms_deg, 2) - mean_u2);
  const double corrected2 = r.reading_std_deg * r.reading_std_deg +
                            r.max_prediction_u_deg * r.max_prediction_u_deg + lack2 + 0.02 * 0.02 +
                            q + (h * h + uh * uh) / 4.0;
  CHECK(r.corrected.gum.u == Approx(std::sqrt(corrected2)).epsilon(1e-9));
  // U: P(|h/2 + N(0, s^2)| <= U) = 0.95 with s^2 = u_c^2 - h^2/4 (the +-h/2 two-point part
  // and a normal rest; symmetric, so one side suffices), solved here by bisection.
  {
    const double s = std::sqrt(corrected2 - h * h / 4.0);
    auto p_in = [&](double u) {
      return 0.5 * (std::erfc(-(u - h / 2) / s / std::sqrt(2.0)) -
                    std::erfc(-(-u - h / 2) / s / std::sqrt(2.0)));
    };
    double lo = 0.0, hi = 10.0;
    for (int i = 0; i < 200; ++i) (p_in(0.5 * (lo + hi)) < 0.95 ? lo : hi) = 0.5 * (lo + hi);
    CHECK(r.corrected.gum.expanded == Approx(hi).epsilon(1e-6));
    CHECK(r.corrected.gum.k == Approx(hi / r.corrected.gum.u).epsilon(1e-6));
  }
  const double uncorrected2 = r.systematic.rms_deg * r.systematic.rms_deg +
                              r.reading_std_deg * r.reading_std_deg + 0.02 * 0.02 + q;
  CHECK(r.uncorrected.gum.u == Approx(std::sqrt(uncorrected2)).epsilon(1e-9));
  CHECK(r.uncorrected_max_abs_expanded_deg ==
        Approx(r.random_expanded_deg + r.systematic.max_abs_deg));
  // Coverage of single readings on the plateaus (the simulated reference is exact): at
  // least ~95 % of the corrected readings lie within U_corrected of the truth, and of the
  // uncorrected ones within U_uncorrected.
  const Tag& tag = sim.session.tags[0];
  const Quantity* yaw = tag.Find("yaw_deg");
  size_t n = 0, in_corrected = 0, in_uncorrected = 0;
  for (const Plateau& p : r.segmentation.plateaus) {
    for (size_t k = p.begin; k < p.end; ++k) {
      const double e = WrapDeg180(yaw->values[k] - p.reference_deg);
      in_corrected += std::fabs(e - r.fit.Predict(p.reference_deg)) <= r.corrected.gum.expanded;
      in_uncorrected += std::fabs(e) <= r.uncorrected.gum.expanded;
      ++n;
    }
  }
  CHECK(static_cast<double>(in_corrected) / n > 0.93);
  CHECK(static_cast<double>(in_uncorrected) / n > 0.93);
  CHECK(r.corrected.gum.expanded < r.uncorrected.gum.expanded);
}

TEST_CASE("Accuracy is wrap-safe across +-180 deg", "[accuracy]") {
  // The table reports 90..270 deg; the tag's yaw wraps to -180..-90 past 180.
  TableSimulationOptions o;
  o.start_deg = 90.0;
  o.end_deg = 270.0;
  o.step_deg = 30.0;
  o.offset_deg = -0.4;
  o.seed = 3;
  const Simulated sim = Simulate(o);
  const AccuracyResult r = Evaluate(sim.session);
  for (size_t i = 0; i < r.points.size(); ++i) {
    CHECK(std::fabs(r.points[i].error_deg - sim.truth.plateaus[i].error_deg) < 0.1);
  }
  CHECK(r.points[4].reference_deg == Approx(210.0));
  CHECK(r.points[4].mean_deg < -149.0);
  CHECK(r.systematic.max_abs_deg < 2.0);
}

TEST_CASE("Accuracy with a receiver capture and a separate reference log", "[accuracy]") {
  TableSimulationOptions o;
  o.sweeps = 1;
  o.seed = 4;
  o.reference_clock_offset_s = 2.0;
  for (double lag : {0.0, 0.3}) {
    o.lag_tau_s = lag;
    std::string capture, ref_text;
    TableTruth truth;
    REQUIRE(
        SimulateTableSession(o, SessionFormat::kReceiver, Into(&capture), Into(&ref_text), &truth)
            .ok());
    const Session session = Load(capture);
    const Session reference = Load(ref_text);
    const AccuracyResult r = Evaluate(session, {}, &reference);
    REQUIRE(r.alignment.has_value());
    // The clock offset, with or without the tag's lag: the lag is estimated with it (a pure
    // delay would land up to tau early, 2 - tau), and the pure delay is kept as delay_s.
    CHECK(r.alignment->offset_s == Approx(2.0).margin(0.05));
    CHECK(r.alignment->lag_tau_s == Approx(lag).margin(0.05));
    if (lag > 0.0) CHECK(r.alignment->delay_s < 2.0 - 0.1);
    CHECK(r.alignment->residual_std_deg < r.alignment->residual_std_at_zero_deg);
    REQUIRE(r.points.size() == truth.plateaus.size());
    for (size_t i = 0; i < r.points.size(); ++i) {
      CHECK(std::fabs(r.points[i].error_deg - truth.plateaus[i].error_deg) <
            5.0 * r.points[i].type_a.u_deg);
    }
    const auto json = ToJsonValue(MakeAccuracyReport(r, session, &reference));
    CHECK(json["input"]["reference"]["alignment"]["offset_s"] == r.alignment->offset_s);
    CHECK(json["input"]["reference"]["alignment"]["method"].get<std::string>().find("estimated") !=
          std::string::npos);
  }
}

TEST_CASE("Accuracy report JSON layout", "[accuracy]") {
  TableSimulationOptions o;
  o.seed = 2;
  const Simulated sim = Simulate(o);
  const AccuracyResult r = Evaluate(sim.session);
  const auto j = ToJsonValue(MakeAccuracyReport(r, sim.session, nullptr));
  CHECK(j["schema"] == "metro.accuracy-report/1");
  CHECK(j["input"]["table_axis"] == "yaw");
  REQUIRE(j["points"].size() == 45);
  for (const char* key : {"reference_deg", "mean_deg", "error_deg", "type_a"}) {
    CHECK(j["points"][0].contains(key));
  }
  CHECK(j["points"][0]["type_a"].contains("n_eff"));
  // harmonic2 and the hysteresis term h_deg (the sweep goes up and down).
  CHECK(j["fit"]["params"].size() == 7);
  CHECK(j["fit"]["params"][6]["name"] == "h_deg");
  CHECK(j["fit"]["covariance"].size() == 7);
  for (const char* key : {"linearity", "hysteresis", "repeatability", "budget", "result",
                          "cross_axis", "segmentation", "systematic"}) {
    CHECK(j.contains(key));
  }
  CHECK(j["result"]["U_corrected_deg"] == r.corrected.gum.expanded);
  CHECK(j["budget"]["corrected"]["inputs"].size() == 6);
  CHECK(AccuracyReportTable(MakeAccuracyReport(r, sim.session, nullptr))
            .find("hysteresis (up - down)") != std::string::npos);
}

TEST_CASE("Accuracy bad input names what to collect", "[accuracy]") {
  TableSimulationOptions o;
  o.sweeps = 1;
  SECTION("fewer points than the model needs") {
    o.start_deg = 0.0;
    o.end_deg = 40.0;
    o.step_deg = 20.0;  // 3 angles
    auto r = EvaluateAccuracy(Simulate(o).session, nullptr, {});
    REQUIRE(!r.ok());
    CHECK(r.error().message.find("fewer points than the linear error model needs: it has 2 "
                                 "parameters and needs plateaus at >= 4 distinct reference "
                                 "angles; found 3 angle(s)") == 0);
  }
  SECTION("no plateau") {
    std::string text = "t_s,yaw_deg,pitch_deg,roll_deg,table_angle_deg\n";
    for (int i = 0; i < 200; ++i) text += fmt::format("{},{},0,0,{}\n", 0.1 * i, i, i);
    auto r = EvaluateAccuracy(Load(text), nullptr, {});
    REQUIRE(!r.ok());
    CHECK(r.error().message.find("no plateau found") == 0);
  }
  SECTION("no table column and no reference log") {
    auto r =
        EvaluateAccuracy(Load("t_s,yaw_deg,pitch_deg,roll_deg\n0,1,2,3\n0.1,1,2,3\n"), nullptr, {});
    REQUIRE(!r.ok());
    CHECK(r.error().message ==
          "tag 1 has no table_angle_deg column: log the table's angle in session.csv or give a "
          "separate reference log with --reference");
  }
  SECTION("no tag angles") {
    auto r = EvaluateAccuracy(Load("t_s,table_angle_deg\n0,1\n0.1,1\n"), nullptr, {});
    REQUIRE(!r.ok());
    CHECK(r.error().message ==
          "tag 1 has no yaw_deg (nor a quaternion qw..qz to derive it from): the accuracy "
          "evaluation of the yaw table needs the tag's yaw_deg");
  }
  SECTION("part of the quaternion") {
    Session s = Load("t_s,table_angle_deg\n0,1\n0.1,1\n");
    for (const char* name : {"qw", "qx"}) {
      s.tags.front().quantities.push_back({name, "1", QuantityOrigin::kFile, {1.0, 1.0}});
    }
    auto r = EvaluateAccuracy(s, nullptr, {});
    REQUIRE(!r.ok());
    CHECK(r.error().message ==
          "tag 1 has no yaw_deg (yaw_deg is derived from qw, qx, qy, qz; the session has qw, qx; "
          "missing qy, qz): the accuracy evaluation of the yaw table needs the tag's yaw_deg");
  }
  SECTION("several tags without --sensor, and an unknown one") {
    const Session s = Load("t_s,sensor,yaw_deg,pitch_deg,roll_deg\n0,1,0,0,0\n0,2,0,0,0\n");
    auto r = EvaluateAccuracy(s, nullptr, {});
    REQUIRE(!r.ok());
    CHECK(r.error().message == "the session holds tags 1, 2: choose one with --sensor");
    AccuracyOptions opt;
    opt.sensor = 7;
    auto r7 = EvaluateAccuracy(s, nullptr, opt);
    REQUIRE(!r7.ok());
    CHECK(r7.error().message == "the session has no tag 7 (--sensor)");
  }
  SECTION("a window that keeps nothing, and settle_auto in the window") {
    AccuracyOptions opt;
    opt.window.from_s = 1e6;
    const Session session = Simulate(o).session;
    auto r = EvaluateAccuracy(session, nullptr, opt);
    REQUIRE(!r.ok());
    CHECK(r.error().message ==
          fmt::format("the window (--skip-samples, --skip-seconds, --from-s, --to-s) keeps no "
                      "observation of tag {}",
                      session.tags.front().sensor));
    opt = {};
    opt.window.settle_auto = true;
    r = EvaluateAccuracy(session, nullptr, opt);
    REQUIRE(!r.ok());
    CHECK(r.error().message ==
          "window.settle_auto does not apply here: plateaus settle by plateaus.settle_auto");
  }
  SECTION("a reference log that does not overlap") {
    o.reference_clock_offset_s = 5000.0;
    std::string capture, ref_text;
    REQUIRE(
        SimulateTableSession(o, SessionFormat::kReceiver, Into(&capture), Into(&ref_text)).ok());
    const Session reference = Load(ref_text);
    auto r = EvaluateAccuracy(Load(capture), &reference, {});
    REQUIRE(!r.ok());
    CHECK(r.error().message.find("the reference log (t_s 5000 .. ") == 0);
    CHECK(r.error().message.find("does not overlap the tag log (t_s 0 .. ") != std::string::npos);
    CHECK(r.error().file == reference.path);
  }
  SECTION("a reference log without the table column") {
    const Session reference = Load("t_s,temp_c\n0,1\n1,1\n");
    auto r = EvaluateAccuracy(Simulate(o).session, &reference, {});
    REQUIRE(!r.ok());
    CHECK(r.error().message ==
          "the reference log has no table_angle_deg column: it needs t_s and table_angle_deg");
  }
  SECTION("invalid options") {
    AccuracyOptions opt;
    opt.reference.u_deg = -1.0;
    auto r = EvaluateAccuracy(Simulate(o).session, nullptr, opt);
    REQUIRE(!r.ok());
    CHECK(r.error().message == "the reference's standard uncertainty must be >= 0 deg, got -1");
  }
}

TEST_CASE("Reference uncertainty from a certificate budget", "[accuracy]") {
  // Certificate: +-0.01 deg rectangular (u = 0.01/sqrt 3) and an encoder term u = 0.004
  // with 10 dof: u_c = sqrt(0.01^2/3 + 0.004^2), nu_eff by Welch-Satterthwaite.
  TempFile budget(R"({"measurand": {"name": "table_error", "unit": "deg"},
    "inputs": [{"name": "cert", "value": 0, "distribution": "rectangular", "half_width": 0.01,
                "sensitivity": 1},
               {"name": "encoder", "value": 0, "u": 0.004, "dof": 10, "sensitivity": 1}],
    "monte_carlo": false})",
                  ".json");
  auto r = ReferenceUncertaintyFromBudget(budget.path());
  REQUIRE(r.ok());
  const double u2 = 0.01 * 0.01 / 3.0 + 0.004 * 0.004;
  CHECK(r.value().u_deg == Approx(std::sqrt(u2)).epsilon(1e-9));
  CHECK(r.value().dof == Approx(u2 * u2 / (std::pow(0.004, 4) / 10.0)).epsilon(1e-6));
  TempFile wrong(R"({"measurand": {"name": "x", "unit": "mm"},
    "inputs": [{"name": "a", "value": 0, "u": 1, "sensitivity": 1}], "monte_carlo": false})",
                 ".json");
  auto bad = ReferenceUncertaintyFromBudget(wrong.path());
  REQUIRE(!bad.ok());
  CHECK(bad.error().message ==
        "the reference budget's measurand is in 'mm'; the table's uncertainty must be in deg");
}

}  // namespace
}  // namespace metro
