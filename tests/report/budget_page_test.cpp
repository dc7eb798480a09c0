// The budget page: its statement and intervals equal the report JSON rounded per JCGM 100
// 7.2.6, and for GUM H.1 the published result.
#include "metro/report/budget_page.hpp"

#include <catch2/catch.hpp>
#include <regex>
#include <string>

#include "metro/core/rounding.hpp"
#include "metro/report/html_report.hpp"
#include "metro/uncertainty/budget_report.hpp"
#include "report/budget_view.hpp"
#include "report/html_dispatch.hpp"
#include "support/html_checks.hpp"

namespace metro {
namespace {

using nlohmann::ordered_json;

BudgetReport EvaluatedReport(const std::string& name, int64_t trials) {
  auto b = LoadBudget(std::string(METRO_SOURCE_DIR) + "/datasets/budgets/" + name);
  REQUIRE(b.ok());
  Budget budget = b.value();
  budget.monte_carlo.adaptive = false;
  budget.monte_carlo.trials = trials;
  auto e = EvaluateBudget(budget);
  REQUIRE(e.ok());
  return MakeBudgetReport(e.value());
}

// The text of the element with id `id` (no nested tags).
std::string ElementText(const std::string& html, const std::string& id) {
  std::smatch m;
  const std::regex re("id=\"" + id + "\"[^>]*>([^<]*)<");
  if (!std::regex_search(html, m, re)) return "";
  return m[1].str();
}

TEST_CASE("Budget page statement equals the JSON rounded per GUM 7.2.6", "[report][budget]") {
  const BudgetReport report = EvaluatedReport("gum_h1_end_gauge.json", 200000);
  Result<std::string> html = RenderBudgetReportHtml(report);
  REQUIRE(html.ok());
  const std::string& h = html.value();
  testing::CheckSelfContained(h);
  // The statement comes before everything else on the page.
  CHECK(h.find("id=\"statement\"") < h.find("<svg"));
  // At 99 % H.1's GUF is not validated (d_high = 0.67 nm > delta = 0.5 nm): the GUF
  // statement stands below the stated Monte Carlo one.
  const bool guf_stated = report.stated.method == kStatedGuf;
  const std::string statement = ElementText(h, guf_stated ? "statement" : "guf-statement");
  std::smatch m;
  REQUIRE(std::regex_match(statement, m, std::regex("(\\S+) = \\((\\S+) \u00b1 (\\S+)\\) (\\S+)")));
  const RoundedResult r = RoundForStatement(report.result.value, report.result.expanded);
  CHECK(m[1].str() == "l");
  CHECK(m[2].str() == r.value);
  CHECK(m[3].str() == r.uncertainty);
  CHECK(m[4].str() == "nm");
  // JCGM 100:2008 H.1: l = 50000838 nm; U99 = t_0.995(16) x 31.66 nm = 92.5 nm at two digits
  // (H.1.6 prints 93 from the rounded u_c = 32 nm).
  CHECK(m[2].str() == "50000838");
  CHECK(m[3].str() == "92");
  CHECK(h.find("k = 2.92") != std::string::npos);
  CHECK(h.find("nu_eff = 16 ") != std::string::npos);
  CHECK(h.find("coverage probability of 99 %") != std::string::npos);
  CHECK(h.find("l = 50000838(32) nm") != std::string::npos);
  if (!guf_stated) {
    CHECK(ElementText(h, "concise") ==
          "l = " + ConciseNotation(report.monte_carlo->value, report.monte_carlo->u) + " nm");
  }
}

TEST_CASE("Budget page prints both intervals to digits that tell their ends apart",
          "[report][budget]") {
  const BudgetReport report = EvaluatedReport("gum_h1_end_gauge.json", 200000);
  Result<std::string> html = RenderBudgetReportHtml(report);
  REQUIRE(html.ok());
  REQUIRE(report.monte_carlo);
  const CoverageInterval& g = report.result.interval;
  const CoverageInterval& s = report.monte_carlo->shortest;
  const RoundedInterval gi = RoundInterval(g.low, g.high);
  const RoundedInterval si = RoundInterval(s.low, s.high);
  CHECK(html.value().find("[" + gi.low + ", " + gi.high + "]") != std::string::npos);
  CHECK(html.value().find("[" + si.low + ", " + si.high + "]") != std::string::npos);
  // The ends of the 99 % interval (width about 185 nm, to the tens) differ in two digits or
  // more; "{:.6g}" gave 5.00007e+07 and 5.00009e+07.
  REQUIRE(gi.low.size() == 8);
  REQUIRE(gi.high.size() == 8);
  int differing = 0;
  for (size_t i = 0; i < 8; ++i) differing += gi.low[i] != gi.high[i] ? 1 : 0;
  CHECK(differing >= 2);
  CHECK(gi.low.back() == '0');
  CHECK(html.value().find("e+07") == std::string::npos);
  // The verdict is the JSON's.
  REQUIRE(report.monte_carlo->validation);
  const bool validated = report.monte_carlo->validation->validated;
  CHECK(html.value().find(validated ? "GUF validated" : "GUF NOT validated") != std::string::npos);
  // The histogram with the GUF density, then the contribution bars.
  CHECK(html.value().find("Histogram of the Monte Carlo values of l") != std::string::npos);
  CHECK(html.value().find("<svg") < html.value().find("id=\"contributions\""));
  size_t svgs = 0;
  for (size_t at = html.value().find("<svg"); at != std::string::npos;
       at = html.value().find("<svg", at + 1)) {
    ++svgs;
  }
  CHECK(svgs == 2);
}

TEST_CASE("Budget page of JCGM 101 9.2.2 states the exact result", "[report][budget]") {
  // Y ~ N(0, 4): y = 0, U = 1.96 x 2 = 3.92, validated.
  const BudgetReport report = EvaluatedReport("jcgm101_9_2_2_additive.json", 200000);
  Result<std::string> html = RenderBudgetReportHtml(report);
  REQUIRE(html.ok());
  CHECK(ElementText(html.value(), "statement") == "Y = (0.0 \u00b1 3.9)");
  CHECK(html.value().find("from the normal distribution") != std::string::npos);
  CHECK(html.value().find("GUF validated") != std::string::npos);
}

TEST_CASE("Budget page headlines the Monte Carlo result when the GUF fails validation",
          "[report][budget]") {
  // JCGM 101:2008 9.3 (mass calibration): the first-order GUF is not validated; the headline
  // is the Monte Carlo mean and shortest interval (9.3: 1.2340 mg, [1.0834, 1.3825] mg at
  // M = 1e6), both results stay in the table below it.
  const BudgetReport report = EvaluatedReport("jcgm101_9_3_mass.json", 200000);
  REQUIRE(report.monte_carlo);
  REQUIRE(report.monte_carlo->validation);
  REQUIRE_FALSE(report.monte_carlo->validation->validated);
  CHECK(report.stated.method == kStatedMonteCarlo);
  Result<std::string> html = RenderBudgetReportHtml(report);
  REQUIRE(html.ok());
  const std::string& h = html.value();
  const std::string statement = ElementText(h, "statement");
  // The mean, u and the shortest interval's ends, rounded at u's second significant digit.
  const double u = report.monte_carlo->u;
  const RoundedResult v = RoundForStatement(report.monte_carlo->value, u);
  const std::string low = RoundForStatement(report.monte_carlo->shortest.low, u).value;
  const std::string high = RoundForStatement(report.monte_carlo->shortest.high, u).value;
  CHECK(statement == "dm = " + v.value + " mg, u(dm) = " + v.uncertainty +
                         " mg, shortest 95 % coverage interval [" + low + ", " + high +
                         "] mg (JCGM 101 7.7)");
  CHECK(statement == report.stated.statement);
  CHECK(v.uncertainty == "0.075");  // 9.3: 0.0754 mg
  CHECK(std::stod(low) == Approx(1.0834).margin(0.002));
  CHECK(std::stod(high) == Approx(1.3825).margin(0.002));
  // The GUF statement is below it, not stated: 9.3's u = 0.0539 mg, U = 0.1056 mg.
  CHECK(ElementText(h, "guf-statement") == "dm = (1.23 \u00b1 0.11) mg");
  // The GUF's +- statement is not the headline, and the verdict below says why.
  CHECK(statement.find("\u00b1") == std::string::npos);
  CHECK(ElementText(h, "stated-basis").find("not validated") != std::string::npos);
  CHECK(h.find("id=\"statement\"") < h.find("id=\"results\""));
  CHECK(h.find("Monte Carlo (JCGM 101), shortest, stated") != std::string::npos);
  CHECK(h.find("<td>GUF (JCGM 100)</td>") != std::string::npos);
  CHECK(h.find("GUF NOT validated") != std::string::npos);
  // A validated budget keeps the GUF headline and says it is the stated one.
  const BudgetReport additive = EvaluatedReport("jcgm101_9_2_2_additive.json", 200000);
  CHECK(additive.stated.method == kStatedGuf);
  Result<std::string> additive_html = RenderBudgetReportHtml(additive);
  REQUIRE(additive_html.ok());
  CHECK(additive_html.value().find("GUF (JCGM 100), stated") != std::string::npos);
  CHECK(additive_html.value().find("id=\"guf-statement\"") == std::string::npos);
}

using testing::WithoutFooter;

TEST_CASE("The page of a saved budget report is the page of the evaluation", "[report][budget]") {
  const BudgetReport report = EvaluatedReport("gum_h1_end_gauge.json", 20000);
  Result<std::string> direct = RenderBudgetReportHtml(report);
  Result<std::string> saved = RenderBudgetReportHtml(ToJson(report), "b.report.json");
  REQUIRE(direct.ok());
  REQUIRE(saved.ok());
  CHECK(direct.value().find("<footer>") != std::string::npos);
  CHECK(WithoutFooter(saved.value()) == WithoutFooter(direct.value()));
}

TEST_CASE("A saved budget report renders as the budget page and a definition is refused",
          "[report][budget]") {
  const ordered_json report =
      ordered_json::parse(ToJson(EvaluatedReport("jcgm101_9_2_2_additive.json", 20000)));
  Result<std::string> html = RenderJsonHtml(report, "b.report.json");
  REQUIRE(html.ok());
  CHECK(html.value().find("<title>Uncertainty budget: Y</title>") != std::string::npos);
  const ordered_json definition = ordered_json::parse(
      R"({"measurand": {"name": "Y"}, "inputs": [{"name": "X", "value": 1, "u": 1}]})");
  CHECK(IsBudgetDefinition(definition));
  CHECK_FALSE(IsBudgetDefinition(report));
  Result<std::string> refused = RenderJsonHtml(definition, "B.json");
  REQUIRE_FALSE(refused.ok());
  CHECK(refused.error().ToString().find("characterize budget B.json --html") != std::string::npos);
}

}  // namespace
}  // namespace metro
