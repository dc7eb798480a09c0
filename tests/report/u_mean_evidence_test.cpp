#include "metro/report/u_mean_evidence.hpp"

#include <catch2/catch.hpp>
#include <optional>
#include <string>

namespace metro {
namespace {

// One tag, one quantity with u_mean = 0.1 (n = 1001) and an Allan link predicting u_allan.
void Build(double u_allan, double u_u, SessionTypeA* s, SessionReport* report) {
  QuantityTypeA q;
  q.name = "gy_dps";
  q.ok = true;
  q.type_a.n = 1001;
  q.type_a.u_mean_available = true;
  q.type_a.u_mean = 0.1;
  q.type_a.u_mean_dof = 40.0;
  q.type_a.u_mean_method = kUMeanArSpectral;
  TagTypeA t;
  t.quantities.push_back(q);
  s->tags.push_back(t);
  QuantityReport jq;
  jq.name = "gy_dps";
  jq.type_a = TypeAReport{};
  jq.type_a->n = 1001;
  jq.type_a->u_mean = 0.1;
  jq.type_a->u_mean_dof = 40.0;
  jq.type_a->u_mean_method = kUMeanArSpectral;
  jq.type_a->u_mean_ar_order = 3;
  AllanTypeALink link;
  link.u_mean_allan = u_allan;
  link.u_u_mean_allan = u_u;
  link.dominant_term = "rate_random_walk";
  link.extrapolated = true;
  jq.allan_type_a_link = link;
  SensorReport sensor;
  sensor.quantities.push_back(jq);
  report->sensors.push_back(sensor);
}

TEST_CASE("Allan evidence more than 2x u_mean replaces it, dof by JCGM 100 G.4.2",
          "[report][u_mean]") {
  SessionTypeA s;
  SessionReport report;
  Build(0.9, 0.3, &s, &report);
  ApplyAllanEvidenceToUMean(&s, &report);
  const TypeAResult& a = s.tags[0].quantities[0].type_a;
  // nu = (1/2) (0.9 / 0.3)^2 = 4.5.
  CHECK(a.u_mean == 0.9);
  CHECK(a.u_mean_dof == Approx(4.5).epsilon(1e-14));
  CHECK(a.u_mean_method == std::string(kUMeanAllan));
  const QuantityReport& jq = *report.sensors[0].Find("gy_dps");
  CHECK(jq.type_a->u_mean == 0.9);
  CHECK(jq.type_a->u_mean_dof == Approx(4.5).epsilon(1e-14));
  CHECK(jq.type_a->u_mean_method == std::optional<std::string>(kUMeanAllan));
  CHECK(!jq.type_a->u_mean_ar_order.has_value());
  // U_mean follows the new u_mean and dof: t_0.975 at 4.5 dof lies between the table's
  // t_0.975(5) = 2.5706 and t_0.975(4) = 2.7764 (JCGM 100:2008 Table G.2).
  const double k = jq.type_a->k;
  CHECK(k > 2.5706);
  CHECK(k < 2.7764);
  CHECK(jq.type_a->coverage == 0.95);
  CHECK(jq.type_a->U_mean == Approx(k * 0.9).epsilon(1e-15));
  REQUIRE(jq.warnings.size() == 1);
  const std::string w = jq.warnings[0];
  CHECK(w.find("rate_random_walk") != std::string::npos);
  CHECK(w.find("9.0x") != std::string::npos);
  CHECK(s.tags[0].quantities[0].warnings.size() == 1);
}

TEST_CASE("Allan evidence within 2x u_mean leaves it alone", "[report][u_mean]") {
  SessionTypeA s;
  SessionReport report;
  Build(0.19, 0.05, &s, &report);
  ApplyAllanEvidenceToUMean(&s, &report);
  CHECK(s.tags[0].quantities[0].type_a.u_mean == 0.1);
  CHECK(s.tags[0].quantities[0].type_a.u_mean_method == std::string(kUMeanArSpectral));
  CHECK(report.sensors[0].Find("gy_dps")->warnings.empty());
  CHECK(report.sensors[0].Find("gy_dps")->type_a->u_mean == 0.1);
}

TEST_CASE("A rejected or untested noise model never replaces u_mean (issue #36)",
          "[report][u_mean]") {
  for (const char* status : {"rejected", "untested"}) {
    INFO(status);
    SessionTypeA s;
    SessionReport report;
    Build(0.9, 0.3, &s, &report);
    QuantityReport& jq = *report.sensors[0].Find("gy_dps");
    jq.allan_type_a_link->noise_model = status;
    AllanReport allan;
    allan.estimator = "oadev";
    AllanModelCheckReport check;
    check.tested = std::string(status) == "rejected";
    check.rejected = check.tested;
    check.chi2 = 412.0;
    check.dof = 13;
    check.p_value = 1e-60;
    allan.model_check = check;
    jq.allan = allan;
    ApplyAllanEvidenceToUMean(&s, &report);
    // u_mean stays the Type A value from the data alone, with its method.
    const TypeAResult& a = s.tags[0].quantities[0].type_a;
    CHECK(a.u_mean == 0.1);
    CHECK(a.u_mean_method == std::string(kUMeanArSpectral));
    CHECK(jq.type_a->u_mean == 0.1);
    CHECK(jq.type_a->u_mean_ar_order == std::optional<int64_t>(3));
    REQUIRE(jq.warnings.size() == 1);
    const std::string& w = jq.warnings[0];
    CHECK(w.find("9.0x") != std::string::npos);
    CHECK(w.find("u_mean stays the Type A value from the data alone") != std::string::npos);
    if (check.tested) {
      CHECK(w.find("rejected by the Allan curve (chi2 = 412 at 13 dof, p = 1e-60") !=
            std::string::npos);
    } else {
      CHECK(w.find("could not be tested") != std::string::npos);
    }
  }
  // A model that holds still replaces it.
  SessionTypeA s;
  SessionReport report;
  Build(0.9, 0.3, &s, &report);
  report.sensors[0].Find("gy_dps")->allan_type_a_link->noise_model = "holds";
  ApplyAllanEvidenceToUMean(&s, &report);
  CHECK(s.tags[0].quantities[0].type_a.u_mean == 0.9);
}

}  // namespace
}  // namespace metro
