// The "metro.budget-report/1" codec: what EvaluateBudget's report writes reads back into the
// same text byte for byte, reports of older metro versions still load, and a damaged report
// is refused at the offending value's own line and column with its path.
#include "uncertainty/budget_report_json.hpp"

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "core/json_text.hpp"
#include "metro/report/budget_page.hpp"
#include "metro/uncertainty/budget_report.hpp"
#include "metro/uncertainty/session_resolver.hpp"
#include "support/temp_file.hpp"
#include "support/text_position.hpp"

namespace metro {
namespace {

namespace fs = std::filesystem;
const std::string kDatasets = std::string(METRO_SOURCE_DIR) + "/datasets/";

// The text `characterize budget` writes (without its final newline) for `budget`.
std::string ProducedText(const Budget& budget) {
  Result<BudgetEvaluation> e = EvaluateBudget(budget);
  REQUIRE(e.ok());
  return ToJson(MakeBudgetReport(e.value()));
}

void CheckRoundTrip(const std::string& text, const std::string& what) {
  INFO(what);
  Result<BudgetReport> read = BudgetReportFromJson(text, "r.json");
  if (!read.ok()) FAIL(read.error().ToString());
  CHECK(ToJson(read.value()) == text);
  // The value-level halves agree with the text-level ones.
  CHECK(JsonText(ToJsonValue(read.value()), 2) == text);
}

// The member order of every object in a "metro.budget-report/1" document, as
// docs/budget-format.md lists it (and metro wrote it before the typed model): an object's
// members must appear in this order, optional ones may be absent.
void CheckKeyOrder(const nlohmann::ordered_json& j, const std::string& path) {
  static const std::map<std::string, std::vector<std::string>> kOrder = {
      {"",
       {"schema", "budget_file", "measurand", "result", "budget", "correlations", "monte_carlo",
        "stated"}},
      {"stated", {"method", "reason", "value", "u", "interval", "coverage", "statement"}},
      {"measurand", {"name", "unit", "model", "unit_check"}},
      {"measurand.unit_check", {"checked", "model_unit", "scale_known", "note"}},
      {"result",
       {"value", "u", "dof_eff", "k", "U", "coverage", "interval", "u_first_order", "second_order",
        "dof_policy", "correlated", "dof_note", "derivatives", "statement"}},
      {"budget[]",
       {"name", "value", "u", "distribution", "sensitivity", "contribution", "dof", "percent",
        "unit", "note", "unit_conversion", "session"}},
      {"budget[].unit_conversion", {"from", "to", "factor", "offset", "value_from", "u_from"}},
      {"budget[].session", {"file", "sensor", "quantity", "n"}},
      {"correlations[]", {"a", "b", "r"}},
      {"monte_carlo",
       {"trials",
        "seed",
        "generator",
        "threads",
        "adaptive",
        "converged",
        "blocks",
        "ndig",
        "coverage",
        "value",
        "u",
        "u_defined",
        "mean_defined",
        "inputs_without_variance",
        "interval_symmetric",
        "interval_shortest",
        "interval_shortest_discrete",
        "numerical_tolerance",
        "stability_half_width",
        "delta",
        "d_low",
        "d_high",
        "guf_validated",
        "histogram",
        "message"}},
      {"monte_carlo.stability_half_width",
       {"value", "u", "interval_symmetric", "interval_shortest", "groups"}},
      {"monte_carlo.histogram", {"edges", "counts", "below", "above"}},
  };
  if (j.is_array()) {
    for (const auto& element : j) CheckKeyOrder(element, path + "[]");
    return;
  }
  if (!j.is_object()) return;
  const auto order = kOrder.find(path);
  INFO(path);
  REQUIRE(order != kOrder.end());
  size_t next = 0;
  for (auto it = j.begin(); it != j.end(); ++it) {
    const auto& keys = order->second;
    const auto at =
        std::find(keys.begin() + static_cast<std::ptrdiff_t>(next), keys.end(), it.key());
    INFO(it.key());
    CHECK(at != keys.end());
    if (at != keys.end()) next = static_cast<size_t>(at - keys.begin()) + 1;
    CheckKeyOrder(it.value(), path.empty() ? it.key() : path + "." + it.key());
  }
}

using testing::LineColumn;

TEST_CASE("Budget reports of the bundled budgets read back byte for byte",
          "[uncertainty][report][json]") {
  int budgets = 0;
  for (const auto& entry : fs::directory_iterator(kDatasets + "budgets")) {
    if (entry.path().extension() != ".json") continue;
    Result<Budget> loaded = LoadBudget(entry.path().string());
    // tag_static_angle_session.json takes its Type A input from the command line's session.
    if (!loaded.ok()) continue;
    ++budgets;
    const std::string name = entry.path().filename().string();
    Budget fixed = loaded.value();
    fixed.monte_carlo.adaptive = false;
    fixed.monte_carlo.trials = 20000;
    CheckRoundTrip(ProducedText(fixed), name + ", 20000 trials");
    Budget gum_only = loaded.value();
    gum_only.monte_carlo.enabled = false;
    const std::string text = ProducedText(gum_only);
    CHECK(text.find("\"monte_carlo\": null") != std::string::npos);
    CheckRoundTrip(text, name + ", no Monte Carlo");
  }
  CHECK(budgets == 7);
  // As written: an adaptive run (stability_half_width) and the GUM H.1 file (truncated dof).
  for (const char* name : {"jcgm101_9_2_2_additive.json", "fingertip_sagitta.json"}) {
    Result<Budget> loaded = LoadBudget(kDatasets + "budgets/" + name);
    REQUIRE(loaded.ok());
    const std::string text = ProducedText(loaded.value());
    CHECK(text.find("\"stability_half_width\"") != std::string::npos);
    CheckKeyOrder(nlohmann::ordered_json::parse(text), "");
    CheckRoundTrip(text, std::string(name) + " as written");
  }
}

TEST_CASE("A budget report with session inputs and a unit conversion reads back byte for byte",
          "[uncertainty][report][json]") {
  // tag_static_angle_session.json with its Type A inputs taken from static_chest.csv by name
  // and obs in rad: its lines carry "session" and "unit_conversion".
  std::ifstream in(kDatasets + "budgets/tag_static_angle_session.json");
  nlohmann::ordered_json b = nlohmann::ordered_json::parse(in);
  for (auto& input : b["inputs"]) {
    if (!input.contains("type_a")) continue;
    input["type_a"]["session"] = kDatasets + "static_chest.csv";
    if (input["name"] == "obs") input["unit"] = "rad";
  }
  b["measurand"]["model"] = "obs*180/pi + res + mount + xaxis*yaw";
  b["monte_carlo"] = {{"trials", 20000}, {"seed", 7}};
  testing::TempFile file(b.dump(1), ".json");
  Result<Budget> budget = LoadBudget(file.path(), MakeSessionQuantityResolver("", {}, {}));
  if (!budget.ok()) FAIL(budget.error().ToString());
  const std::string text = ProducedText(budget.value());
  CHECK(text.find("\"unit_conversion\"") != std::string::npos);
  CHECK(text.find("\"session\"") != std::string::npos);
  CheckKeyOrder(nlohmann::ordered_json::parse(text), "");
  CheckRoundTrip(text, "session inputs");
  Result<BudgetReport> read = BudgetReportFromJson(text, "r.json");
  REQUIRE(read.ok());
  bool converted = false;
  for (const BudgetReportLine& line : read.value().budget) {
    if (line.name != "obs") continue;
    REQUIRE(line.unit_conversion);
    REQUIRE(line.session);
    converted = true;
    CHECK(line.session->sensor == 2);
    CHECK(line.session->quantity == "pitch_deg");
    // value = factor * value_from, factor = pi/180 (deg -> rad).
    CHECK(line.unit_conversion->factor == Approx(3.141592653589793 / 180.0).epsilon(1e-15));
    CHECK(line.value ==
          Approx(line.unit_conversion->factor * line.unit_conversion->value_from).epsilon(1e-15));
  }
  CHECK(converted);
}

TEST_CASE("A budget report with correlations and an input without variance reads back",
          "[uncertainty][report][json]") {
  // y = a + b, r(a, b) = 0.5; c from 3 readings has nu = 2: no variance in the Monte Carlo
  // method (JCGM 101 6.4.9.4), so u is null and u_defined false.
  Result<Budget> budget = ParseBudget(
      R"({"measurand": {"name": "y", "unit": "mm", "model": "a + b + c"},
          "inputs": [{"name": "a", "value": 1, "u": 0.1, "unit": "mm"},
                     {"name": "b", "value": 2, "u": 0.2, "unit": "mm", "note": "calibrated"},
                     {"name": "c", "type_a": {"values": [0.01, 0.03, 0.02]}, "unit": "mm"}],
          "correlations": [{"a": "a", "b": "b", "r": 0.5}],
          "monte_carlo": {"trials": 20000, "seed": 3}})",
      "inline.json");
  if (!budget.ok()) FAIL(budget.error().ToString());
  const std::string text = ProducedText(budget.value());
  CHECK(text.find("\"u_defined\": false") != std::string::npos);
  CHECK(text.find("\"r\": 0.5") != std::string::npos);
  CheckKeyOrder(nlohmann::ordered_json::parse(text), "");
  CheckRoundTrip(text, "correlated");
  Result<BudgetReport> read = BudgetReportFromJson(text, "r.json");
  REQUIRE(read.ok());
  REQUIRE(read.value().correlations.size() == 1);
  CHECK(read.value().correlations[0].r == 0.5);
  REQUIRE(read.value().monte_carlo);
  CHECK(std::isnan(read.value().monte_carlo->u));
  CHECK(read.value().monte_carlo->inputs_without_variance ==
        std::vector<std::string>{"c (nu = 2)"});
  // nu of c is 2 (3 readings), of a and b infinite (null in the JSON).
  for (const BudgetReportLine& line : read.value().budget) {
    if (line.name == "c") {
      CHECK(line.dof == 2.0);
    } else {
      CHECK(std::isinf(line.dof));
    }
  }
}

// The GUM H.1 report at 20000 trials, for the error and old-version cases.
std::string H1Text() {
  Result<Budget> loaded = LoadBudget(kDatasets + "budgets/gum_h1_end_gauge.json");
  REQUIRE(loaded.ok());
  Budget budget = loaded.value();
  budget.monte_carlo.trials = 20000;
  return ProducedText(budget);
}

TEST_CASE("A damaged budget report is refused at the value's line and column with its path",
          "[uncertainty][report][json]") {
  using nlohmann::ordered_json;
  const ordered_json good = ordered_json::parse(H1Text());
  struct Case {
    std::function<void(ordered_json*)> damage;
    std::string token;    // Where the reported value starts: its first occurrence in the text.
    std::string message;  // After "r.json:LINE:COLUMN: ".
  };
  const std::vector<Case> cases = {
      {[](ordered_json* j) { (*j)["result"]["u"] = "thirty-one"; }, "\"thirty-one\"",
       "result.u: expected a number or null, found the string \"thirty-one\""},
      {[](ordered_json* j) { (*j)["result"]["dof_policy"] = "grouped"; }, "\"grouped\"",
       "result.dof_policy: expected one of \"group\", \"ignore\", \"reject\", found the string "
       "\"grouped\""},
      // A missing member is reported at the object it belongs to.
      {[](ordered_json* j) { (*j)["budget"][0].erase("percent"); }, "{\n      \"name\": \"ls\"",
       "budget[0].percent: expected a number or null, found nothing (the member is missing)"},
      {[](ordered_json* j) { (*j)["budget"][2]["dof"] = "many"; }, "\"many\"",
       "budget[2].dof: expected a number or null (infinite degrees of freedom), found the "
       "string \"many\""},
      {[](ordered_json* j) { (*j)["monte_carlo"]["histogram"]["counts"][3] = "three"; },
       "\"three\"",
       "monte_carlo.histogram.counts[3]: expected an integer, found the string \"three\""},
      {[](ordered_json* j) { (*j)["monte_carlo"]["trials"] = 2.5; }, "2.5,\n    \"seed\"",
       "monte_carlo.trials: expected an integer, found the number 2.5"},
      {[](ordered_json* j) { (*j)["schema"] = "metro.report/1"; }, "\"metro.report/1\"",
       "schema: expected \"metro.budget-report/1\", found the string \"metro.report/1\""},
      {[](ordered_json* j) {
         (*j)["monte_carlo"]["interval_symmetric"] = {1, 2, 3};
       },
       "[\n      1,\n      2,\n      3\n    ]",
       "monte_carlo.interval_symmetric: expected an array of 2 numbers or nulls [low, high], "
       "found an array"},
  };
  for (const Case& c : cases) {
    ordered_json j = good;
    c.damage(&j);
    const std::string damaged = JsonText(j, 2);
    const size_t offset = damaged.find(c.token);
    REQUIRE(offset != std::string::npos);
    INFO(c.message);
    Result<BudgetReport> read = BudgetReportFromJson(damaged, "r.json");
    REQUIRE_FALSE(read.ok());
    CHECK(read.error().ToString() == "r.json:" + LineColumn(damaged, offset) + ": " + c.message);
    // The page of a damaged report is refused with the same message.
    Result<std::string> page = RenderBudgetReportHtml(damaged, "r.json");
    REQUIRE_FALSE(page.ok());
    CHECK(page.error().ToString() == read.error().ToString());
  }
  // Not JSON at all: the parser's position, on line 2.
  Result<BudgetReport> broken = BudgetReportFromJson("{\n  \"schema\": ,\n}", "r.json");
  REQUIRE_FALSE(broken.ok());
  CHECK(broken.error().ToString().rfind("r.json:2:", 0) == 0);
  CHECK(broken.error().ToString().find("invalid JSON") != std::string::npos);
}

TEST_CASE("A budget report written before 2026-11-27 still loads", "[uncertainty][report][json]") {
  // The keys later versions added (docs/budget-format.md): derivatives, u_defined,
  // mean_defined, inputs_without_variance, interval_shortest_discrete, numerical_tolerance,
  // unit_check, histogram.
  nlohmann::ordered_json j = nlohmann::ordered_json::parse(H1Text());
  j["result"].erase("derivatives");
  j["measurand"].erase("unit_check");
  for (const char* key : {"u_defined", "mean_defined", "inputs_without_variance",
                          "interval_shortest_discrete", "numerical_tolerance", "histogram"}) {
    REQUIRE(j["monte_carlo"].contains(key));
    j["monte_carlo"].erase(key);
  }
  Result<BudgetReport> read = BudgetReportFromJson(JsonText(j, 2), "old.json");
  if (!read.ok()) FAIL(read.error().ToString());
  const BudgetReport& r = read.value();
  CHECK(r.result.derivatives.empty());
  CHECK_FALSE(r.measurand.unit_check);
  REQUIRE(r.monte_carlo);
  CHECK(r.monte_carlo->u_defined);
  CHECK(r.monte_carlo->mean_defined);
  CHECK(std::isnan(r.monte_carlo->numerical_tolerance));
  CHECK_FALSE(r.monte_carlo->histogram);
  CHECK(r.result.statement == "l = (50000838 +- 92) nm, k = 2.92, p = 99 %");
  // Without "stated" (before 2026-12-02) the stated result is decided from the report.
  nlohmann::ordered_json without = nlohmann::ordered_json::parse(H1Text());
  REQUIRE(without.contains("stated"));
  without.erase("stated");
  Result<BudgetReport> again = BudgetReportFromJson(JsonText(without, 2), "old.json");
  REQUIRE(again.ok());
  CHECK(JsonText(ToJsonValue(again.value()), 2) == H1Text());
  // Its page: the statement, without the histogram.
  Result<std::string> page = RenderBudgetReportHtml(r);
  REQUIRE(page.ok());
  CHECK(page.value().find("No histogram") != std::string::npos);
}

}  // namespace
}  // namespace metro
