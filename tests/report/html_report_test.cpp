// HTML reports: structure (plots present, nothing external), the session-less path, the
// schema dispatch and bad input.
#include "metro/report/html_report.hpp"

#include <fmt/format.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "core/json_text.hpp"
#include "metro/core/file.hpp"
#include "metro/core/rounding.hpp"
#include "metro/noise/allan.hpp"
#include "metro/uncertainty/budget.hpp"
#include "metro/uncertainty/budget_report.hpp"
#include "report/html_dispatch.hpp"
#include "report/session_report_json.hpp"
#include "support/html_checks.hpp"
#include "support/temp_file.hpp"
#include "uncertainty/budget_report_json.hpp"

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

// ImuAnalysis's report in its JSON form, as a reader of the saved file sees it.
const ordered_json& ImuJson() {
  static const ordered_json json = ToJsonValue(ImuAnalysis().report);
  return json;
}

// Plots the report calls for, counted from the JSON: per evaluated quantity with plot data
// and s > 0 a time series, a histogram and an autocorrelation (only the time series when
// s = 0), plus an Allan plot where the report has an Allan curve, and per tag one combined
// plot per sensor group (ax_g ay_g az_g; gx_dps gy_dps gz_dps) with two or more Allan curves.
size_t ExpectedPlots(const ordered_json& report) {
  size_t n = 0;
  for (const auto& s : report["sensors"]) {
    std::map<std::string, int> groups;  // "a_g" -> Allan curves of ax_g, ay_g, az_g.
    for (const auto& [name, q] : s["quantities"].items()) {
      if (!q["type_a"].is_object()) continue;
      if (q.contains("plot")) n += q["type_a"]["std"].get<double>() > 0.0 ? 3 : 1;
      if (q.contains("allan") && q["allan"].contains("tau_s")) {
        ++n;
        const size_t underscore = name.find('_');
        if (underscore >= 2 && std::string("xyz").find(name[underscore - 1]) != std::string::npos) {
          ++groups[name.substr(0, underscore - 1) + name.substr(underscore)];
        }
      }
    }
    for (const auto& g : groups) n += g.second >= 2 ? 1 : 0;
  }
  return n;
}

// The text of the cell with class `cls` in the table row with id `row_id` ("" when absent).
std::string Cell(const std::string& html, const std::string& row_id, const std::string& cls) {
  const size_t row = html.find("<tr id=\"" + row_id + "\">");
  if (row == std::string::npos) return "";
  const size_t row_end = html.find("</tr>", row);
  const std::string open = "<td class=\"num " + cls + "\">";
  const size_t at = html.find(open, row);
  if (at == std::string::npos || at > row_end) return "";
  const size_t begin = at + open.size();
  return html.substr(begin, html.find("</td>", begin) - begin);
}

// The leaf keys of an options object as the page names them ("autocorrelation.method").
void LeafKeys(const ordered_json& j, const std::string& prefix, std::vector<std::string>* out) {
  for (const auto& [key, value] : j.items()) {
    const std::string name = prefix.empty() ? key : prefix + "." + key;
    if (value.is_object()) {
      LeafKeys(value, name, out);
    } else {
      out->push_back(name);
    }
  }
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
  const size_t expected = ExpectedPlots(ImuJson());
  CHECK(expected >= 3 * 6 + 6 + 2);  // Six rate quantities with Allan curves, two groups.
  CHECK(Count(h, "<svg") == expected);
  // The summary states the mean rounded per GUM 7.2.6 to two digits of u(mean).
  const auto& gx = ImuJson()["sensors"][0]["quantities"]["gx_dps"]["type_a"];
  const RoundedResult r = RoundForStatement(gx["mean"].get<double>(), gx["u_mean"].get<double>());
  CHECK(h.find("<td class=\"num\">" + r.value + "</td><td class=\"num\">" + r.uncertainty +
               "</td>") != std::string::npos);
  // The settle window is shaded and named.
  CHECK(h.find("shaded: observations left out of the Type A window") != std::string::npos);
}

TEST_CASE("Session page opens with the result: value U k and p as the JSON rounded per 7.2.6",
          "[report][html]") {
  const SessionAnalysis& a = ImuAnalysis();
  REQUIRE(a.ok);
  // From the JSON alone (as characterize report renders a saved report) and with the session.
  for (const bool with_session : {false, true}) {
    Result<std::string> html =
        with_session ? RenderSessionAnalysisHtml(a) : RenderSessionReportHtml(a.report);
    REQUIRE(html.ok());
    const std::string& h = html.value();
    // The result is the page's first section, before the input and the options.
    const size_t result = h.find("<section id=\"result\">");
    REQUIRE(result != std::string::npos);
    CHECK(result < h.find("<section id=\"input\">"));
    CHECK(result < h.find("<section id=\"options\">"));
    CHECK(h.find("<section") == result);
    int rows = 0;
    for (const auto& s : ImuJson()["sensors"]) {
      const std::string sensor = std::to_string(s["sensor"].get<int>());
      for (const auto& [name, q] : s["quantities"].items()) {
        if (!q["type_a"].is_object()) continue;
        const ordered_json& t = q["type_a"];
        const std::string id = "result-" + sensor + "-" + name;
        INFO(id);
        CHECK(Cell(h, id, "p") == "95 %");
        if (t["U_mean"].is_null()) {
          CHECK(Cell(h, id, "U") == "-");
          CHECK(Cell(h, id, "k") == "-");
          continue;
        }
        ++rows;
        // U = k u(mean), k = t_0.975(nu); for nu >= 30 the Cornish-Fisher expansion of t
        // about the normal quantile z = 1.959964 is within 1e-4 of it: t = z + (z^3 + z) /
        // (4 nu) + (5 z^5 + 16 z^3 + 3 z) / (96 nu^2) (Abramowitz and Stegun 26.7.5).
        CHECK(t["U_mean"].get<double>() ==
              Approx(t["k"].get<double>() * t["u_mean"].get<double>()).epsilon(1e-15));
        const double nu = t["u_mean_dof"].get<double>();
        const double z = 1.959963984540054;
        REQUIRE(nu >= 30.0);
        CHECK(t["k"].get<double>() ==
              Approx(z + (z * z * z + z) / (4.0 * nu) +
                     (5.0 * std::pow(z, 5) + 16.0 * z * z * z + 3.0 * z) / (96.0 * nu * nu))
                  .margin(1e-4));
        const RoundedResult r =
            RoundForStatement(t["mean"].get<double>(), t["U_mean"].get<double>());
        CHECK(Cell(h, id, "value") == r.value);
        CHECK(Cell(h, id, "U") == r.uncertainty);
        CHECK(Cell(h, id, "k") == fmt::format("{:.3g}", t["k"].get<double>()));
      }
    }
    CHECK(rows >= 6);
  }
  // temp_c drifts: its u(mean) has fewer than one degree of freedom, so no U is stated and
  // the page says why.
  const ordered_json& temp = ImuJson()["sensors"][0]["quantities"]["temp_c"]["type_a"];
  REQUIRE(temp["u_mean_dof"].get<double>() < 1.0);
  CHECK(temp["k"].is_null());
  Result<std::string> html = RenderSessionAnalysisHtml(a);
  REQUIRE(html.ok());
  CHECK(html.value().find("sensor 1 temp_c: no U: u(mean) = ") != std::string::npos);
}

TEST_CASE("Session page of a report saved before U was recorded states no U and says why",
          "[report][html]") {
  ordered_json old = ImuJson();
  for (auto& [name, q] : old["sensors"][0]["quantities"].items()) {
    if (!q["type_a"].is_object()) continue;
    for (const char* key : {"coverage", "k", "U_mean"}) q["type_a"].erase(key);
  }
  Result<SessionReport> old_report = SessionReportFromJson(JsonText(old, 2), "old.json");
  REQUIRE(old_report.ok());
  Result<std::string> html = RenderSessionReportHtml(old_report.value());
  REQUIRE(html.ok());
  CHECK(Cell(html.value(), "result-1-gx_dps", "U") == "-");
  CHECK(Cell(html.value(), "result-1-gx_dps", "k") == "-");
  CHECK(Cell(html.value(), "result-1-gx_dps", "p") == "-");
  CHECK(html.value().find("sensor 1 gx_dps: the report states no U (written before metro "
                          "recorded it): run characterize again") != std::string::npos);
}

TEST_CASE("Session page states the options as a table and not as the JSON string",
          "[report][html]") {
  const SessionAnalysis& a = ImuAnalysis();
  REQUIRE(a.ok);
  Result<std::string> html = RenderSessionAnalysisHtml(a);
  REQUIRE(html.ok());
  const std::string& h = html.value();
  const size_t table = h.find("<table id=\"options-table\">");
  REQUIRE(table != std::string::npos);
  const std::string options = h.substr(table, h.find("</table>", table) - table);
  std::vector<std::string> keys;
  LeafKeys(ImuJson()["options"], "", &keys);
  CHECK(keys.size() >= 10);
  for (const std::string& key : keys) {
    INFO(key);
    CHECK(options.find("<tr><th>" + key + "</th><td>") != std::string::npos);
  }
  CHECK(options.find("<tr><th>settle</th><td>auto</td></tr>") != std::string::npos);
  CHECK(options.find("<tr><th>from_s</th><td>not set</td></tr>") != std::string::npos);
  // The raw JSON is gone (as the page escaped it and as it is).
  const std::string raw = JsonText(ImuJson()["options"]);
  CHECK(h.find(raw) == std::string::npos);
  CHECK(h.find("{&quot;skip_samples&quot;") == std::string::npos);
  CHECK(h.find("window options") == std::string::npos);
}

TEST_CASE("Session page noise table: density, Allan minimum and u(mean) from the JSON",
          "[report][html]") {
  const SessionAnalysis& a = ImuAnalysis();
  REQUIRE(a.ok);
  Result<std::string> html = RenderSessionReportHtml(a.report);
  REQUIRE(html.ok());
  const std::string& h = html.value();
  int rows = 0;
  for (const auto& [name, q] : ImuJson()["sensors"][0]["quantities"].items()) {
    if (!q.contains("allan")) continue;
    const std::string id = "noise-1-" + name;
    INFO(id);
    const ordered_json& white = q["allan"]["noise"]["random_walk"];
    const ordered_json& link = q["allan_type_a_link"];
    const double d = white["density_one_sided"].get<double>();
    const double u_d = white["u_density_one_sided"].get<double>();
    // The one-sided density is sqrt(2) N (IEEE Std 952-1997: sigma(1 s) = N = d / sqrt 2).
    CHECK(d == Approx(std::sqrt(2.0) * white["value"].get<double>()).epsilon(1e-14));
    CHECK(Cell(h, id, "density") == ConciseNotation(d, u_d));
    CHECK(Cell(h, id, "sigma-min") == fmt::format("{:.3g}", link["allan_min_dev"].get<double>()));
    CHECK_THAT(Cell(h, id, "tau-min"),
               Catch::StartsWith(fmt::format("{:.3g}", link["allan_min_tau_s"].get<double>())));
    CHECK(Cell(h, id, "u-mean-allan") ==
          RoundForStatement(0.0, link["u_mean_allan"].get<double>()).uncertainty);
    CHECK(Cell(h, id, "u-mean") ==
          RoundForStatement(0.0, q["type_a"]["u_mean"].get<double>()).uncertainty);
    // The accelerometer's density also in ug/sqrt(Hz) (1 g = 1e6 ug).
    if (q["unit"] == "g") {
      CHECK(Cell(h, id, "density-conventional") ==
            ConciseNotation(1e6 * d, 1e6 * u_d) + " ug/sqrt(Hz)");
    }
    ++rows;
  }
  CHECK(rows == 6);
}

TEST_CASE("Session page draws the x y and z Allan curves of a sensor in one plot with decades",
          "[report][html]") {
  const SessionAnalysis& a = ImuAnalysis();
  REQUIRE(a.ok);
  Result<std::string> html = RenderSessionReportHtml(a.report);
  REQUIRE(html.ok());
  const std::string& h = html.value();
  // Octave taus from 0.01 s to 10.24 s: the decades 0.01, 0.1, 1 and 10 s.
  const ordered_json& tau = ImuJson()["sensors"][0]["quantities"]["gx_dps"]["allan"]["tau_s"];
  REQUIRE(tau.front().get<double>() == Approx(0.01));
  REQUIRE(tau.back().get<double>() == Approx(10.24));
  for (const std::string names : {"ax_g, ay_g and az_g", "gx_dps, gy_dps and gz_dps"}) {
    INFO(names);
    // The figure's caption follows its SVG.
    const size_t at = h.find("oadev of " + names + " on log-log axes, one colour per axis");
    REQUIRE(at != std::string::npos);
    const size_t begin = h.rfind("<svg", at);
    const std::string svg = h.substr(begin, at - begin);
    // A legend entry per axis (PLplot writes text as hexadecimal character references) and
    // each axis in its colour: x blue, y orange, z green.
    const std::string unit = names.substr(2, names.find(',') - 2);  // "_g"
    for (const char axis : {'x', 'y', 'z'}) {
      std::string entry;
      for (const char c : names.substr(0, 1) + axis + unit) entry += fmt::format("&#x{:x};", c);
      CHECK(svg.find(">" + entry + "<") != std::string::npos);
    }
    for (const char* color : {"#1F77B4", "#FF7F0E", "#2CA02C"}) {
      CHECK(svg.find(std::string("stroke=\"") + color + "\"") != std::string::npos);
    }
    // One vertical decade line at each of the four decades, equally spaced (x is log10 tau;
    // the SVG writes 0.01 px).
    std::vector<double> decades;
    for (size_t p = svg.find("stroke=\"#B0B8C2\""); p != std::string::npos;
         p = svg.find("stroke=\"#B0B8C2\"", p + 1)) {
      const size_t points = svg.find("points=\"", p) + 8;
      double x0 = 0, y0 = 0, x1 = 0, y1 = 0;
      REQUIRE(std::sscanf(svg.c_str() + points, "%lf,%lf %lf,%lf", &x0, &y0, &x1, &y1) == 4);
      if (std::fabs(x0 - x1) < 0.01) decades.push_back(x0);
    }
    REQUIRE(decades.size() == 4);
    std::sort(decades.begin(), decades.end());
    CHECK(decades[2] - decades[1] == Approx(decades[1] - decades[0]).margin(0.05));
    CHECK(decades[3] - decades[2] == Approx(decades[1] - decades[0]).margin(0.05));
  }
}

// The text of a page's plots: PLplot writes each character as a hexadecimal reference
// ("&#x61;" for 'a'); these are decoded, the rest kept.
std::string PlotText(const std::string& html) {
  std::string out;
  for (size_t i = 0; i < html.size(); ++i) {
    if (html.compare(i, 3, "&#x") == 0) {
      const size_t end = html.find(';', i);
      const long code = std::strtol(html.substr(i + 3, end - i - 3).c_str(), nullptr, 16);
      out += code < 128 ? static_cast<char>(code) : '?';
      i = end;
    } else {
      out += html[i];
    }
  }
  return out;
}

TEST_CASE("Session page axes carry their scale in the label and no detached multiplier",
          "[report][html]") {
  const SessionAnalysis& a = ImuAnalysis();
  REQUIRE(a.ok);
  Result<std::string> html = RenderSessionAnalysisHtml(a);
  REQUIRE(html.ok());
  const std::string text = PlotText(html.value());
  // PLplot's multiplier is a "(x10" beside the axis: az_g near 0.97 g with a spread of
  // 0.01 g was labelled 9.6 .. 9.8 "(x10^-1)".
  CHECK(text.find("(x10") == std::string::npos);
  // az_g: the values sit 100 spreads away from zero, so the axis is az_g minus its mean
  // rounded to the span (0.971 g), in mg; rho_k stays within +-0.05: in thousandths.
  const double mean = ImuJson()["sensors"][0]["quantities"]["az_g"]["type_a"]["mean"].get<double>();
  REQUIRE(std::fabs(mean - 0.971) < 0.0005);
  CHECK(text.find(">az_g - 0.971 g [1e-3 g]<") != std::string::npos);
  CHECK(text.find(">rho_k [1e-3]<") != std::string::npos);
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

TEST_CASE("Report without plot data keeps the Allan plots and says to analyse again",
          "[report][html]") {
  // A report written before metro kept plot data: no quantity has "plot".
  ordered_json old = ImuJson();
  for (auto& s : old["sensors"]) {
    for (auto& [name, q] : s["quantities"].items()) q.erase("plot");
  }
  Result<SessionReport> report = SessionReportFromJson(JsonText(old, 2), "old.json");
  REQUIRE(report.ok());
  Result<std::string> html = RenderSessionReportHtml(report.value());
  REQUIRE(html.ok());
  CheckSelfContained(html.value());
  // Only the Allan curves and groups: six rate quantities and two sensor groups.
  CHECK(ExpectedPlots(old) == 6 + 2);
  CHECK(Count(html.value(), "<svg") == ExpectedPlots(old));
  CHECK(html.value().find("This report predates the plot data") != std::string::npos);
  CHECK(html.value().find("unavailable (the report predates plot data; run characterize analyze "
                          "again)") != std::string::npos);
}

TEST_CASE("Saved report draws every plot from its plot data without the session",
          "[report][html]") {
  const SessionAnalysis& a = ImuAnalysis();
  REQUIRE(a.ok);
  testing::TempFile json(ToJson(a.report), ".json");
  Result<std::string> html = RenderJsonFileHtml(json.path());
  REQUIRE(html.ok());
  CHECK(html.value().find("drawn from the plot data computed when the session was analysed") !=
        std::string::npos);
  CHECK(Count(html.value(), "<svg") == ExpectedPlots(ImuJson()));
  CHECK(ExpectedPlots(ImuJson()) == 3 * 7 + 6 + 2);  // Seven quantities, six Allan curves.
  // The same page as the one drawn at analysis time (but for the time it was made).
  Result<std::string> live = RenderSessionAnalysisHtml(a);
  REQUIRE(live.ok());
  CHECK(testing::WithoutFooter(html.value()) == testing::WithoutFooter(live.value()));
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

  // An array of objects whose keys all differ was one table of every row by every key: an
  // 83 KB file made a 225 MB page in 60 s (issue #37). Past 32 columns each element is its
  // own small table, so the page grows with the document: here about 50 bytes of page per
  // byte of key text at most, against 5000 x 5000 cells before.
  std::string distinct = "[";
  for (int i = 0; i < 5000; ++i) {
    distinct += (i ? "," : "") + ("{\"k" + std::to_string(i) + "\":" + std::to_string(i) + "}");
  }
  distinct += "]";
  testing::TempFile wide(distinct, ".json");
  r = RenderJsonFileHtml(wide.path());
  REQUIRE(r.ok());
  CHECK(r.value().size() < 50 * distinct.size());
  CHECK(r.value().find("k4999") != std::string::npos);
  // A few columns are still one table: one header row naming them once.
  testing::TempFile narrow(R"([{"a": 1, "b": 2}, {"a": 3, "c": 4}])", ".json");
  r = RenderJsonFileHtml(narrow.path());
  REQUIRE(r.ok());
  CHECK(r.value().find("<tr><th>a</th><th>b</th><th>c</th></tr>") != std::string::npos);

  r = RenderJsonFileHtml("no_such_report.json");
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().ToString().find("no_such_report.json") != std::string::npos);

  // A report is read with SessionReportFromJson: the first wrong or missing value is named
  // at its line and column with its path (the root object opens at 1:1).
  const ordered_json missing = ordered_json::parse(R"({"schema": "metro.report/1", "input": {}})");
  r = RenderJsonHtml(missing, "r.json");
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().ToString() ==
        "r.json:1:1: tool.name: expected a string, found nothing (the member is missing)");
  // A saved report with a wrong value deep inside: line 2, column 12 of the file.
  testing::TempFile wrong("{\"schema\": \"metro.report/1\",\n \"tool\": {\"name\": 7}}", ".json");
  r = RenderJsonFileHtml(wrong.path());
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().ToString() ==
        wrong.path() + ":2:19: tool.name: expected a string, found the number 7");

  HtmlReportOptions o;
  o.max_plotted_quantities = -1;
  std::string why;
  CHECK_FALSE(o.IsValid(&why));
  CHECK(why == "html: max_plotted_quantities must be >= 0");
  r = RenderSessionAnalysisHtml(ImuAnalysis(), o);
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().message == "html: max_plotted_quantities must be >= 0");

  SessionAnalysis failed;
  r = RenderSessionAnalysisHtml(failed);
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().message == "no HTML report of a failed analysis");
}

}  // namespace
}  // namespace metro
