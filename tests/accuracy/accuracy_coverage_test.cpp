// Coverage of every uncertainty the accuracy evaluation states, by simulation with known truth
// (issue #24): per-plateau errors, the fit parameters, hysteresis, repeatability, linearity and
// both single-reading U, over >= 40 seeds in each case of docs/accuracy.md ("Validation").
// The truth is read from the simulator's sidecar JSON (TableTruthJson). Fresh readings for
// the single-reading U come from a second session of the same tag (another seed).
#include <fmt/format.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>

#include "metro/accuracy/accuracy.hpp"
#include "metro/accuracy/accuracy_stages.hpp"
#include "metro/core/angles.hpp"
#include "metro/io/session_io.hpp"
#include "metro/sim/table_session.hpp"
#include "metro/uncertainty/gum.hpp"
#include "support/session_text.hpp"

namespace metro {
namespace {

using testing::Into;
using testing::Load;

// Hits and trials of one stated uncertainty.
struct Tally {
  int hit = 0, n = 0;
  void Add(bool in) {
    hit += in;
    ++n;
  }
  double Rate() const { return n > 0 ? static_cast<double>(hit) / n : 0.0; }
};

struct CaseTally {
  Tally plateau, params, hysteresis, repeatability, linearity, cross_axis, corrected, uncorrected;
  // Fresh readings per session: the share within U, averaged over sessions.
  double corrected_sum = 0.0, uncorrected_sum = 0.0;
  int sessions = 0;
};

enum class Reference { kColumn, kLog };

struct Case {
  std::string name;
  TableSimulationOptions sim;
  Reference reference = Reference::kColumn;
};

// The true per-plateau errors of the simulated session, from its truth JSON, matched to the
// evaluated plateaus by time.
const nlohmann::json* TruthPlateau(const nlohmann::json& truth, double t_s) {
  for (const nlohmann::json& p : truth["plateaus"]) {
    if (t_s >= p["t_start_s"].get<double>() - 1e-6 && t_s <= p["t_end_s"].get<double>() + 1e-6) {
      return &p;
    }
  }
  return nullptr;
}

int DirectionOf(const nlohmann::json& p) {
  const std::string d = p["direction"];
  return d == "up" ? 1 : d == "down" ? -1 : 0;
}

void RunCase(const Case& c, uint64_t seeds, CaseTally* tally) {
  for (uint64_t seed = 1; seed <= seeds; ++seed) {
    TableSimulationOptions o = c.sim;
    o.seed = seed;
    if (c.reference == Reference::kLog) {
      o.reference_clock_offset_s = 0.05 + 0.05 * static_cast<double>(seed % 4);  // 50..200 ms
    }
    std::string text, ref_text;
    TableTruth truth_plateaus;
    REQUIRE(SimulateTableSession(o, SessionFormat::kCsv, Into(&text),
                                 c.reference == Reference::kLog ? Into(&ref_text) : nullptr,
                                 &truth_plateaus)
                .ok());
    const nlohmann::json truth = nlohmann::json::parse(TableTruthJson(o, truth_plateaus));
    const Session session = Load(text);
    std::optional<Session> reference;
    if (c.reference == Reference::kLog) reference = Load(ref_text);
    auto evaluated = EvaluateAccuracy(session, reference ? &*reference : nullptr, {});
    if (!evaluated.ok()) FAIL(c.name << " seed " << seed << ": " << evaluated.error().ToString());
    const AccuracyResult& r = evaluated.value();

    // Per-plateau errors.
    std::vector<double> true_error(r.points.size());
    for (size_t i = 0; i < r.points.size(); ++i) {
      const AccuracyPoint& p = r.points[i];
      const nlohmann::json* t = TruthPlateau(truth, 0.5 * (p.t_start_s + p.t_end_s));
      REQUIRE(t != nullptr);
      // The first plateau's direction is unknown to the evaluation ("first").
      CHECK((DirectionOf(*t) == p.direction || (i == 0 && p.direction == 0)));
      true_error[i] = (*t)["error_deg"].get<double>();
      const double k = CoverageFactor(0.95, p.type_a.dof);
      tally->plateau.Add(std::fabs(p.error_deg - true_error[i]) <= k * p.type_a.u_deg);
    }
    // Fit parameters: with the hysteresis term the curve is the mean of up and down; without
    // it (up-only) the curve is the up curve, offset by h/2.
    const double h = truth["hysteresis_deg"];
    const double up_shift = r.fit_hysteresis_term ? 0.0 : 0.5 * h;
    const double kfit = CoverageFactor(0.95, r.fit.dof);
    for (size_t j = 0; j < r.fit.terms.size(); ++j) {
      double value = 0.0;
      switch (r.fit.terms[j]) {
        case ErrorTerm::kOffset:
          value = truth["offset_deg"].get<double>() + up_shift;
          break;
        case ErrorTerm::kScale:
          value = truth["scale_error"];
          break;
        case ErrorTerm::kCos1:
          value = truth["cos1_deg"];
          break;
        case ErrorTerm::kSin1:
          value = truth["sin1_deg"];
          break;
        case ErrorTerm::kHysteresis:
          value = h;
          break;
        default:
          break;
      }
      tally->params.Add(std::fabs(r.fit.params[j] - value) <= kfit * r.fit.u[j]);
    }
    if (r.hysteresis.available) {
      tally->hysteresis.Add(std::fabs(r.hysteresis.mean_deg - h) <= 1.96 * r.hysteresis.u_mean_deg);
    }
    if (r.repeatability.available) {
      // The truth: the simulated tag repeats but for the noise of its plateau means,
      // s_r^2 = mean of sigma^2 F(n_i, phi) over the plateaus (AR(1) per frame).
      double v = 0.0;
      for (const AccuracyPoint& p : r.points) {
        v += std::pow(truth["noise_std_deg"].get<double>(), 2) *
                 Ar1MeanVarianceFactor(static_cast<size_t>(p.type_a.n),
                                       truth["noise_ar1_per_frame"].get<double>()) +
             std::pow(truth["quantization_deg"].get<double>(), 2) / 12.0 /
                 static_cast<double>(p.type_a.n);
      }
      const double s_true = std::sqrt(v / static_cast<double>(r.points.size()));
      tally->repeatability.Add(std::fabs(r.repeatability.s_r_deg - s_true) <=
                               1.96 * r.repeatability.u_s_r_deg);
    }
    {
      // Linearity: the same straight-line deviation of the true per-angle mean errors.
      std::vector<AccuracyPoint> truth_points = r.points;
      for (size_t i = 0; i < truth_points.size(); ++i) truth_points[i].error_deg = true_error[i];
      const Linearity true_lin = LinearityOf(truth_points, r.options.angle_match_deg);
      // Deviation at the reported angle, estimated and true.
      auto deviation_at = [&](const std::vector<AccuracyPoint>& pts, const Linearity& lin) {
        double sum = 0.0;
        int count = 0;
        for (const AccuracyPoint& p : pts) {
          if (std::fabs(p.reference_deg - lin.at_reference_deg) <= r.options.angle_match_deg) {
            sum += p.error_deg;
            ++count;
          }
        }
        return sum / count - (lin.line_offset_deg + lin.line_slope * lin.at_reference_deg);
      };
      Linearity at = true_lin;
      at.at_reference_deg = r.linearity.at_reference_deg;
      const double d_true = deviation_at(truth_points, at);
      const double d_est = deviation_at(r.points, r.linearity);
      tally->linearity.Add(std::fabs(d_est - d_true) <= 1.96 * r.linearity.u_max_abs_deviation_deg);
    }

    // Cross-axis: both other axes carry the mounting tilt's first harmonic, amplitude tilt.
    for (const CrossAxis& x : r.cross_axis) {
      if (!x.fitted) continue;
      tally->cross_axis.Add(std::fabs(x.amplitude_deg - truth["tilt_deg"].get<double>()) <=
                            1.96 * x.u_amplitude_deg);
    }

    // Fresh readings: another session of the same tag, up and down, at the same angles.
    TableSimulationOptions f = c.sim;
    f.seed = seed + 100000;
    f.up_only = false;
    f.sweeps = 1;
    f.readout_wrap_180 = false;
    f.reference_clock_offset_s = 0.0;
    std::string fresh_text;
    TableTruth fresh_truth;
    REQUIRE(SimulateTableSession(f, SessionFormat::kCsv, Into(&fresh_text), nullptr, &fresh_truth)
                .ok());
    const Session fresh = Load(fresh_text);
    const Tag& tag = fresh.tags.at(0);
    const Quantity* reading = tag.Find(TableAxisQuantity(f.axis));
    const Quantity* table = tag.Find("table_angle_deg");
    REQUIRE(reading != nullptr);
    REQUIRE(table != nullptr);
    Tally corrected, uncorrected;
    size_t next = 0;
    for (const TablePlateauTruth& p : fresh_truth.plateaus) {
      // Settled readings: 10 response times after the table stopped.
      const double from = p.t_start_s + std::min(10.0 * f.lag_tau_s + 0.5, 0.5 * f.dwell_s);
      while (next < tag.size() && tag.t_s[next] < from) ++next;
      for (; next < tag.size() && tag.t_s[next] < p.t_end_s; next += 3) {
        const double e = WrapDeg180(reading->values[next] - table->values[next]);
        corrected.Add(std::fabs(e - r.fit.Predict(p.reference_deg)) <= r.corrected.gum.expanded);
        uncorrected.Add(std::fabs(e) <= r.uncorrected.gum.expanded);
      }
    }
    tally->corrected.hit += corrected.hit;
    tally->corrected.n += corrected.n;
    tally->uncorrected.hit += uncorrected.hit;
    tally->uncorrected.n += uncorrected.n;
    tally->corrected_sum += corrected.Rate();
    tally->uncorrected_sum += uncorrected.Rate();
    ++tally->sessions;
  }
}

std::vector<Case> Cases() {
  std::vector<Case> cases;
  Case c;
  c.name = "default sweeps";
  cases.push_back(c);
  c = Case();
  c.name = "4 s dwell";
  c.sim.dwell_s = 4.0;
  cases.push_back(c);
  c = Case();
  c.name = "tag lags 1 s";
  c.sim.lag_tau_s = 1.0;
  cases.push_back(c);
  c = Case();
  c.name = "reference log 50-200 ms ahead";
  c.reference = Reference::kLog;
  cases.push_back(c);
  c = Case();
  c.name = "readout wraps at 180";
  c.sim.readout_wrap_180 = true;
  cases.push_back(c);
  c = Case();
  c.name = "up-only sweep";
  c.sim.up_only = true;
  c.sim.sweeps = 1;
  cases.push_back(c);
  return cases;
}

void Report(const std::string& name, const CaseTally& t) {
  auto cell = [](const Tally& x) {
    return x.n > 0 ? fmt::format("{:5.1f} % ({:4d})", 100.0 * x.Rate(), x.n) : std::string("  n/a");
  };
  std::fprintf(stderr,
               "%-30s plateau %s  params %s  hysteresis %s  repeatability %s  linearity %s  "
               "cross-axis %s  U_corrected %5.1f %%  U_uncorrected %5.1f %% (sessions %d)\n",
               name.c_str(), cell(t.plateau).c_str(), cell(t.params).c_str(),
               cell(t.hysteresis).c_str(), cell(t.repeatability).c_str(), cell(t.linearity).c_str(),
               cell(t.cross_axis).c_str(), 100.0 * t.corrected_sum / t.sessions,
               100.0 * t.uncorrected_sum / t.sessions, t.sessions);
}

// p within sampling error of 0.95 for n trials: at least 0.95 - 3 sqrt(0.95 0.05 / n_eff)
// (trials of one session are correlated, so n_eff is the trial count capped at 10 per
// session), and at most the larger of 99.5 % and 95 % + 3 standard errors (conservative,
// but not grossly: at 4 s dwell the fit parameters cover 98.2 %, their points' u resting on a
// noise estimate of about 11 dof that the Birge ratio only enlarges).
void CheckCoverage(const Tally& t, int sessions, const char* what, const std::string& name) {
  if (t.n == 0) return;
  const double n_eff = std::min<double>(t.n, 10.0 * sessions);
  const double band = 3.0 * std::sqrt(0.95 * 0.05 / n_eff);
  INFO(name << ": " << what << " " << 100.0 * t.Rate() << " % of " << t.n);
  CHECK(t.Rate() >= 0.95 - band);
  CHECK(t.Rate() <= std::max(0.995, 0.95 + band));
}

TEST_CASE("Accuracy uncertainties hold their coverage over 40 seeds per case", "[accuracy][slow]") {
  for (const Case& c : Cases()) {
    CaseTally t;
    RunCase(c, 40, &t);
    Report(c.name, t);
    CheckCoverage(t.plateau, t.sessions, "per-plateau error", c.name);
    CheckCoverage(t.params, t.sessions, "fit parameters", c.name);
    CheckCoverage(t.hysteresis, t.sessions, "hysteresis", c.name);
    CheckCoverage(t.repeatability, t.sessions, "repeatability", c.name);
    CheckCoverage(t.linearity, t.sessions, "linearity", c.name);
    CheckCoverage(t.cross_axis, t.sessions, "cross-axis amplitude", c.name);
    // Single readings: the share of fresh readings within U, averaged over the sessions, at
    // least the stated 95 % less sampling error, and not far above it except when
    // hysteresis was not measured (the assumed bound widens U by design).
    const double corrected = t.corrected_sum / t.sessions;
    const double uncorrected = t.uncorrected_sum / t.sessions;
    INFO(c.name << ": corrected " << corrected << ", uncorrected " << uncorrected);
    CHECK(corrected >= 0.93);
    CHECK(uncorrected >= 0.93);
    if (!c.sim.up_only) CHECK(corrected <= 0.99);
    CHECK(uncorrected <= 0.99);
  }
}

TEST_CASE("Accuracy coverage harness on one seed per case", "[accuracy]") {
  // The quick loop's version of the slow run: every case evaluates and its numbers are sane.
  for (const Case& c : Cases()) {
    CaseTally t;
    RunCase(c, 1, &t);
    CHECK(t.plateau.n > 0);
    CHECK(t.plateau.Rate() >= 0.8);
    CHECK(t.corrected_sum / t.sessions >= 0.85);
  }
}

TEST_CASE("A pitch table through 90 deg is refused with the reason", "[accuracy]") {
  TableSimulationOptions o;
  o.axis = TableAxis::kPitch;
  o.pitch_through_90 = true;
  o.start_deg = 0.0;
  o.end_deg = 120.0;
  o.base_deg[0] = 10.0;  // yaw
  o.base_deg[1] = 5.0;   // roll
  std::string text;
  REQUIRE(SimulateTableSession(o, SessionFormat::kCsv, Into(&text)).ok());
  const Session s = Load(text);
  AccuracyOptions opt;
  opt.axis = TableAxis::kPitch;
  auto r = EvaluateAccuracy(s, nullptr, opt);
  REQUIRE(!r.ok());
  CHECK(r.error().message.find("the pitch table reaches 120 deg: the tag's pitch is an Euler angle "
                               "in [-90, 90] deg that folds over at +-90") == 0);
}

}  // namespace
}  // namespace metro
