// Report rendering and the JCGM 100 7.2.6 rounding of the statement.
#include "metro/uncertainty/budget_report.hpp"

#include <catch2/catch.hpp>
#include <cmath>
#include <string>

#include "uncertainty/budget_report_json.hpp"

namespace metro {
namespace {

TEST_CASE("Budget report JSON for GUM H.1 with Monte Carlo", "[uncertainty][report]") {
  auto b = LoadBudget(std::string(METRO_SOURCE_DIR) + "/datasets/budgets/gum_h1_end_gauge.json");
  REQUIRE(b.ok());
  Budget budget = b.value();
  budget.monte_carlo.trials = 100000;
  auto e = EvaluateBudget(budget);
  REQUIRE(e.ok());
  const auto j = ToJsonValue(MakeBudgetReport(e.value()));
  CHECK(j["schema"] == "metro.budget-report/1");
  CHECK(j["result"]["u"].get<double>() == Approx(31.66388).margin(5e-4));
  // The file truncates nu_eff = 16.75 to 16 as H.1.6 does (G.6.4): k = t_0.995(16) = 2.9208,
  // U = 2.9208 x 31.664 = 92.48 nm -> "92" (H.1.6's 93 is 2.92 x the rounded u_c = 32 nm).
  CHECK(j["result"]["dof_eff"].get<double>() == 16.0);
  CHECK(j["result"]["coverage"].get<double>() == 0.99);
  CHECK(j["result"]["interval"].size() == 2);
  CHECK(j["result"]["statement"] == "l = (50000838 +- 92) nm, k = 2.92, p = 99 %");
  REQUIRE(j["budget"].size() == 9);
  CHECK(j["budget"][0]["name"] == "ls");
  CHECK(j["budget"][0]["dof"].get<double>() == 18.0);
  for (const char* key :
       {"name", "value", "u", "distribution", "sensitivity", "contribution", "dof", "percent"}) {
    CHECK(j["budget"][0].contains(key));
  }
  // Infinite dof is written as null.
  bool saw_null = false;
  for (const auto& line : j["budget"]) saw_null = saw_null || line["dof"].is_null();
  CHECK(saw_null);
  const auto& mc = j["monte_carlo"];
  CHECK(mc["trials"] == 100000);
  CHECK(mc["seed"] == 1);
  CHECK(mc["generator"].get<std::string>().find("pcg64") == 0);
  for (const char* key : {"value", "u", "interval_symmetric", "interval_shortest", "delta", "d_low",
                          "d_high", "guf_validated"}) {
    CHECK(mc.contains(key));
  }
  // Beside the contract keys: the discrete 7.7 interval and the MCM's own tolerance (7.9.2,
  // from u = 36 nm at ndig 2: delta = 0.5 nm); no stopping half-widths for a fixed run.
  CHECK(mc["interval_shortest_discrete"].size() == 2);
  CHECK(mc["numerical_tolerance"].get<double>() == Approx(0.5));
  CHECK_FALSE(mc.contains("stability_half_width"));
  const std::string table = BudgetReportTable(e.value());
  CHECK(table.find("Result (JCGM 100 7.2.6): l = (50000838 +- 92) nm") != std::string::npos);
  CHECK(table.find("Monte Carlo (JCGM 101): M = 100000") != std::string::npos);
}

TEST_CASE("Budget report of an adaptive run states the half-widths that met delta",
          "[uncertainty][report]") {
  auto b =
      LoadBudget(std::string(METRO_SOURCE_DIR) + "/datasets/budgets/jcgm101_9_2_2_additive.json");
  REQUIRE(b.ok());
  auto e = EvaluateBudget(b.value());
  REQUIRE(e.ok());
  const auto j = ToJsonValue(MakeBudgetReport(e.value()));
  const auto& mc = j["monte_carlo"];
  REQUIRE(mc["converged"] == true);
  // u = 2 at ndig 2: delta = 0.05 (JCGM 101 9.2.2).
  const double delta = mc["numerical_tolerance"].get<double>();
  CHECK(delta == Approx(0.05));
  const auto& st = mc["stability_half_width"];
  CHECK(st["groups"] == 10);
  for (const auto& x :
       {st["value"], st["u"], st["interval_symmetric"][0], st["interval_symmetric"][1],
        st["interval_shortest"][0], st["interval_shortest"][1]}) {
    REQUIRE(x.is_number());
    CHECK(x.get<double>() <= delta);
  }
  CHECK(BudgetReportTable(e.value()).find("stable to delta = 0.05 (7.9.2)") != std::string::npos);
}

TEST_CASE("Budget report states the unit check and every session unit conversion",
          "[uncertainty][report][units]") {
  // pitch_deg from a session, 30 deg +- 0.5 deg, declared in rad (30 deg = pi/6 rad).
  const SessionQuantityResolver resolver = [](const SessionQuantityRef&) -> Result<TypeASummary> {
    return TypeASummary{30.0, 0.5, 99.0, 100, "test session", "deg"};
  };
  auto b = ParseBudget(R"j({"measurand": {"name": "h", "unit": "cm", "model": "R*sin(theta)"},
      "inputs": [{"name": "R", "value": 32, "u": 0.1, "unit": "cm"},
                 {"name": "theta", "type_a": {"quantity": "pitch_deg"}, "unit": "rad"}],
      "monte_carlo": false})j",
                       "b.json", resolver);
  if (!b.ok()) FAIL(b.error().ToString());
  auto e = EvaluateBudget(b.value());
  REQUIRE(e.ok());
  // h = 32 sin(pi/6) = 16 cm exactly.
  CHECK(e.value().gum.value == Approx(16.0).epsilon(1e-14));
  const auto j = ToJsonValue(MakeBudgetReport(e.value()));
  CHECK(j["measurand"]["unit_check"]["checked"] == true);
  CHECK(j["measurand"]["unit_check"]["model_unit"] == "cm");
  bool found = false;
  for (const auto& line : j["budget"]) {
    if (line["name"] != "theta") continue;
    found = true;
    CHECK(line["unit"] == "rad");
    CHECK(line["value"].get<double>() == Approx(0.5235987755982988).epsilon(1e-15));
    const auto& c = line["unit_conversion"];
    CHECK(c["from"] == "deg");
    CHECK(c["to"] == "rad");
    CHECK(c["factor"].get<double>() == Approx(0.017453292519943295).epsilon(1e-15));
    CHECK(c["value_from"].get<double>() == 30.0);
    CHECK(c["u_from"].get<double>() == 0.5);
  }
  CHECK(found);
  const std::string table = BudgetReportTable(e.value());
  INFO(table);
  CHECK(table.find("unit: theta converted from deg to rad: 30 deg -> 0.5235987756 rad") !=
        std::string::npos);
}

}  // namespace
}  // namespace metro

namespace metro {
namespace {

TEST_CASE("Budget report histogram of the Monte Carlo values follows the known distribution",
          "[uncertainty][report]") {
  // JCGM 101 9.2.2: Y = X1 + X2 + X3 + X4 with standard normal inputs, so Y ~ N(0, 2^2).
  auto b =
      LoadBudget(std::string(METRO_SOURCE_DIR) + "/datasets/budgets/jcgm101_9_2_2_additive.json");
  REQUIRE(b.ok());
  Budget budget = b.value();
  budget.monte_carlo.adaptive = false;
  budget.monte_carlo.trials = 200000;
  auto e = EvaluateBudget(budget);
  REQUIRE(e.ok());
  REQUIRE(e.value().histogram.has_value());
  const McHistogram& h = *e.value().histogram;
  REQUIRE(h.edges.size() == h.counts.size() + 1);
  CHECK(h.counts.size() == 60);  // sqrt(200000) = 447, clamped to 60.
  int64_t total = h.below + h.above;
  for (int64_t c : h.counts) total += c;
  CHECK(total == 200000);
  // The central 99.9 % of N(0, 4) is +-3.29 sigma = +-6.58, widened by 5 % of the span.
  CHECK(h.edges.front() == Approx(-6.58 - 0.658).margin(0.1));
  CHECK(h.edges.back() == Approx(6.58 + 0.658).margin(0.1));
  const auto cdf = [](double y) { return 0.5 * std::erfc(-y / (2.0 * std::sqrt(2.0))); };
  for (size_t i = 0; i < h.counts.size(); ++i) {
    const double expected = 200000.0 * (cdf(h.edges[i + 1]) - cdf(h.edges[i]));
    // Binomial counts: within 5 standard deviations.
    CHECK(std::fabs(static_cast<double>(h.counts[i]) - expected) <= 5.0 * std::sqrt(expected) + 1);
  }
  const auto j = ToJsonValue(MakeBudgetReport(e.value()));
  CHECK(j["monte_carlo"]["histogram"]["counts"].size() == 60);
  CHECK(j["monte_carlo"]["histogram"]["edges"].size() == 61);
  CHECK(j["monte_carlo"]["histogram"]["below"].get<int64_t>() == h.below);
}

}  // namespace
}  // namespace metro
