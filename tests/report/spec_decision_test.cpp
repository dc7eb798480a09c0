// Noise terms judged against datasheet figures (issue #40 step 5): typ figures give a ratio
// and E_n only, max figures a JCGM 106 decision; every number derived here by closed form.
#include "metro/report/spec_decision.hpp"

#include <catch2/catch.hpp>
#include <cmath>
#include <string>

namespace metro {
namespace {

// One gyroscope axis in deg/s: N = 0.004 deg/s*sqrt(s) (u 1e-4), Allan minimum 0.002 deg/s
// with a 68.3 % interval [0.0018, 0.0022] at tau 100 s, K not supported.
NoiseExportInput Record() {
  NoiseExportAxis a;
  a.quantity = "gx_dps";
  a.unit = "deg/s";
  AllanReport& r = a.allan;
  r.tau_s = {1.0, 100.0, 1000.0};
  r.adev = {0.004, 0.002, 0.003};
  r.ci_low = {0.0039, 0.0018, 0.0025};
  r.ci_high = {0.0041, 0.0022, 0.0035};
  r.confidence = 0.683;
  AllanNoiseTermReport& n = r.noise[static_cast<size_t>(NoiseTerm::kRandomWalk)];
  n.value = 0.004;
  n.u = 1e-4;
  n.supported = true;
  NoiseExportInput in;
  in.source = "test";
  in.axes.push_back(a);
  return in;
}

SpecPart Part(const std::string& n_kind, const std::string& b_kind) {
  const std::string text = R"j({"schema": "metro.specs/1", "parts": [{"part": "X1", "names": [],
  "manufacturer": "m", "documents": [{"id": "ds", "title": "t", "number": "DS-1",
  "revision": "2", "read_at": "here"}], "figures": [
  {"source": "ds", "sensor": "gyroscope", "convention": "one_sided_density", "kind": ")j" +
                           n_kind + R"j(", "value": 0.006, "unit": "deg/s/sqrt(Hz)",
   "printed": "0.006", "page": "3", "table": "T1"},
  {"source": "ds", "sensor": "gyroscope", "convention": "allan_minimum", "kind": ")j" +
                           b_kind +
                           R"j(", "value": 10, "unit": "deg/h", "printed": "10 °/hr", "page": "3",
   "table": "T1"}]}]})j";
  Result<SpecLibrary> lib = ParseSpecLibrary(text, "test.json");
  REQUIRE(lib.ok());
  return lib.value().parts.front();
}

double Phi(double x) { return 0.5 * std::erfc(-x / std::sqrt(2.0)); }

TEST_CASE("a typ figure gives ratio and E_n, never a decision", "[specs]") {
  Result<SpecDecisions> d = DecideAgainstSpec(Record(), Part("typ", "typ"), "test.json", {});
  REQUIRE(d.ok());
  REQUIRE(d.value().rows.size() == 3);  // N, B, and K without a figure.
  const SpecDecisionRow& n = d.value().rows[0];
  // One-sided density sqrt(2) N, in deg/s/sqrt(Hz) (the report's unit already).
  const double measured = std::sqrt(2.0) * 0.004, u = std::sqrt(2.0) * 1e-4;
  CHECK(n.measured == Approx(measured).epsilon(1e-14));
  CHECK(n.u == Approx(u).epsilon(1e-14));
  CHECK(n.ratio == Approx(measured / 0.006).epsilon(1e-14));
  CHECK(n.e_n == Approx((measured - 0.006) / (2.0 * u)).epsilon(1e-12));
  CHECK_FALSE(n.conformity);
  CHECK_THAT(n.note, Catch::Contains("typ is not a specification limit"));
  // B: the Allan minimum 0.002 deg/s = 7.2 deg/h; u from the 68.3 % interval, z =
  // Phi^-1((1 + 0.683)/2) = 1.0006418287624492 (Python statistics.NormalDist).
  const SpecDecisionRow& b = d.value().rows[1];
  CHECK(b.measured == Approx(7.2).epsilon(1e-12));
  CHECK(b.u == Approx(0.0002 * 3600.0 / 1.0006418287624492).epsilon(1e-9));
  CHECK(b.ratio == Approx(0.72).epsilon(1e-12));
  const SpecDecisionRow& k = d.value().rows[2];
  CHECK_FALSE(k.figure);
  CHECK_THAT(k.note, Catch::Contains("gyroscope K: the datasheet gives no figure"));
  CHECK_THAT(SpecDecisionsTable(d.value()), Catch::Contains("typ/unstated figures are not"));
}

TEST_CASE("a max figure is a limit: JCGM 106 guarded decision with p_c", "[specs]") {
  Result<SpecDecisions> d = DecideAgainstSpec(Record(), Part("max", "max"), "test.json", {});
  REQUIRE(d.ok());
  const SpecDecisionRow& n = d.value().rows[0];
  REQUIRE(n.conformity);
  const double measured = std::sqrt(2.0) * 0.004, u = std::sqrt(2.0) * 1e-4;
  // p_c = Phi((T_U - y)/u) (JCGM 106 7.3); guarded: y <= T_U - 2u passes.
  CHECK(n.conformity->p_conformance == Approx(Phi((0.006 - measured) / u)).epsilon(1e-10));
  CHECK(measured <= 0.006 - 2.0 * u);
  CHECK(n.conformity->decision == ConformityDecision::kPass);
  // B: 7.2 deg/h against max 10 deg/h with u ~0.72: 7.2 + 2u = 8.64 <= 10: pass.
  CHECK(d.value().rows[1].conformity->decision == ConformityDecision::kPass);
  // The same value against a tighter limit: 0.0058 - 2u < y <= 0.0058 is inconclusive.
  SpecPart tight = Part("max", "max");
  tight.figures[0].value = 0.0058;
  Result<SpecDecisions> t = DecideAgainstSpec(Record(), tight, "test.json", {});
  REQUIRE(t.ok());
  CHECK(t.value().rows[0].conformity->decision == ConformityDecision::kInconclusive);
  tight.figures[0].value = 0.005;  // y > T_U: fail.
  t = DecideAgainstSpec(Record(), tight, "test.json", {});
  CHECK(t.value().rows[0].conformity->decision == ConformityDecision::kFail);
}

TEST_CASE("raw LSB columns beside scaled ones are skipped, alone refused", "[specs]") {
  NoiseExportInput in = Record();
  NoiseExportAxis raw = in.axes.front();
  raw.quantity = "gx_lsb";
  raw.unit = "LSB";
  in.axes.insert(in.axes.begin(), raw);
  Result<SpecDecisions> d = DecideAgainstSpec(in, Part("typ", "typ"), "test.json", {});
  REQUIRE(d.ok());
  REQUIRE(d.value().rows.size() == 3);
  CHECK(d.value().rows[0].quantity == "gx_dps");
  in.axes.pop_back();  // Only the LSB column left.
  d = DecideAgainstSpec(in, Part("typ", "typ"), "test.json", {});
  REQUIRE_FALSE(d.ok());
  CHECK_THAT(d.error().message,
             Catch::Contains("gx_lsb is in LSB: a datasheet figure needs an SI scale (rad/s)"));
}

TEST_CASE("a part with only published configurations is not a datasheet", "[specs]") {
  SpecPart p = Part("typ", "typ");
  for (SpecFigure& f : p.figures) f.kind = SpecKind::kConfig;
  Result<SpecDecisions> d = DecideAgainstSpec(Record(), p, "test.json", {});
  REQUIRE_FALSE(d.ok());
  CHECK_THAT(d.error().message, Catch::Contains("no datasheet figure of X1"));
}

}  // namespace
}  // namespace metro
