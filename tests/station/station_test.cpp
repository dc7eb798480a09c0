// The station's guide against simulated operators with known truth (issue #44): protocols,
// dwell, acceptance and rejection, the live u and the stop rule, the final fit.
#include "metro/station/station.hpp"

#include <Eigen/Geometry>
#include <catch2/catch.hpp>
#include <cmath>
#include <map>
#include <pcg_random.hpp>
#include <random>

#include "metro/calibration/named_constants.hpp"
#include "station/simulated_operator.hpp"

using namespace metro;
using namespace metro::station;
using metro::station_test::OperatorRun;
using metro::station_test::OperatorScript;
using metro::station_test::RunOperator;

namespace {

StationOptions Options() {
  StationOptions o;
  o.rate_hz = 100;
  return o;
}

int Count(const OperatorRun& run, StationEventKind kind) {
  return static_cast<int>(std::count_if(run.events.begin(), run.events.end(),
                                        [&](const StationEvent& e) { return e.kind == kind; }));
}

const StationEvent* Last(const OperatorRun& run, StationEventKind kind) {
  for (auto it = run.events.rbegin(); it != run.events.rend(); ++it) {
    if (it->kind == kind) return &*it;
  }
  return nullptr;
}

// The truth as a TagCalibration, so that NamedConstants names its values as the fit's.
TagCalibration TruthTag(const ImuTruth& truth, int sensor) {
  TagCalibration t;
  t.sensor = sensor;
  SensorCalibration a, g;
  a.model = truth.accel;
  g.model = truth.gyro;
  a.covariance = Eigen::MatrixXd::Zero(9, 9);
  g.covariance = Eigen::MatrixXd::Zero(12, 12);
  t.accel = a;
  t.gyro = g;
  return t;
}

}  // namespace

TEST_CASE("Six-face asks for the faces first, then the farthest orientation", "[station]") {
  const auto poses = ProtocolPoses(Protocol::kSixFace);
  REQUIRE(poses.size() == 26);
  std::vector<Eigen::Vector3d> taken;
  for (int i = 0; i < 6; ++i) {
    const int next = ChooseNextPose(Protocol::kSixFace, poses, taken, 20);
    REQUIRE(next >= 0);
    CHECK(poses[static_cast<size_t>(next)].face);
    taken.push_back(poses[static_cast<size_t>(next)].up_body);
  }
  // After the faces every corner is 54.7 deg from the nearest face, every edge 45 deg: a corner.
  const int next = ChooseNextPose(Protocol::kSixFace, poses, taken, 20);
  CHECK(poses[static_cast<size_t>(next)].name.rfind("corner", 0) == 0);
  for (const auto& p : poses) taken.push_back(p.up_body);
  CHECK(ChooseNextPose(Protocol::kSixFace, poses, taken, 20) == -1);
  CHECK(NearestWithin({Eigen::Vector3d::UnitZ()}, Eigen::Vector3d(0, 0.2, 1).normalized(), 20) ==
        0);
  CHECK(AngleDeg(Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY()) == Approx(90));
}

TEST_CASE("The turn instruction turns the body to the pose asked for", "[station]") {
  CHECK(TurnInstruction(Eigen::Vector3d::UnitZ(), Eigen::Vector3d::UnitX()) ==
        "turn 90 deg about body -Y (right-hand)");
  CHECK(TurnInstruction(Eigen::Vector3d::UnitZ(), -Eigen::Vector3d::UnitZ()).find("turn 180") == 0);
  // Independently: the body rotation R (body frame) must bring world up to the new body
  // direction, R^T from = to, for the axis and angle the text states.
  const Eigen::Matrix3d r =
      Eigen::AngleAxisd(-M_PI / 2, Eigen::Vector3d::UnitY()).toRotationMatrix();
  CHECK((r.transpose() * Eigen::Vector3d::UnitZ() - Eigen::Vector3d::UnitX()).norm() < 1e-12);
}

TEST_CASE("The dwell follows the noise: n = s^2 / (f T)^2 for white noise", "[station]") {
  pcg64 rng(5);
  std::normal_distribution<double> normal(0.0, 1.0);
  StationOptions o = Options();
  o.target_u_accel_mg = 0.2;
  o.dwell_fraction = 0.5;
  o.max_dwell_s = 100;
  const double sd_lsb = 46.0;  // 2.8 mg at 16384 LSB/g.
  std::vector<Eigen::Vector3d> a, g;
  for (int i = 0; i < 4000; ++i) {
    a.emplace_back(sd_lsb * normal(rng), sd_lsb * normal(rng), 16384 + sd_lsb * normal(rng));
    g.emplace_back(std::round(normal(rng)), std::round(normal(rng)), std::round(normal(rng)));
  }
  // Goal 0.1 mg = 1.6384 LSB: n = (46 / 1.6384)^2 = 788 (the largest of three axes' estimates).
  const double expected = std::pow(sd_lsb / 1.6384, 2);
  CHECK(static_cast<double>(DwellNeeded(a, g, o)) == Approx(expected).epsilon(0.12));
  o.target_u_accel_mg = 2.0;  // n = 7.9: the minimum dwell rules.
  CHECK(DwellNeeded(a, g, o) == static_cast<int64_t>(o.min_dwell_s * o.rate_hz));
}

TEST_CASE("A guided session ends with every target met and the same fit's constants", "[station]") {
  RawTagOptions to;
  to.seed = 41;
  SimulatedRawTag tag(to);
  Station st(Options(), "simulated");
  OperatorScript script;
  script.seed = 7;
  script.short_hold_rate = 0;
  script.knock_rate = 0;
  script.skip_face_rate = 0;
  script.reseat_rate = 0;
  const OperatorRun run = RunOperator(script, &tag, &st);
  REQUIRE(st.Done());
  CHECK(st.TargetsMet());
  const StationEvent* stop = Last(run, StationEventKind::kStopped);
  REQUIRE(stop != nullptr);
  CHECK_THAT(stop->reason, Catch::Contains("every target met"));
  CHECK(Count(run, StationEventKind::kPoseAccepted) >= MinOrientations(ModelKind::kFull));
  CHECK(Count(run, StationEventKind::kPoseRejected) == 0);
  // The first 6 accepted poses are the six faces.
  int faces = 0, seen = 0;
  for (const StationEvent& e : run.events) {
    if (e.kind != StationEventKind::kPoseAccepted || ++seen > 6) continue;
    faces += e.pose_name.rfind("corner", 0) != 0 && e.pose_name.rfind("edge", 0) != 0 ? 1 : 0;
  }
  CHECK(faces == 6);
  Result<Calibration> cal = st.FitCalibration();
  REQUIRE(cal.ok());
  const TagCalibration& t = cal.value().tags.front();
  // The final u is the last live u (the same data, the same fit).
  const std::vector<ConstantU> u = ConstantUncertainties(t, Options());
  REQUIRE(u.size() == stop->u.size());
  for (size_t i = 0; i < u.size(); ++i) {
    CHECK(u[i].name == stop->u[i].name);
    CHECK(u[i].u == Approx(stop->u[i].u).epsilon(1e-6));
    CHECK(u[i].met);
  }
}

TEST_CASE("A knock is rejected and the pose repeated; a re-seat is too close", "[station]") {
  RawTagOptions to;
  to.seed = 42;
  SimulatedRawTag tag(to);
  Station st(Options(), "simulated");
  std::vector<RawTagSample> buf;
  OperatorRun run;
  tag.Hold(2.5, &buf);
  tag.Move(Eigen::Vector3d::UnitX(), 1.5, &buf);
  tag.Hold(0.8, &buf);
  tag.Knock(0.6, &buf);
  tag.Hold(2.5, &buf);
  tag.Reseat(1.2, &buf);
  tag.Hold(2.0, &buf);
  tag.Move(Eigen::Vector3d::UnitY(), 1.5, &buf);
  tag.Hold(2.5, &buf);
  tag.Move(-Eigen::Vector3d::UnitY(), 1.5, &buf);
  station_test::FeedSamples(buf, &st, &run);
  std::vector<std::string> seq;
  for (const StationEvent& e : run.events) {
    if (e.kind == StationEventKind::kPoseAccepted || e.kind == StationEventKind::kPoseRejected ||
        e.kind == StationEventKind::kTooClose) {
      seq.push_back(std::string(StationEventKindName(e.kind)) + " " + e.pose_name);
    }
  }
  INFO(Catch::Detail::stringify(seq));
  REQUIRE(seq.size() == 5);
  CHECK(seq[0] == "pose_accepted Z up");
  CHECK(seq[1] == "pose_rejected X up");
  CHECK(seq[2] == "pose_accepted X up");
  CHECK(seq[3] == "too_close X up");
  CHECK(seq[4] == "pose_accepted Y up");
  const StationEvent* rejected = Last(run, StationEventKind::kPoseRejected);
  CHECK_THAT(rejected->reason, Catch::Contains("disturbed after 0."));
  CHECK_THAT(rejected->reason, Catch::Contains("nothing of it is averaged in"));
  const StationEvent* close = Last(run, StationEventKind::kTooClose);
  CHECK_THAT(close->reason, Catch::Contains("from pose 2 (X up)"));
  // The accepted X-up pose starts after the knock: none of the knocked hold is in it.
  const auto segments = st.Segments();
  REQUIRE(segments.size() == 3);
  CHECK(segments[1].start_s >= 2.5 + 1.5 + 0.8 + 0.08 - 1e-9);
}

TEST_CASE("A saturated sample in a hold makes the pose unusable and says so", "[station]") {
  RawTagOptions to;
  to.seed = 43;
  SimulatedRawTag tag(to);
  Station st(Options(), "simulated");
  std::vector<RawTagSample> buf;
  tag.Hold(1.0, &buf);
  buf[60].counts[2] = 32767;  // A clipped az inside the still period.
  tag.Move(Eigen::Vector3d::UnitX(), 1.5, &buf);
  OperatorRun run;
  station_test::FeedSamples(buf, &st, &run);
  const StationEvent* rejected = Last(run, StationEventKind::kPoseRejected);
  REQUIRE(rejected != nullptr);
  CHECK_THAT(rejected->reason, Catch::Contains("saturated"));
  CHECK_THAT(rejected->reason, Catch::Contains("line 61"));
  CHECK(st.AcceptedPoses() == 0);
}

TEST_CASE("A lost stream keeps the poses taken and resumes in a new record", "[station]") {
  RawTagOptions to;
  to.seed = 44;
  SimulatedRawTag tag(to);
  Station st(Options(), "simulated");
  OperatorScript script;
  script.seed = 9;
  script.short_hold_rate = script.knock_rate = script.skip_face_rate = script.reseat_rate = 0;
  script.max_actions = 4;  // Four poses, then the port disappears.
  OperatorRun first = RunOperator(script, &tag, &st);
  const int before = st.AcceptedPoses();
  CHECK(before >= 3);
  const auto gap = st.Gap("the port disappeared");
  REQUIRE(gap.size() == 1);
  CHECK_THAT(EventText(gap[0]), Catch::Contains("poses taken are kept"));
  script.max_actions = 120;
  OperatorRun second = RunOperator(script, &tag, &st);
  REQUIRE(st.Done());
  CHECK(st.TargetsMet());
  CHECK(st.Sessions().size() == 2);
  Result<Calibration> cal = st.FitCalibration();
  REQUIRE(cal.ok());
  CHECK(cal.value().inputs.size() == 2);
}

TEST_CASE("Targets the protocol cannot reach stop it and name the constant and why", "[station]") {
  RawTagOptions to;
  to.seed = 45;
  SimulatedRawTag tag(to);
  StationOptions o = Options();
  o.target_u_accel_mg = 0.01;  // Far below what 26 poses of 2 s give at 2.8 mg per sample.
  o.max_dwell_s = 2.0;
  Station st(o, "simulated");
  OperatorScript script;
  script.seed = 11;
  script.short_hold_rate = script.knock_rate = script.skip_face_rate = script.reseat_rate = 0;
  const OperatorRun run = RunOperator(script, &tag, &st);
  REQUIRE(st.Done());
  CHECK_FALSE(st.TargetsMet());
  CHECK(st.AcceptedPoses() == 26);
  const StationEvent* stop = Last(run, StationEventKind::kStopped);
  REQUIRE(stop != nullptr);
  CHECK_THAT(stop->reason, Catch::Contains("the six-face protocol is complete (26 poses)"));
  CHECK_THAT(stop->reason, Catch::Contains("accel.b_x u "));
  CHECK_THAT(stop->reason, Catch::Contains("> target 0.01 mg"));
  CHECK_THAT(EventJson(*stop), Catch::Contains("\"targets_met\":false"));
  CHECK(st.FitCalibration().ok());  // What was taken still fits.
}

// Issue #44's done-when: over 200 simulated operator sessions (random face order, 10 % holds
// too short, 5 % knocks, some skipped faces and re-seats; the bundled session's noise), at
// least 95 % end with every constant within its target u on the first run; every constant is
// within 2u of the truth in 95 +- 3 % of the fits (pooled over constants: 200 x 21 trials);
// no session ends with a refusal (the final fit succeeds in every one).
TEST_CASE("Station done-when over 200 simulated operator sessions", "[station][slow]") {
  int met = 0, fitted = 0, inside = 0, trials = 0, short_holds = 0, knocks = 0, rejected = 0;
  std::map<std::string, std::pair<int, int>> per_class;
  std::vector<std::string> failures;
  for (int s = 0; s < 200; ++s) {
    RawTagOptions to;
    to.seed = 5000 + static_cast<uint64_t>(s);
    SimulatedRawTag tag(to);
    Station st(Options(), "simulated");
    OperatorScript script;
    script.seed = 9000 + static_cast<uint64_t>(s);
    const OperatorRun run = RunOperator(script, &tag, &st);
    short_holds += run.short_holds;
    knocks += run.knocks;
    rejected += Count(run, StationEventKind::kPoseRejected);
    met += st.Done() && st.TargetsMet() ? 1 : 0;
    Result<Calibration> cal = st.FitCalibration();
    if (!cal.ok()) {
      failures.push_back(cal.error().ToString());
      continue;
    }
    ++fitted;
    const TagCalibration& t = cal.value().tags.front();
    const std::vector<NamedConstant> fit = NamedConstants(t);
    const std::vector<NamedConstant> truth = NamedConstants(TruthTag(tag.Truth(), 1));
    REQUIRE(fit.size() == truth.size());
    for (size_t i = 0; i < fit.size(); ++i) {
      REQUIRE(fit[i].name == truth[i].name);
      const bool in = std::abs(fit[i].value - truth[i].value) <= 2.0 * fit[i].u;
      inside += in ? 1 : 0;
      ++trials;
      const std::string cls = fit[i].name.substr(0, fit[i].name.find('.') + 2);
      per_class[cls].first += in ? 1 : 0;
      ++per_class[cls].second;
    }
  }
  const double rate = static_cast<double>(inside) / trials;
  std::printf(
      "station: %d of 200 met every target, %d fitted, within 2u %.1f %% of %d; %d short "
      "holds, %d knocks, %d rejections\n",
      met, fitted, 100 * rate, trials, short_holds, knocks, rejected);
  for (const auto& [cls, c] : per_class) {
    std::printf("  %s within 2u %.1f %% of %d\n", cls.c_str(), 100.0 * c.first / c.second,
                c.second);
  }
  INFO(Catch::Detail::stringify(failures));
  CHECK(failures.empty());
  CHECK(met >= 190);
  CHECK(rate >= 0.92);
  CHECK(rate <= 0.98);
  CHECK(short_holds > 0);
  CHECK(knocks > 0);
}

TEST_CASE("The sphere and Ferraris protocols guide to every target met", "[station]") {
  for (Protocol p : {Protocol::kSphere, Protocol::kFerraris}) {
    RawTagOptions to;
    to.seed = 46;
    SimulatedRawTag tag(to);
    StationOptions o = Options();
    o.protocol = p;
    Station st(o, "simulated");
    OperatorScript script;
    script.seed = 12;
    const OperatorRun run = RunOperator(script, &tag, &st);
    INFO(ProtocolName(p));
    REQUIRE(st.Done());
    CHECK(st.TargetsMet());
    CHECK(st.FitCalibration().ok());
  }
  // Ferraris names the faces in its fixed order and the turn between them.
  const auto poses = ProtocolPoses(Protocol::kFerraris);
  CHECK(poses[0].name == "Z up");
  CHECK(poses[1].name == "X up");
  CHECK(TurnInstruction(poses[0].up_body, poses[1].up_body) ==
        "turn 90 deg about body -Y (right-hand)");
  std::vector<Eigen::Vector3d> taken = {poses[0].up_body};
  CHECK(ChooseNextPose(Protocol::kFerraris, poses, taken, 20) == 1);
}

TEST_CASE("The view shows the next pose, the hold and the coverage", "[station]") {
  RawTagOptions to;
  to.seed = 47;
  SimulatedRawTag tag(to);
  Station st(Options(), "simulated");
  std::vector<RawTagSample> buf;
  OperatorRun run;
  tag.Hold(2.5, &buf);
  tag.Move(Eigen::Vector3d::UnitX(), 1.5, &buf);
  tag.Hold(0.9, &buf);
  station_test::FeedSamples(buf, &st, &run);
  const StationView v = st.View();
  CHECK(v.holding);
  CHECK(v.held_s > 0.3);
  CHECK(v.dwell_s >= 1.5);
  CHECK(v.taken.size() == 1);
  CHECK(v.next_pose == "Z down");  // The first face not taken (X up is being held).
  const std::string text = RenderStationView(v, "title", false);
  CHECK_THAT(text, Catch::Contains("Next pose: Z down"));
  CHECK_THAT(text, Catch::Contains("s left"));
  CHECK_THAT(text, Catch::Contains("needs 9 more distinct orientations"));
  // The map: Z up taken at the north pole, the next pose (Z down) at the south pole.
  const auto map = CoverageMap(v, 9, 37);
  CHECK(map.front()[18] == '#');
  CHECK(map.back()[18] == '@');
}
