// HTML reports: structure (plots present, nothing external), the session-less path, the
// schema dispatch and bad input.
#include "metro/report/html_report.hpp"

#include <fmt/format.h>

#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <string>

#include "metro/core/file.hpp"
#include "metro/core/rounding.hpp"
#include "metro/noise/allan.hpp"
#include "metro/uncertainty/budget.hpp"
#include "metro/uncertainty/budget_report.hpp"
#include "support/html_checks.hpp"
#include "support/temp_file.hpp"

namespace metro {
namespace {

using testing::CheckSelfContained;
using testing::Count;

using nlohmann::ordered_json;

const std::string kDatasets = std::string(METRO_SOURCE_DIR) + "/datasets/";

const SessionAnalysis& ImuAnalysis() {
  static const SessionAnalysis analysis = [] {
    SessionAnalysisOptions o;
    o.type_a.window.settle_auto = true;
    o.type_a.window.skip_seconds = 2.0;
    o.allan = true;
    o.allan_options.allan.taus = ParseTauSpacing("octave").value();
    return AnalyzeSession(kDatasets + "static_imu_100hz.csv", o);
  }();
  return analysis;
}

// Plots the report calls for, counted from the JSON: per evaluated quantity with s > 0 a
// time series, a histogram and an autocorrelation (only the time series when s = 0), plus
// an Allan plot where the report has an Allan curve.
size_t ExpectedPlots(const ordered_json& report, bool with_session) {
  size_t n = 0;
  for (const auto& s : report["sensors"]) {
    for (const auto& [name, q] : s["quantities"].items()) {
      if (!q["type_a"].is_object()) continue;
      if (with_session) n += q["type_a"]["std"].get<double>() > 0.0 ? 3 : 1;
      if (q.contains("allan") && q["allan"].contains("tau_s")) ++n;
    }
  }
  return n;
}

TEST_CASE("Session HTML has every plot and no external reference", "[report][html]") {
  const SessionAnalysis& a = ImuAnalysis();
  REQUIRE(a.ok);
  Result<std::string> html = RenderSessionAnalysisHtml(a);
  REQUIRE(html.ok());
  const std::string& h = html.value();
  CheckSelfContained(h);
  CHECK(h.find("<title>Session report: static_imu_100hz.csv</title>") != std::string::npos);
  CHECK(h.find("Type A summary") != std::string::npos);
  CHECK(h.find("Sensor 1") != std::string::npos);
  CHECK(h.find(a.session.sha256) != std::string::npos);
  const size_t expected = ExpectedPlots(a.report, true);
  CHECK(expected >= 3 * 6 + 6);  // Six rate quantities with Allan curves at least.
  CHECK(Count(h, "<svg") == expected);
  // The summary states the mean rounded per GUM 7.2.6 to two digits of u(mean).
  const auto& gx = a.report["sensors"][0]["quantities"]["gx_dps"]["type_a"];
  const RoundedResult r = RoundForStatement(gx["mean"].get<double>(), gx["u_mean"].get<double>());
  CHECK(h.find("<td class=\"num\">" + r.value + "</td><td class=\"num\">" + r.uncertainty +
               "</td>") != std::string::npos);
  // The settle window is shaded and named.
  CHECK(h.find("shaded: observations left out of the Type A window") != std::string::npos);
}

TEST_CASE("Session HTML says how a non-canonical file was read", "[report][html]") {
  // ';'-separated with decimal commas and CRLF, integer milliseconds, one mapped column.
  std::string text = "t_ms;sensor;Gyro Z\r\n";
  for (int i = 0; i < 40; ++i) {
    text += fmt::format("{};1;{},{}\r\n", 1000 + 10 * i, i % 2 == 0 ? 0 : 1, 25 + i % 3);
  }
  testing::TempFile file(text, ".csv");
  SessionAnalysisOptions o;
  o.load.column_map = {{"Gyro Z", "gz_dps"}};
  const SessionAnalysis a = AnalyzeSession(file.path(), o);
  REQUIRE(a.ok);
  Result<std::string> html = RenderSessionAnalysisHtml(a);
  REQUIRE(html.ok());
  const std::string& h = html.value();
  CHECK(h.find("<tr><th>read as</th><td>semicolon-separated, decimal comma, CRLF line "
               "ends</td></tr>") != std::string::npos);
  CHECK(h.find("<tr><th>columns mapped</th><td>Gyro Z \u2192 gz_dps</td></tr>") !=
        std::string::npos);
  CHECK(h.find("<tr><th>time</th><td>column t_ms in ms, integer (exact), origin 1000000000 "
               "ns</td></tr>") != std::string::npos);
  // The canonical sample file has no mapping row.
  Result<std::string> canonical = RenderSessionAnalysisHtml(ImuAnalysis());
  REQUIRE(canonical.ok());
  CHECK(canonical.value().find("columns mapped") == std::string::npos);
  CHECK(canonical.value().find("<tr><th>read as</th>") != std::string::npos);
}

TEST_CASE("Report without its session keeps the JSON plots and says why", "[report][html]") {
  const SessionAnalysis& a = ImuAnalysis();
  REQUIRE(a.ok);
  Result<std::string> html = RenderSessionReportHtml(a.report, nullptr, "the session is gone");
  REQUIRE(html.ok());
  CheckSelfContained(html.value());
  CHECK(Count(html.value(), "<svg") == ExpectedPlots(a.report, false));
  CHECK(html.value().find("unavailable (the session is gone)") != std::string::npos);
}

TEST_CASE("Saved report reloads its session only when the SHA-256 matches", "[report][html]") {
  const SessionAnalysis& a = ImuAnalysis();
  REQUIRE(a.ok);
  testing::TempFile json(a.report.dump(2), ".json");
  Result<std::string> html = RenderJsonFileHtml(json.path());
  REQUIRE(html.ok());
  CHECK(html.value().find("SHA-256 matches the report") != std::string::npos);
  CHECK(Count(html.value(), "<svg") == ExpectedPlots(a.report, true));

  // A different file given as the session: refused, plots from the JSON only.
  Result<std::string> other = RenderJsonFileHtml(json.path(), kDatasets + "static_chest.csv");
  REQUIRE(other.ok());
  CHECK(other.value().find("differs from the report") != std::string::npos);
  CHECK(Count(other.value(), "<svg") == ExpectedPlots(a.report, false));
}

TEST_CASE("Budget report gets sorted bars", "[report][html]") {
  Result<Budget> budget = LoadBudget(kDatasets + "budgets/gum_h1_end_gauge.json");
  REQUIRE(budget.ok());
  Result<BudgetEvaluation> e = EvaluateBudget(budget.value());
  REQUIRE(e.ok());
  const ordered_json report = BudgetReportJson(e.value());
  Result<std::string> html = RenderJsonHtml(report, "budget_report.json");
  REQUIRE(html.ok());
  CheckSelfContained(html.value());
  CHECK(html.value().find("Uncertainty budget") != std::string::npos);
  // The budget page: the Monte Carlo histogram and the contribution bars.
  CHECK(Count(html.value(), "<svg") == 2);
  // Table rows in decreasing percent: the first line is the largest contributor.
  double largest = -1.0;
  std::string largest_name;
  for (const auto& l : report["budget"]) {
    if (l["percent"].get<double>() > largest) {
      largest = l["percent"].get<double>();
      largest_name = l["name"].get<std::string>();
    }
  }
  const size_t table = html.value().find("<th>percent</th>");
  REQUIRE(table != std::string::npos);
  CHECK(html.value().find("<td>" + largest_name + "</td>", table) ==
        html.value().find("<tr><td>", table) + 4);
}

TEST_CASE("Unknown schema falls back to tables", "[report][html]") {
  const ordered_json doc = ordered_json::parse(
      R"({"schema": "metro.example/1", "angle_deg": [1, 2, 3], "rows": [{"a": 1, "b": "<x>"}]})");
  Result<std::string> html = RenderJsonHtml(doc, "acc.json");
  REQUIRE(html.ok());
  CheckSelfContained(html.value());
  CHECK(html.value().find("No dedicated view for the schema") != std::string::npos);
  CHECK(html.value().find("metro.example/1") != std::string::npos);
  CHECK(html.value().find("&lt;x&gt;") != std::string::npos);  // Escaped.
  CHECK(html.value().find("<x>") == std::string::npos);
}

TEST_CASE("Bad report input is refused with a message", "[report][html]") {
  testing::TempFile not_json("{not json", ".json");
  Result<std::string> r = RenderJsonFileHtml(not_json.path());
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().file == not_json.path());
  CHECK(r.error().message.rfind("invalid JSON: ", 0) == 0);
  // The parser takes 'n' for the start of null and stops at the 'o' that breaks it: column 3,
  // as nlohmann::json's own message says.
  CHECK(r.error().line == 1);
  CHECK(r.error().column == 3);
  CHECK(r.error().message.find("line 1, column 3") != std::string::npos);

  // A number beyond a double's range made nlohmann::json throw out_of_range, which nothing
  // caught: the process terminated (issue #20, found by fuzz/report_fuzz). Now an input
  // error at the number.
  testing::TempFile huge("{\"schema\": \"metro.report/1\",\n \"x\": [1, -1e999]}", ".json");
  r = RenderJsonFileHtml(huge.path());
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().file == huge.path());
  CHECK(r.error().line == 2);
  CHECK(r.error().column == 11);
  CHECK(r.error().message.find("number overflow") != std::string::npos);

  // 70,000 levels of nesting crashed the page's recursive walk (issue #20): refused at the
  // bracket that opens level 65.
  testing::TempFile deep(std::string(70000, '[') + std::string(70000, ']'), ".json");
  r = RenderJsonFileHtml(deep.path());
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().ToString() ==
        deep.path() +
            ":1:65: JSON nested deeper than 64 levels; metro's files nest a few levels "
            "(docs/report-schema.md, docs/budget-format.md)");
  // 64 levels are JSON like any other (a generic page).
  testing::TempFile deep64(std::string(64, '[') + std::string(64, ']'), ".json");
  CHECK(RenderJsonFileHtml(deep64.path()).ok());

  r = RenderJsonFileHtml("no_such_report.json");
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().ToString().find("no_such_report.json") != std::string::npos);

  const ordered_json missing = ordered_json::parse(R"({"schema": "metro.report/1", "input": {}})");
  r = RenderJsonHtml(missing, "r.json");
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().message == "metro.report/1 report: missing key 'sensors'");

  r = RenderSessionReportHtml(ordered_json::parse(R"({"schema": "x"})"), nullptr, "");
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().message == "not a metro.report/1 report (schema key missing or different)");

  HtmlReportOptions o;
  o.max_series_points = 3;
  std::string why;
  CHECK_FALSE(o.IsValid(&why));
  CHECK(why == "html: max_series_points must be >= 16");
  r = RenderSessionAnalysisHtml(ImuAnalysis(), o);
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().message == "html: max_series_points must be >= 16");

  SessionAnalysis failed;
  r = RenderSessionAnalysisHtml(failed);
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().message == "no HTML report of a failed analysis");
}

}  // namespace
}  // namespace metro
