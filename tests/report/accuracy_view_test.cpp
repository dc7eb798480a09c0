// The HTML view of "metro.accuracy-report/1": plots present and counted from the JSON,
// nothing external, numbers rounded per JCGM 100:2008 7.2.6 with k = t_{(1+p)/2}(nu) from
// published t tables, bad input named; and the programs end to end.
#include <catch2/catch.hpp>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>

#include "accuracy/accuracy_report_json.hpp"
#include "core/json_text.hpp"
#include "metro/accuracy/accuracy.hpp"
#include "metro/accuracy/accuracy_report.hpp"
#include "metro/core/rounding.hpp"
#include "metro/io/session_io.hpp"
#include "metro/report/html_report.hpp"
#include "report/html_dispatch.hpp"
#include "support/html_checks.hpp"
#include "support/run_program.hpp"
#include "support/temp_file.hpp"
#include "support/text_position.hpp"

namespace metro {
namespace {

using testing::CheckSelfContained;
using testing::Count;

using nlohmann::ordered_json;

const std::string kSweep = std::string(METRO_SOURCE_DIR) + "/datasets/table_sweep.csv";

// PLplot writes the characters of SVG text as "&#xNN;" references; decoded for searching.
std::string DecodeCharRefs(const std::string& html) {
  std::string out;
  for (size_t i = 0; i < html.size(); ++i) {
    if (html.compare(i, 3, "&#x") == 0) {
      const size_t end = html.find(';', i);
      if (end != std::string::npos && end - i <= 8) {
        out += static_cast<char>(std::stoi(html.substr(i + 3, end - i - 3), nullptr, 16));
        i = end;
        continue;
      }
    }
    out += html[i];
  }
  return out;
}

const ordered_json& SweepReport() {
  static const ordered_json report = [] {
    Result<Session> session = LoadSession(kSweep);
    REQUIRE(session.ok());
    AccuracyOptions options;
    options.reference.u_deg = 0.01;
    Result<AccuracyResult> result = EvaluateAccuracy(session.value(), nullptr, options);
    REQUIRE(result.ok());
    return ToJsonValue(MakeAccuracyReport(result.value(), session.value(), nullptr));
  }();
  return report;
}

// Plots the view calls for, counted from the JSON: the error plot, one hysteresis plot when
// there are pairs, one plot per cross-axis quantity, one bar plot per budget.
size_t ExpectedPlots(const ordered_json& report) {
  size_t n = 1;
  if (report["hysteresis"]["available"].get<bool>() && !report["hysteresis"]["pairs"].empty()) {
    ++n;
  }
  n += report["cross_axis"].size();
  n += report["budget"].size();
  return n;
}

TEST_CASE("Accuracy HTML has every plot and no external reference", "[report][html][accuracy]") {
  const ordered_json& report = SweepReport();
  REQUIRE(report["cross_axis"].size() == 2);
  REQUIRE(report["budget"].size() == 2);
  Result<std::string> html = RenderJsonHtml(report, "acc.json");
  REQUIRE(html.ok());
  const std::string h = DecodeCharRefs(html.value());
  CheckSelfContained(html.value());
  CHECK(h.find("<title>Accuracy report: table_sweep.csv</title>") != std::string::npos);
  CHECK(h.find("No dedicated view") == std::string::npos);
  CHECK(Count(h, "<svg") == ExpectedPlots(report));
  CHECK(Count(h, "<figure>") == ExpectedPlots(report));
  // Both sweep directions are drawn (their legend entries) and the fitted curve and band.
  CHECK(h.find("turning up (+-U_i)") != std::string::npos);
  CHECK(h.find("turning down (+-U_i)") != std::string::npos);
  CHECK(h.find("fitted error curve e(theta)") != std::string::npos);
  CHECK(h.find("band e +- ") != std::string::npos);
  // One row per plateau in the plateau table and one per hysteresis pair.
  CHECK(Count(h, "<td>up</td>") + Count(h, "<td>down</td>") + Count(h, "<td>first</td>") ==
        report["points"].size());
  // Each plateau's error rounded per GUM 7.2.6 to its u.
  for (const auto& p : report["points"]) {
    const RoundedResult r =
        RoundForStatement(p["error_deg"].get<double>(), p["type_a"]["u_deg"].get<double>());
    INFO(p.dump());
    CHECK(h.find("<td class=\"num\">" + r.value + "</td><td class=\"num\">" + r.uncertainty +
                 "</td>") != std::string::npos);
  }
  CHECK(h.find("a single yaw_deg reading corrected by the fitted curve") != std::string::npos);
  CHECK(h.find("Hysteresis and repeatability") != std::string::npos);
  CHECK(h.find("Cross-axis: pitch_deg against the reference angle") != std::string::npos);
  CHECK(h.find("Cross-axis: roll_deg against the reference angle") != std::string::npos);
}

// A hand-made report whose numbers are checked against published Student t quantiles:
// t_0.975(4) = 2.776, t_0.975(9) = 2.262, z_0.975 = 1.960 (e.g. JCGM 100:2008 Table G.2).
// The sweep's report with its points, fit, corrected budget and statements replaced by hand
// values, the cross-axis section not evaluated and no hysteresis.
ordered_json HandReport() {
  ordered_json doc = SweepReport();
  doc["input"]["session"] = "hand.csv";
  const ordered_json base = doc["points"][0];
  const auto point = [&base](double reference, double mean, double error, const char* direction,
                             double u, double n_eff, const ordered_json& dof) {
    ordered_json p = base;
    p["reference_deg"] = reference;
    p["mean_deg"] = mean;
    p["error_deg"] = error;
    p["direction"] = direction;
    p["type_a"] = {{"n", 50}, {"std_deg", 0.05}, {"u_deg", u}, {"n_eff", n_eff}, {"dof", dof}};
    for (auto& item : p["other_axes_mean_deg"].items()) item.value() = nullptr;
    for (auto& item : p["other_axes_u_deg"].items()) item.value() = nullptr;
    return p;
  };
  doc["points"] = {point(0, 0.1234567, 0.1234567, "first", 0.0123, 5, 4),
                   point(90, 90.2, 0.2, "up", 0.01, 1e9, nullptr),
                   point(45, 44.95, -0.05, "down", 0.02, 10, 9)};
  ordered_json& fit = doc["fit"];
  fit["model"] = "linear";
  fit["params"] =
      ordered_json::parse(R"([{"name": "c0_deg", "value": 0.1, "u": 0.01, "unit": "deg"},
      {"name": "scale", "value": 0.001, "u": 0.0001, "unit": "deg/deg"}])");
  fit["covariance"] = ordered_json::parse("[[1e-4, 0], [0, 1e-8]]");
  fit["chi2"] = 1.0;
  fit["dof"] = 1;
  fit["reduced_chi2"] = 1.0;
  fit["residuals_deg"] = {0.0, 0.0, 0.0};
  doc["budget"]["corrected"] = ordered_json::parse(R"({"u_deg": 0.02, "dof_eff": 30, "k": 2.04,
      "U_deg": 0.0408, "coverage": 0.95, "dof_note": "",
      "inputs": [{"name": "small_input", "u_deg": 0.001, "distribution": "normal",
                  "sensitivity": 1, "contribution_deg": 0.001, "dof": null, "percent": 0.25,
                  "note": ""},
                 {"name": "big_input", "u_deg": 0.0199, "distribution": "normal",
                  "sensitivity": 1, "contribution_deg": 0.0199, "dof": null, "percent": 99.75,
                  "note": ""}]})");
  doc["result"]["statement_corrected"] = "STATEMENT-C";
  doc["result"]["statement_uncorrected"] = "STATEMENT-U";
  ordered_json& h = doc["hysteresis"];
  h["available"] = false;
  for (const char* key :
       {"mean_deg", "u_mean_deg", "max_abs_deg", "u_max_abs_deg", "at_reference_deg"}) {
    h[key] = nullptr;
  }
  h["pairs"] = ordered_json::array();
  for (auto& item : doc["cross_axis"].items()) {
    item.value() = {{"evaluated", false},
                    {"mean_deg", nullptr},
                    {"span_deg", nullptr},
                    {"fitted", false},
                    {"note", "no other angles"}};
  }
  return doc;
}

TEST_CASE("Accuracy HTML rounds per GUM 7.2.6 with k from the t distribution",
          "[report][html][accuracy]") {
  const ordered_json doc = HandReport();
  Result<std::string> html = RenderJsonHtml(doc, "hand.json");
  if (!html.ok()) FAIL(html.error().ToString());
  const std::string& h = html.value();
  CheckSelfContained(h);
  CHECK(Count(h, "<svg") == 3);  // The error plot and the two budgets' bars.
  // Point 1: e = 0.1234567, u = 0.0123 -> 0.123, 0.012; U = 2.776 * 0.0123 = 0.03415 -> 0.034.
  CHECK(h.find("<td class=\"num\">0.123</td><td class=\"num\">0.012</td><td class=\"num\">5</td>"
               "<td class=\"num\">2.78</td><td class=\"num\">0.034</td>") != std::string::npos);
  // Point 2: infinite dof -> k = 1.96, U = 0.0196 -> 0.020.
  CHECK(h.find("<td class=\"num\">1.96</td><td class=\"num\">0.020</td>") != std::string::npos);
  // Point 3: dof 9 -> k = 2.262, U = 0.04524 -> 0.045; e = -0.05 with u = 0.02 -> -0.050.
  CHECK(h.find("<td class=\"num\">-0.050</td><td class=\"num\">0.020</td>") != std::string::npos);
  CHECK(h.find("<td class=\"num\">2.26</td><td class=\"num\">0.045</td>") != std::string::npos);
  // Fit parameters rounded to their u: 0.100 +- 0.010, 0.00100 +- 0.00010.
  CHECK(h.find("<td>c0_deg</td><td class=\"num\">0.100</td><td class=\"num\">0.010</td>") !=
        std::string::npos);
  CHECK(h.find("<td>scale</td><td class=\"num\">0.00100</td><td class=\"num\">0.00010</td>") !=
        std::string::npos);
  // Budget lines sorted by share, largest first.
  const size_t big = h.find("<td>big_input</td>");
  const size_t small = h.find("<td>small_input</td>");
  REQUIRE(big != std::string::npos);
  REQUIRE(small != std::string::npos);
  CHECK(big < small);
  CHECK(h.find("STATEMENT-C") != std::string::npos);
  CHECK(h.find("STATEMENT-U") != std::string::npos);
  CHECK(h.find("Hysteresis not available") != std::string::npos);
  CHECK(h.find("<title>Accuracy report: hand.csv</title>") != std::string::npos);
}

TEST_CASE("Accuracy HTML lists the options as a table and names the tag",
          "[report][html][accuracy]") {
  const ordered_json& report = SweepReport();
  Result<std::string> html = RenderJsonHtml(report, "acc.json");
  REQUIRE(html.ok());
  const std::string& h = html.value();
  const size_t at = h.find("<table id=\"options-table\">");
  REQUIRE(at != std::string::npos);
  const std::string table = h.substr(at, h.find("</table>", at) - at);
  // One row per option of the JSON (every leaf is a scalar here), with its value.
  size_t rows = 0;
  for (const auto& item : report["options"].items()) {
    INFO(item.key());
    REQUIRE_FALSE(item.value().is_structured());
    const std::string value = item.value().is_null()     ? "not set"
                              : item.value().is_string() ? item.value().get<std::string>()
                                                         : JsonText(item.value());
    CHECK(table.find("<tr><th>" + item.key() + "</th><td>" + value + "</td></tr>") !=
          std::string::npos);
    ++rows;
  }
  CHECK(Count(table, "<tr><th>") == rows + 1);  // The header row and one per option.
  CHECK(h.find(JsonText(report["options"])) == std::string::npos);  // No raw JSON string.
  // The tag's name in the input table (thesis Table 5.2 without a tags file).
  CHECK(h.find("<tr><th>tag</th><td><code>" + report["input"]["tag"]["name"].get<std::string>() +
               "</code></td></tr>") != std::string::npos);
}

using testing::LineColumn;

TEST_CASE("Bad accuracy report input is refused with a message", "[report][html][accuracy]") {
  // Read with AccuracyReportFromJson: the position of the value in the document as metro writes
  // it (indent 2) and its path.
  ordered_json doc = HandReport();
  doc.erase("points");
  Result<std::string> r = RenderJsonHtml(doc, "bad.json");
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().ToString() ==
        "bad.json:1:1: points: expected an array of plateau points, found nothing (the member is "
        "missing)");

  doc = HandReport();
  doc["points"] = ordered_json::array();
  r = RenderJsonHtml(doc, "bad.json");
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().file == "bad.json");
  CHECK(r.error().message == "metro.accuracy-report/1 report: 'points' is not a non-empty array");

  doc = HandReport();
  doc["points"][1]["type_a"].erase("u_deg");
  std::string text = JsonText(doc, 2);
  r = RenderJsonHtml(doc, "bad.json");
  REQUIRE_FALSE(r.ok());
  // Missing: at the object it belongs to, the "type_a" of the second point (n = 50 first).
  const size_t second = text.find("\"type_a\": {", text.find("\"reference_deg\": 90"));
  REQUIRE(second != std::string::npos);
  CHECK(r.error().ToString() ==
        "bad.json:" + LineColumn(text, second + 10) +
            ": points[1].type_a.u_deg: expected a number or null, found nothing (the member is "
            "missing)");

  doc = HandReport();
  doc["budget"] = "none";
  text = JsonText(doc, 2);
  r = RenderJsonHtml(doc, "bad.json");
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().ToString() ==
        "bad.json:" + LineColumn(text, text.find("\"budget\": \"none\"") + 10) +
            ": budget: expected an object {corrected, uncorrected}, "
            "found the string \"none\"");
}

#ifdef METRO_CHARACTERIZE_EXE
std::string Slurp(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

TEST_CASE("characterize --accuracy --html and characterize report render the accuracy view",
          "[report][html][accuracy][apps]") {
  const std::string json = "metro_acc_view.json";
  const std::string html = "metro_acc_view.html";
  const std::string html2 = "metro_acc_view2.html";
  for (const std::string& f : {json, html, html2}) std::remove(f.c_str());
  testing::ProgramRun r =
      testing::RunProgram(METRO_CHARACTERIZE_EXE,
                          kSweep + " --accuracy --reference-u 0.01 -o " + json + " --html " + html);
  INFO(r.err);
  REQUIRE(r.exit_code == 0);
  const std::string page = Slurp(html);
  CheckSelfContained(page);
  const ordered_json report = ordered_json::parse(Slurp(json));
  CHECK(Count(page, "<svg") == ExpectedPlots(report));
  CHECK(page.find("<title>Accuracy report: table_sweep.csv</title>") != std::string::npos);

  r = testing::RunProgram(METRO_CHARACTERIZE_EXE, "report " + json + " --html " + html2);
  REQUIRE(r.exit_code == 0);
  const std::string page2 = Slurp(html2);
  CheckSelfContained(page2);
  CHECK(Count(page2, "<svg") == ExpectedPlots(report));
  CHECK(page2.find("No dedicated view") == std::string::npos);

  // The HTML may not overwrite the session nor the JSON (exit 2).
  r = testing::RunProgram(METRO_CHARACTERIZE_EXE,
                          kSweep + " --accuracy -o " + json + " --html " + kSweep);
  CHECK(r.exit_code == 2);
  CHECK(r.err.find("is the input file: refusing to overwrite it") != std::string::npos);
  r = testing::RunProgram(METRO_CHARACTERIZE_EXE,
                          kSweep + " --accuracy -o " + json + " --html " + json);
  CHECK(r.exit_code == 2);
  CHECK(r.err.find("--html and -o name the same file") != std::string::npos);
  for (const std::string& f : {json, html, html2}) std::remove(f.c_str());
}
#endif

}  // namespace
}  // namespace metro
