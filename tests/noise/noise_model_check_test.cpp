// The goodness of fit of the IEEE 952 model against the Allan curve, the stretch where it
// holds, and the model selection's statistics (issue #36 parts 1 and 2; docs/noise.md 4a).
#include <catch2/catch.hpp>
#include <cmath>
#include <string>
#include <vector>

#include "core/json_reader.hpp"
#include "metro/noise/allan.hpp"
#include "metro/noise/allan_report.hpp"
#include "metro/noise/noise_fit.hpp"
#include "noise/allan_report_json.hpp"
#include "noise/noise_simulation.hpp"
#include "support/noise_generators.hpp"

namespace metro {
namespace {

constexpr double kTau0 = 0.01;  // 100 Hz

TEST_CASE("The model check accepts records the IEEE 952 model describes", "[noise][slow]") {
  // N + B + K through an integrating sampler (noise_simulation.hpp: the model is exact at
  // every tau), 20 min at 100 Hz. Under the model p is uniform: at alpha = 0.01 three or more
  // rejections in 10 records have probability 1e-4, and the mean of 10 p-values lies in
  // 0.5 +- 0.3 with probability 0.999 (sd 0.091).
  const std::array<double, 5> truth = {0.0, 0.005, 0.0075, 1.3e-3, 0.0};
  int rejected = 0;
  double sum_p = 0.0;
  const int records = 10;
  for (int r = 0; r < records; ++r) {
    const Result<AllanCurve> curve =
        ComputeAllan(testing::Ieee952Rate(120000, kTau0, truth, 7100 + r), kTau0);
    REQUIRE(curve.ok());
    const Result<NoiseFit> fit = FitNoiseTerms(curve.value());
    REQUIRE(fit.ok());
    const NoiseModelCheck& c = fit.value().model_check;
    REQUIRE(c.tested);
    CHECK(c.dof == fit.value().dof);
    CHECK(c.chi2 == Approx(fit.value().chi2));
    REQUIRE(c.z.size() == c.tau_s.size());
    CHECK(static_cast<int>(c.tau_s.size()) == fit.value().n_points);
    rejected += c.rejected ? 1 : 0;
    sum_p += c.p_value;
    if (!c.rejected) {
      // Not rejected: it holds over the whole fitted range, and the terms are fitted there.
      CHECK(c.holds_tau_min_s == fit.value().fit_tau_min_s);
      CHECK(c.holds_tau_max_s == fit.value().fit_tau_max_s);
      CHECK(c.holds_p_value == c.p_value);
    }
    const AllanTypeALink link = MakeAllanTypeALink(curve.value(), fit.value(), 1200.0);
    CHECK(link.noise_model == std::optional<std::string>(c.rejected ? "rejected" : "holds"));
  }
  CHECK(rejected <= 2);
  CHECK(sum_p / records > 0.2);
  CHECK(sum_p / records < 0.8);
}

TEST_CASE("A slow oscillation the model lacks is rejected, and the model holds below it",
          "[noise]") {
  // White rate N plus a rate oscillation of amplitude A and period P = 300 s over 20 min
  // (a temperature cycle): AVAR = N^2 / tau + A^2 sin^4(pi tau / P) / (pi tau / P)^2, which
  // rises like a ramp below ~P / 6 and falls again beyond 0.37 P, which no IEEE 952 term does.
  const double n = 0.005, a = 0.01, period_s = 300.0;
  std::vector<double> y = testing::WhiteNoise(120000, n / std::sqrt(kTau0), 88);
  for (size_t k = 0; k < y.size(); ++k) {
    y[k] += a * std::sin(2.0 * M_PI * static_cast<double>(k) * kTau0 / period_s);
  }
  const Result<AllanCurve> curve = ComputeAllan(y, kTau0);
  REQUIRE(curve.ok());
  const Result<NoiseFit> fit = FitNoiseTerms(curve.value());
  REQUIRE(fit.ok());
  const NoiseModelCheck& c = fit.value().model_check;
  REQUIRE(c.tested);
  CHECK(c.rejected);
  CHECK(c.p_value < 1e-6);
  REQUIRE_FALSE(c.contradicting_taus_s.empty());
  REQUIRE(c.holds_somewhere());
  // It holds from the shortest tau up to below the bump's fall, and the terms are fitted there.
  CHECK(c.holds_tau_min_s == c.tau_s.front());
  CHECK(c.holds_tau_max_s < 0.5 * period_s);
  CHECK(c.holds_p_value >= 0.01);
  CHECK(fit.value().fit_tau_max_s == c.holds_tau_max_s);
  CHECK(c.holds_tau_max_s < c.tau_s.back());  // the longest taus lie outside
  // N from the stretch where the model holds is the truth (white noise rules there).
  const NoiseTermEstimate& nt = fit.value().term(NoiseTerm::kRandomWalk);
  REQUIRE(nt.supported);
  CHECK(std::fabs(nt.value - n) < 4.0 * nt.u);
  // The report says so, marks the terms and never lets the model set u(mean).
  const AllanReport report = MakeAllanReport(curve.value(), fit.value(), "deg/s");
  REQUIRE(report.model_check.has_value());
  CHECK(report.model_check->rejected);
  REQUIRE(report.model_check->tau_range_model_holds_s.has_value());
  CHECK((*report.model_check->tau_range_model_holds_s)[1] == c.holds_tau_max_s);
  CHECK(report.model_check->summary.find("rejected by the Allan curve") != std::string::npos);
  CHECK(report.model_check->summary.find("u(mean) is not taken from the model") !=
        std::string::npos);
  CHECK(report.term(NoiseTerm::kRandomWalk).model_rejected == std::optional<bool>(true));
  const AllanTypeALink link = MakeAllanTypeALink(curve.value(), fit.value(), 1200.0);
  CHECK(link.noise_model == std::optional<std::string>("rejected"));

  // Without the search for a holding stretch the terms are fitted over the whole range.
  NoiseFitOptions whole;
  whole.restrict_to_holding_range = false;
  const Result<NoiseFit> all = FitNoiseTerms(curve.value(), whole);
  REQUIRE(all.ok());
  CHECK(all.value().model_check.rejected);
  CHECK_FALSE(all.value().model_check.holds_somewhere());
  CHECK(all.value().fit_tau_max_s > c.holds_tau_max_s);
}

TEST_CASE("A model with no degree of freedom is not tested and says so", "[noise]") {
  // Two non-overlapping points that need two terms (Q and N, both far beyond their u with
  // edf 1e6): an exact fit with dof 0, which cannot be tested.
  AllanCurve c;
  c.estimator = AllanEstimator::kAdev;
  c.tau0_s = 1.0;
  c.m = {1, 2};
  c.tau_s = {1.0, 2.0};
  const double q = 0.1, nn = 0.2;
  for (double tau : c.tau_s) {
    const double var = 3.0 * q * q / (tau * tau) + nn * nn / tau;
    c.dev.push_back(std::sqrt(var));
    c.edf.push_back(1e6);
    c.ci_low.push_back(std::sqrt(var) * 0.999);
    c.ci_high.push_back(std::sqrt(var) * 1.001);
    c.alpha.push_back(0);
    c.alpha_source.push_back(AlphaSource::kFixed);
  }
  c.n_terms = {1000000, 500000};
  NoiseFitOptions o;
  o.allow = {true, true, false, false, false};
  const Result<NoiseFit> fit = FitNoiseTerms(c, o);
  REQUIRE(fit.ok());
  REQUIRE(fit.value().dof == 0);
  const NoiseModelCheck& check = fit.value().model_check;
  CHECK_FALSE(check.tested);
  CHECK(check.not_tested ==
        "the model cannot be tested: 2 fitted taus for 2 terms leave no degree of freedom");
  CHECK(std::isnan(check.chi2));
  CHECK(std::isnan(check.p_value));
  CHECK_FALSE(check.rejected);
  const AllanReport report = MakeAllanReport(c, fit.value(), "deg/s");
  REQUIRE(report.model_check.has_value());
  CHECK_FALSE(report.model_check->tested);
  CHECK(report.model_check->summary.find("was not tested") != std::string::npos);
  const nlohmann::ordered_json j = ToJsonValue(report);
  CHECK(j["model_check"]["chi2"].is_null());
  CHECK(j["model_check"]["p_value"].is_null());
  CHECK(j["model_check"]["dof"].is_null());
  CHECK(j["model_check"]["tau_range_model_holds_s"].is_null());
  CHECK(MakeAllanTypeALink(c, fit.value(), 10.0).noise_model ==
        std::optional<std::string>("untested"));
}

TEST_CASE("Model check and selection round-trip through the report JSON", "[noise]") {
  const std::array<double, 5> truth = {0.0, 0.005, 0.0075, 0.0, 0.0};
  const Result<AllanCurve> curve =
      ComputeAllan(testing::Ieee952Rate(60000, kTau0, truth, 31), kTau0);
  REQUIRE(curve.ok());
  const Result<NoiseFit> fit = FitNoiseTerms(curve.value());
  REQUIRE(fit.ok());
  const AllanReport report = MakeAllanReport(curve.value(), fit.value(), "deg/s");
  const nlohmann::ordered_json j = ToJsonValue(report);
  // The added keys come after the existing ones, so older keys keep their places.
  std::vector<std::string> top;
  for (auto it = j.begin(); it != j.end(); ++it) top.push_back(it.key());
  REQUIRE(top.size() >= 15);
  CHECK(top[13] == "sample_period");
  CHECK(top[14] == "model_check");
  std::vector<std::string> keys;
  for (auto it = j["model_check"].begin(); it != j["model_check"].end(); ++it) {
    keys.push_back(it.key());
  }
  CHECK(keys == std::vector<std::string>{"tested", "not_tested", "chi2", "dof", "p_value", "alpha",
                                         "rejected", "tau_s", "z", "contradicting_taus_s",
                                         "tau_range_model_holds_s", "holds_chi2", "holds_dof",
                                         "holds_p_value", "summary"});
  const auto& rw = j["noise"]["random_walk"];
  CHECK(rw["selection"]["decision"] == "in");
  // A kept term raised chi2 by more than its penalty when removed.
  CHECK(rw["selection"]["delta_chi2"].get<double>() >
        rw["selection"]["penalty_chi2"].get<double>());
  CHECK(j["noise"]["rate_ramp"]["selection"]["penalty_chi2"].get<double>() == Approx(6.635));
  CHECK(j["noise"]["rate_ramp"]["u_model"].is_null());
  CHECK(rw["u_model"].get<double>() <= rw["u"].get<double>());
  // Round trip.
  const JsonDocument doc = JsonDocument::Parse(j.dump(), "allan.json").value();
  const JsonCursor cursor(doc);
  const AllanReport back = AllanReportFromJsonValue(cursor);
  REQUIRE(cursor.ok());
  CHECK(ToJsonValue(back) == j);
  // A report from before issue #36 (no model_check, no term additions) still loads.
  nlohmann::ordered_json old = j;
  old.erase("model_check");
  old.erase("b_k");
  for (auto& [key, term] : old["noise"].items()) {
    term.erase("model_rejected");
    term.erase("u_model");
    term.erase("selection");
  }
  const JsonDocument old_doc = JsonDocument::Parse(old.dump(), "old.json").value();
  const JsonCursor old_cursor(old_doc);
  const AllanReport old_back = AllanReportFromJsonValue(old_cursor);
  REQUIRE(old_cursor.ok());
  CHECK_FALSE(old_back.model_check.has_value());
  CHECK(ToJsonValue(old_back) == old);
}

}  // namespace
}  // namespace metro
