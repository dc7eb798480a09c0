// Issue #36: nested model comparison (bias < scale < full), --model auto, and the Type B term
// for the cross-axis sensitivity a rejected or exact scale model leaves out.
#include "calibration/model_selection.hpp"

#include <fmt/format.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <map>
#include <string>
#include <tuple>
#include <vector>

#include "metro/calibration/calibrate.hpp"
#include "metro/calibration/simulate.hpp"

namespace metro {
namespace {

namespace ci = calibration_internal;

constexpr double kPi = 3.14159265358979323846;

// The upper tail of chi2(3) in closed form: erfc(sqrt(x/2)) + sqrt(2x/pi) exp(-x/2).
double ChiSquare3Tail(double x) {
  return std::erfc(std::sqrt(x / 2)) + std::sqrt(2 * x / kPi) * std::exp(-x / 2);
}

ci::LadderFit Fitted(ModelKind kind, double chi2, double dof, int parameters) {
  ci::LadderFit f;
  f.kind = kind;
  f.fitted = true;
  f.chi2 = chi2;
  f.chi2_dof = dof;
  f.parameters = parameters;
  return f;
}

TEST_CASE("Model comparison: chi-square difference when the larger model fits its noise",
          "[calibration][model]") {
  // full: chi-square 10 over 10 dof (fits); scale: 3 fewer parameters.
  const ci::LadderFit full = Fitted(ModelKind::kFull, 10.0, 10.0, 9);
  for (const auto& [scale_chi2, rejected] : {std::pair{30.0, true}, std::pair{15.0, false}}) {
    const ModelComparison c =
        ci::CompareModels(Fitted(ModelKind::kScale, scale_chi2, 13.0, 6), full);
    CHECK(c.test == "chi2_difference");
    CHECK(c.statistic == Approx(scale_chi2 - 10.0));
    CHECK(c.dof1 == 3);
    CHECK(c.dof2 == 0);
    CHECK(c.p_value == Approx(ChiSquare3Tail(scale_chi2 - 10.0)).epsilon(1e-10));
    CHECK(c.rejected == rejected);  // p = 1.9e-4 and 0.172
  }
}

TEST_CASE("Model comparison: F-test when the larger model does not fit its noise",
          "[calibration][model]") {
  // full: chi-square 50 over 10 dof, above its 99 % point 23.21: F = (delta / 3) / (50 / 10).
  // At the tabulated 5 % point of F(3, 10), 3.7083, p = 0.05.
  const ci::LadderFit full = Fitted(ModelKind::kFull, 50.0, 10.0, 9);
  const ModelComparison at =
      ci::CompareModels(Fitted(ModelKind::kScale, 50.0 + 3 * 3.7083 * 5.0, 13.0, 6), full);
  CHECK(at.test == "F");
  CHECK(at.statistic == Approx(3.7083));
  CHECK(at.dof1 == 3);
  CHECK(at.dof2 == 10);
  CHECK(at.p_value == Approx(0.05).margin(2e-5));
  // F = 2 lies between the tabulated 25 % (1.6028) and 10 % (2.7277) points.
  const ModelComparison two =
      ci::CompareModels(Fitted(ModelKind::kScale, 50.0 + 3 * 2.0 * 5.0, 13.0, 6), full);
  CHECK(two.statistic == Approx(2.0));
  CHECK(two.p_value > 0.10);
  CHECK(two.p_value < 0.25);
  CHECK_FALSE(two.rejected);
  // Without a chi-square against the noise nothing is computed, and it says so.
  ci::LadderFit unmeasured = full;
  unmeasured.chi2 = -1;
  const ModelComparison none =
      ci::CompareModels(Fitted(ModelKind::kScale, 80.0, 13.0, 6), unmeasured);
  CHECK(none.test.empty());
  CHECK_THAT(none.note, Catch::Contains("not computed"));
}

TEST_CASE("Model auto takes the smallest model its larger neighbour does not reject",
          "[calibration][model]") {
  const ci::LadderFit bias = Fitted(ModelKind::kBias, 5000.0, 16.0, 3);
  const ci::LadderFit scale_ok = Fitted(ModelKind::kScale, 14.0, 13.0, 6);
  const ci::LadderFit scale_bad = Fitted(ModelKind::kScale, 400.0, 13.0, 6);
  const ci::LadderFit full = Fitted(ModelKind::kFull, 10.0, 10.0, 9);
  {
    const std::vector<ci::LadderFit> fits = {bias, scale_ok, full};
    CHECK(ci::ChooseModel(fits, ci::CompareLadder(fits)) == ModelKind::kScale);
  }
  {
    const std::vector<ci::LadderFit> fits = {bias, scale_bad, full};
    CHECK(ci::ChooseModel(fits, ci::CompareLadder(fits)) == ModelKind::kFull);
  }
  {
    // The full model could not be fitted (6 orientations): scale, untested against it.
    ci::LadderFit no_full;
    no_full.kind = ModelKind::kFull;
    no_full.why = "degenerate calibration";
    const std::vector<ci::LadderFit> fits = {bias, scale_bad, no_full};
    const std::vector<ModelComparison> c = ci::CompareLadder(fits);
    REQUIRE(c.size() == 2);
    CHECK_THAT(c[1].note, Catch::Contains("could not be fitted: degenerate calibration"));
    CHECK(ci::ChooseModel(fits, c) == ModelKind::kScale);
    // Rejected against its noise: the scale model gets the Type B term, not a refusal.
    const ModelCheck m = ci::CheckChosenModel(ImuSensor::kGyro, scale_bad, true, c, false);
    CHECK(m.status == "rejected");
    REQUIRE(m.type_b);
    CHECK(m.type_b->u == Approx(0.02 / std::sqrt(3.0)));
    CHECK_FALSE(m.model_rejected);
  }
  {
    // A rejected bias model and an exact full model are marked model_rejected.
    const ModelCheck b = ci::CheckChosenModel(ImuSensor::kAccel, bias, false, {}, false);
    CHECK(b.status == "rejected");
    CHECK(b.model_rejected);
    ci::LadderFit exact = full;
    exact.orientations = 9;
    const ModelCheck e = ci::CheckChosenModel(ImuSensor::kAccel, exact, false, {}, false);
    CHECK(e.status == "exact_fit");
    CHECK(e.model_rejected);
    CHECK_THAT(e.reason, Catch::Contains("one more distinct orientation"));
  }
}

// ---- Simulated tags ------------------------------------------------------------------------

struct SimCase {
  const char* name;
  double accel_cross = 0.01;  // Truth's cross-axis half-widths (issue #36's realistic terms).
  double gyro_cross = 0.015;
  int poses = 26;
  PoseSet set = PoseSet::kCube;
  bool automatic = true;  // --model auto; else `model` for both sensors.
  ModelKind model = ModelKind::kScale;
};

// Over simulated tags: per sensor the model chosen, the tags whose constants are marked
// model_rejected, and per sensor and constant class (b, k, m) the truth within 2u of the
// constants that are not.
struct TagRun {
  std::map<std::string, int> chosen;                  // "accel full" -> tags
  std::map<std::string, int> refused;                 // "accel" -> tags
  std::map<std::string, std::pair<int, int>> inside;  // "accel b" -> (within, total)
  std::string refusal;                                // The first refused fit's error.
  double Rate(const std::string& key) const {
    const auto it = inside.find(key);
    return it == inside.end() || it->second.second == 0
               ? 1.0
               : static_cast<double>(it->second.first) / it->second.second;
  }
  int Total(const std::string& key) const {
    const auto it = inside.find(key);
    return it == inside.end() ? 0 : it->second.second;
  }
};

void Tally(const SensorCalibration& c, const SensorModel& truth, const std::string& sensor,
           TagRun* run) {
  const SensorModel& m = c.model;
  const auto add = [&](const char* cls, double error, double u) {
    auto& [in, total] = run->inside[sensor + " " + cls];
    in += std::abs(error) <= 2.0 * u ? 1 : 0;
    ++total;
  };
  for (int a = 0; a < 3; ++a) {
    add("b", m.bias[a] - truth.bias[a], c.bias_u[a]);
    if (m.kind != ModelKind::kBias) add("k", m.scale[a] - truth.scale[a], c.scale_u[a]);
  }
  if (m.kind == ModelKind::kFull) {
    for (size_t i = 0; i < m.misalignment.size(); ++i) {
      add("m", m.misalignment[i] - truth.misalignment[i], c.misalignment_u[i]);
    }
  }
}

TagRun RunTags(const SimCase& c, int tags, uint64_t seed) {
  TagRun run;
  for (int tag = 0; tag < tags; ++tag) {
    SimulationOptions so;
    so.seed = seed + static_cast<uint64_t>(tag);
    so.poses = c.poses;
    so.pose_set = c.set;
    so.dwell_s = 2.0;
    so.move_s = 1.5;
    so.accel_cross_axis = c.accel_cross;
    so.gyro_cross_axis = c.gyro_cross;
    Result<SimulatedSession> sim = SimulateCalibrationSession(so);
    REQUIRE(sim.ok());
    CalibrationOptions o;
    o.accel_auto = o.gyro_auto = c.automatic;
    o.compare_models = true;
    o.accel_model = o.gyro_model = c.model;
    Result<TagCalibration> r = CalibrateTag({&sim.value().session.tags.front()}, o);
    if (!r.ok() && r.error().message.find("degenerate calibration") != std::string::npos) {
      ++run.refused["fit (degenerate)"];  // No constants at all: nothing to cover.
      if (run.refusal.empty()) run.refusal = r.error().message;
      continue;
    }
    if (!r.ok()) FAIL(c.name << " tag " << tag << ": " << r.error().ToString());
    for (const auto& [cal, truth, name] :
         {std::tuple{&r.value().accel, &sim.value().truth.accel, "accel"},
          std::tuple{&r.value().gyro, &sim.value().truth.gyro, "gyro"}}) {
      REQUIRE(cal->has_value());
      REQUIRE((*cal)->model_check);
      ++run.chosen[fmt::format("{} {}", name, ModelKindName((*cal)->model.kind))];
      if ((*cal)->model_check->model_rejected) {
        ++run.refused[name];
        continue;
      }
      Tally(**cal, *truth, name, &run);
    }
  }
  return run;
}

std::string Describe(const SimCase& c, const TagRun& run, int tags) {
  std::string line = fmt::format("{} ({} tags):", c.name, tags);
  for (const auto& [k, n] : run.chosen) line += fmt::format(" {} {},", k, n);
  for (const auto& [k, n] : run.refused) line += fmt::format(" {} refused {},", k, n);
  for (const auto& [k, v] : run.inside) {
    line += fmt::format(" {} {:.1f} % of {},", k, 100.0 * v.first / v.second, v.second);
  }
  if (!run.refusal.empty()) line += " first refusal: " + run.refusal;
  return line;
}

TEST_CASE("Model auto chooses the full model on tags with cross-axis terms, scale without",
          "[calibration][model]") {
  const int tags = 4;
  const SimCase with{"26 cube directions, accel +-1 %, gyro +-1.5 %"};
  TagRun w = RunTags(with, tags, 3600);
  INFO(Describe(with, w, tags));
  CHECK(w.chosen["accel full"] == tags);
  CHECK(w.chosen["gyro full"] == tags);
  SimCase without{"26 cube directions, no cross-axis terms"};
  without.accel_cross = without.gyro_cross = 0.0;
  TagRun wo = RunTags(without, tags, 3700);
  INFO(Describe(without, wo, tags));
  // Each comparison wrongly rejects the scale model 5 % of the time: of 2 x 4 choices, at most
  // one is full (probability of two or more 5.7 %, for a fixed seed a deterministic outcome).
  CHECK(wo.chosen["accel scale"] + wo.chosen["gyro scale"] >= 2 * tags - 1);
}

// Issue #36 point 3: a scale model the data reject, or an exact fit, on tags with realistic
// cross-axis terms. Before, the gyroscope's scale factors lay within 2u on 0-52 % of such tags
// and the accelerometer's constants with 6 orientations on 0-7 %; with the Type B term for the
// omitted terms (or model_rejected) they must lie within 2u on at least 92 % (issue #36 "Done
// when"). Pooled over axes and tags.
const std::vector<SimCase>& TypeBCases() {
  static const std::vector<SimCase> cases = [] {
    SimCase cube{"26 cube directions, --model scale"};
    cube.automatic = false;
    SimCase nine{"9 orientations, --model scale"};
    nine.poses = 9;
    nine.automatic = false;
    SimCase six{"6 faces x3, --model scale"};
    six.poses = 18;
    six.set = PoseSet::kFaces;
    six.automatic = false;
    SimCase six_auto{"6 faces x3, --model auto"};
    six_auto.poses = 18;
    six_auto.set = PoseSet::kFaces;
    return std::vector<SimCase>{cube, nine, six, six_auto};
  }();
  return cases;
}

void CheckTypeBCoverage(int tags, double min_rate) {
  uint64_t seed = 4100;
  for (const SimCase& c : TypeBCases()) {
    const TagRun run = RunTags(c, tags, seed);
    seed += 1000;
    const std::string line = Describe(c, run, tags);
    std::printf("%s\n", line.c_str());
    std::fflush(stdout);
    INFO(line);
    for (const auto& [key, counts] : run.inside) {
      INFO(key);
      CHECK(run.Rate(key) >= min_rate);
    }
  }
}

TEST_CASE("A rejected or exact scale model covers the truth with its cross-axis Type B",
          "[calibration][model]") {
  // 6 tags x 3 axes = 18 constants per class and sensor: at a true rate of 95 % at least 15
  // lie within 2u with probability 98.9 % (binomial); without the Type B, 0-52 % do.
  CheckTypeBCoverage(6, 15.0 / 18.0);
}

TEST_CASE("Coverage of the cross-axis Type B over 100 tags per case",
          "[.][coverage][calibration]") {
  // 100 tags x 3 axes: the floor 92 %. Prints docs/calibration-model.md's table.
  CheckTypeBCoverage(100, 0.92);
}

}  // namespace
}  // namespace metro
