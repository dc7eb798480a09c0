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
#include "metro/sim/calibration_session.hpp"

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
  bool gyro = true;  // False: the accelerometer alone (--accel-only).
  double dwell_s = 2.0;
  double tilt_deg = 0.0;  // SimulationOptions::pose_tilt_deg
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
    so.dwell_s = c.dwell_s;
    so.move_s = 1.5;
    so.pose_tilt_deg = c.tilt_deg;
    so.accel_cross_axis = c.accel_cross;
    so.gyro_cross_axis = c.gyro_cross;
    Result<SimulatedSession> sim = SimulateCalibrationSession(so);
    REQUIRE(sim.ok());
    CalibrationOptions o;
    o.accel_auto = o.gyro_auto = c.automatic;
    o.compare_models = true;
    o.accel_model = o.gyro_model = c.model;
    o.fit_gyro = c.gyro;
    Result<TagCalibration> r = CalibrateTag({&sim.value().session.tags.front()}, o);
    if (!r.ok() && r.error().message.find("degenerate calibration") != std::string::npos) {
      ++run.refused["fit (degenerate)"];  // No constants at all: nothing to cover.
      if (run.refusal.empty()) run.refusal = r.error().message;
      continue;
    }
    if (!r.ok() && r.error().kind == ErrorKind::kInput &&
        r.error().message.find("hand rotations") != std::string::npos) {
      ++run.refused["fit (too few rotations)"];  // Refused, saying what to record.
      if (run.refusal.empty()) run.refusal = r.error().message;
      continue;
    }
    if (!r.ok()) FAIL(c.name << " tag " << tag << ": " << r.error().ToString());
    for (const auto& [cal, truth, name] :
         {std::tuple{&r.value().accel, &sim.value().truth.accel, "accel"},
          std::tuple{&r.value().gyro, &sim.value().truth.gyro, "gyro"}}) {
      if (!c.gyro && std::string(name) == "gyro") continue;
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

// Issue #36 "Done when": exactly 6 axis-aligned orientations (+x, -x, +y, -y, +z, -z, one stop
// each: the common 6-position protocol) on tags with realistic cross-axis terms (accelerometer
// +-1 %, gyroscope +-1.5 %). The scale model is then an exact fit (6 parameters, 6 gravity-norm
// equations): nothing tests it, its u gets the cross-axis Type B. Each constant class, pooled
// over tags and axes, must lie within 2u at the rate given, or the constants be marked
// model_rejected (refused by blob and push) or the fit refused.
const std::vector<SimCase>& SixFaceCases() {
  static const std::vector<SimCase> cases = [] {
    SimCase scale{"6 faces once, --model scale"};
    scale.poses = 6;
    scale.set = PoseSet::kFaces;
    scale.automatic = false;
    SimCase automatic{"6 faces once, --model auto"};
    automatic.poses = 6;
    automatic.set = PoseSet::kFaces;
    // The accelerometer alone: every tag's constants (with the gyroscope, a fit that five
    // rotations cannot determine is refused as a whole).
    SimCase accel_scale = scale;
    accel_scale.name = "6 faces once, accelerometer only, --model scale";
    accel_scale.gyro = false;
    SimCase accel_auto = automatic;
    accel_auto.name = "6 faces once, accelerometer only, --model auto";
    accel_auto.gyro = false;
    SimCase tilted = accel_scale;
    tilted.name = "6 faces once tilted up to 3 deg, accelerometer only, --model scale";
    tilted.tilt_deg = 3.0;
    SimCase tilted_auto = accel_auto;
    tilted_auto.name = "6 faces once tilted up to 3 deg, accelerometer only, --model auto";
    tilted_auto.tilt_deg = 3.0;
    SimCase long_dwell = accel_scale;
    long_dwell.name = "6 faces once, 30 s each, accelerometer only, --model scale";
    long_dwell.dwell_s = 30.0;
    SimCase long_tilted = tilted;
    long_tilted.name =
        "6 faces once tilted up to 3 deg, 30 s each, accelerometer only, --model scale";
    long_tilted.dwell_s = 30.0;
    return std::vector<SimCase>{scale,  automatic,   accel_scale, accel_auto,
                                tilted, tilted_auto, long_dwell,  long_tilted};
  }();
  return cases;
}

void CheckSixFaceCoverage(int tags, double min_rate) {
  uint64_t seed = 9100;
  for (const SimCase& c : SixFaceCases()) {
    const TagRun run = RunTags(c, tags, seed);
    seed += 1000;
    const std::string line = Describe(c, run, tags);
    std::printf("%s\n", line.c_str());
    std::fflush(stdout);
    INFO(line);
    // Every tag gave constants (covered or marked model_rejected) or was refused as a whole.
    int sensors = 0, refused = 0;
    for (const auto& [key, n] : run.chosen) sensors += n;
    for (const auto& [key, n] : run.refused) refused += key.rfind("fit", 0) == 0 ? n : 0;
    const int per_tag = c.gyro ? 2 : 1;
    CHECK(sensors + per_tag * refused == per_tag * tags);
    for (const auto& [key, counts] : run.inside) {
      INFO(key);
      CHECK(run.Rate(key) >= min_rate);
    }
  }
}

TEST_CASE("Six axis-aligned orientations with cross-axis terms: constants within 2u",
          "[calibration][model]") {
  // 20 tags x 3 axes = 60 constants per class and sensor: at a true 95 % at least 53 lie within
  // 2u with probability 98.9 % (binomial); the issue measured 0-7 % before the Type B.
  CheckSixFaceCoverage(20, 53.0 / 60.0);
}

TEST_CASE("Six axis-aligned orientations: coverage over 100 tags per case",
          "[.][coverage][calibration]") {
  // 100 tags x 3 axes: the floor 92 %. Prints docs/calibration-model.md's rows.
  CheckSixFaceCoverage(100, 0.92);
}

// Issue #36 "Done when": --model auto chooses the full model on tags with cross-axis terms and
// the scale model on tags without, at the usual pose counts (the simulator's cube: the 6 faces,
// then the 8 corners, then the 12 edges). Counts per sensor; a comparison rejects a true scale
// model at its 5 % level, so of the choices without cross-axis terms at most a few are full.
struct ChoiceCounts {
  int tags = 0;
  std::map<std::string, int> chosen;  // "accel full" -> tags, from TagRun
  std::map<std::string, int> marked;  // "accel" -> tags whose constants are model_rejected
  int refused = 0;                    // Fits refused as a whole (degenerate).
  int Chosen(const std::string& key) const {
    const auto it = chosen.find(key);
    return it == chosen.end() ? 0 : it->second;
  }
  int Marked(const std::string& key) const {
    const auto it = marked.find(key);
    return it == marked.end() ? 0 : it->second;
  }
};

ChoiceCounts CountChoices(int poses, double accel_cross, double gyro_cross, int tags,
                          uint64_t seed) {
  SimCase c{"auto"};
  c.poses = poses;
  c.accel_cross = accel_cross;
  c.gyro_cross = gyro_cross;
  const TagRun run = RunTags(c, tags, seed);
  ChoiceCounts out;
  out.tags = tags;
  out.chosen = run.chosen;
  for (const auto& [key, n] : run.refused) {
    if (key.rfind("fit", 0) == 0) {
      out.refused += n;
    } else {
      out.marked[key] = n;
    }
  }
  return out;
}

// `max_missed_full`: tags with cross-axis terms on which a sensor may keep the scale model (drawn
// uniform in +-1 % / +-1.5 %, some tags' terms are too small for their poses to show);
// `max_false_full`: tags without them on which a sensor may take the full model.
void CheckAutoChoices(const std::vector<int>& pose_counts, int tags, int max_missed_full,
                      int max_false_full) {
  uint64_t seed = 12000;
  for (int poses : pose_counts) {
    const ChoiceCounts w = CountChoices(poses, 0.01, 0.015, tags, seed);
    const ChoiceCounts wo = CountChoices(poses, 0.0, 0.0, tags, seed + 500);
    seed += 1000;
    const std::string line = fmt::format(
        "{} poses, {} tags: with cross-axis terms accel full {} scale {} (model_rejected {}), "
        "gyro full {} scale {} (model_rejected {}), fits refused {}; without: accel full {} "
        "scale {} (model_rejected {}), gyro full {} scale {} (model_rejected {}), fits refused "
        "{}",
        poses, tags, w.Chosen("accel full"), w.Chosen("accel scale"), w.Marked("accel"),
        w.Chosen("gyro full"), w.Chosen("gyro scale"), w.Marked("gyro"), w.refused,
        wo.Chosen("accel full"), wo.Chosen("accel scale"), wo.Marked("accel"),
        wo.Chosen("gyro full"), wo.Chosen("gyro scale"), wo.Marked("gyro"), wo.refused);
    std::printf("%s\n", line.c_str());
    std::fflush(stdout);
    INFO(line);
    CHECK(w.refused == 0);
    CHECK(wo.refused == 0);
    CHECK(w.Chosen("accel full") >= tags - max_missed_full);
    CHECK(w.Chosen("gyro full") >= tags - max_missed_full);
    CHECK(wo.Chosen("accel scale") >= tags - max_false_full);
    CHECK(wo.Chosen("gyro scale") >= tags - max_false_full);
  }
}

TEST_CASE("Model auto at 9 to 26 orientations: full with cross-axis terms, scale without",
          "[calibration][model]") {
  // 5 tags per pose count and truth: every tag with cross-axis terms full; without, at most one
  // full per sensor and pose count (5 % each: two or more of 5 with probability 2.3 %).
  CheckAutoChoices({9, 12, 18, 26}, 5, 0, 1);
}

TEST_CASE("Model auto choices over 100 tags per pose count", "[.][coverage][calibration]") {
  // 5 % of 100 choices is 5 (standard deviation 2.2): at most 10 full without cross-axis terms
  // (11 or more with probability 1.1 % per sensor and pose count; the gyroscope's comparison
  // on the weighted fit's residuals took 11 at 9 orientations); with them, at most 3 of 100
  // tags keep the scale model. Prints docs/calibration-model.md's table.
  CheckAutoChoices({9, 12, 18, 26}, 100, 3, 10);
}

}  // namespace
}  // namespace metro
