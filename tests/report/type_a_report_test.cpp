// The report's `input` block says how a text file was read (docs/report-schema.md): the
// dialect, every renamed column, the time column and its unit, notes and warnings, and the
// table for people shows the warnings.
#include <catch2/catch.hpp>
#include <cmath>
#include <string>

#include "metro/report/html_report.hpp"
#include "metro/report/session_analysis.hpp"
#include "report/session_report_json.hpp"
#include "support/temp_file.hpp"

namespace metro {
namespace {

using testing::TempFile;

TEST_CASE("the input block records the dialect, mapping and time", "[report][dialect]") {
  // 1.5 and 2.5 deg/s: mean 2, written with decimal commas; times in ms.
  TempFile file(
      "\xEF\xBB\xBF"
      "Time (ms);gyro_z (deg/s)\r\n0;1,5\r\n10;2,5\r\n20;1,5\r\n30;2,5\r\n");
  SessionAnalysisOptions options;
  options.load.column_map = {{"Time (ms)", "t_ms"}, {"gyro_z (deg/s)", "gz_dps"}};
  SessionAnalysis a = AnalyzeSession(file.path(), options);
  REQUIRE(a.ok);
  nlohmann::ordered_json report_a = ToJsonValue(a.report);
  const auto& input = report_a["input"];
  CHECK(input["format"] == "phone");  // The header spells its axis and unit (Time (ms)).
  CHECK(input["dialect"]["delimiter"] == ";");
  CHECK(input["dialect"]["decimal_point"] == ",");
  CHECK(input["dialect"]["line_ends"] == "CRLF");
  CHECK(input["dialect"]["bom"] == true);
  REQUIRE(input["mapping"].size() == 2);
  CHECK(input["mapping"][1]["source"] == "gyro_z (deg/s)");
  CHECK(input["mapping"][1]["canonical"] == "gz_dps");
  CHECK(input["time"]["unit"] == "ms");
  CHECK(input["time"]["integer"] == true);
  CHECK(input["time"]["origin_ns"] == 0);
  const auto& q = report_a["sensors"][0]["quantities"]["gz_dps"]["type_a"];
  CHECK(q["n"] == 4);
  CHECK(q["mean"].get<double>() == 2.0);
  // Sample variance of 1.5, 2.5, 1.5, 2.5: 4 * 0.25 / 3.
  CHECK(q["variance"].get<double>() == Approx(1.0 / 3.0).epsilon(1e-15));
}

TEST_CASE("terms that were not computed are null with the reason, never 0 or n",
          "[report][type_a]") {
  // gy_dps is constant; gz_dps varies over 20 samples; a second file has n = 3.
  std::string text = "t_s,gy_dps,gz_dps\n";
  for (int i = 0; i < 20; ++i)
    text += std::to_string(0.1 * i) + ",0.25," + std::to_string(i % 3) + "\n";
  TempFile file(text);
  SessionAnalysis a = AnalyzeSession(file.path(), SessionAnalysisOptions{});
  REQUIRE(a.ok);
  nlohmann::ordered_json report_a = ToJsonValue(a.report);
  const auto& quantities = report_a["sensors"][0]["quantities"];
  const auto& constant = quantities["gy_dps"]["type_a"];
  CHECK(constant["mean"].get<double>() == 0.25);
  for (const char* key : {"n_eff", "rho1", "autocorr_cutoff_lag", "std_of_mean_autocorr", "u_mean",
                          "u_mean_dof", "u_mean_method"}) {
    INFO(key);
    CHECK(constant[key].is_null());
  }
  CHECK_THAT(constant["autocorr_note"].get<std::string>(), Catch::Contains("constant"));
  const auto& varying = quantities["gz_dps"]["type_a"];
  CHECK(varying["autocorr_note"].is_null());
  CHECK(varying["n_eff"].is_number());
  CHECK(varying["u_mean"].get<double>() > 0.0);
  // The HTML says "not computed" where the report has null, never "nan".
  Result<std::string> html = RenderSessionAnalysisHtml(a);
  REQUIRE(html.ok());
  CHECK_THAT(html.value(), Catch::Contains(">not computed<"));
  CHECK_THAT(html.value(), !Catch::Contains(">nan<"));

  TempFile three("t_s,gz_dps\n0,1\n0.1,2\n0.2,4\n");
  SessionAnalysis b = AnalyzeSession(three.path(), SessionAnalysisOptions{});
  REQUIRE(b.ok);
  nlohmann::ordered_json report_b = ToJsonValue(b.report);
  const auto& small = report_b["sensors"][0]["quantities"]["gz_dps"]["type_a"];
  CHECK(small["n_eff"].is_null());
  CHECK(small["rho1"].is_null());
  CHECK(small["autocorr_note"].is_string());
  // n <= 3: the classical s / sqrt(n) with n - 1 dof (s^2 of 1, 2, 4 is 7/3).
  CHECK(small["u_mean"].get<double>() == Approx(std::sqrt(7.0 / 3.0 / 3.0)).epsilon(1e-12));
  CHECK(small["u_mean_dof"].get<double>() == 2.0);
  // U_mean = k u_mean with k = t_0.975(2) for p = 95 %: Student's t at 2 dof in closed form,
  // t_a = (2a - 1) / sqrt(2 a (1 - a)) = 4.3027 (JCGM 100:2008 Table G.2: 4.30); none for the
  // constant series.
  const double t2 = (2.0 * 0.975 - 1.0) / std::sqrt(2.0 * 0.975 * 0.025);
  CHECK(small["coverage"].get<double>() == 0.95);
  CHECK(small["k"].get<double>() == Approx(t2).epsilon(1e-12));
  CHECK(small["U_mean"].get<double>() == Approx(t2 * std::sqrt(7.0 / 3.0 / 3.0)).epsilon(1e-12));
  CHECK(constant["k"].is_null());
  CHECK(constant["U_mean"].is_null());
}

TEST_CASE("input warnings reach the table", "[report][dialect]") {
  TempFile file("t_ns,gz_dps\n1.0E+10,1\n1.1E+10,2\n1.2E+10,3\n");
  SessionAnalysis a = AnalyzeSession(file.path(), SessionAnalysisOptions{});
  REQUIRE(a.ok);
  nlohmann::ordered_json report_a = ToJsonValue(a.report);
  REQUIRE(report_a["input"]["warnings"].size() == 1);
  // 1.1E+10 ns = 11 s: its last written digit is the 1e9 ns place.
  CHECK(report_a["input"]["time"]["resolution_s"].get<double>() == 1.0);
  CHECK_THAT(a.table, Catch::Contains("input: t_ns is written in E-notation"));
}

TEST_CASE("Allan tau0 of an epoch-nanosecond clock comes from integer differences",
          "[report][dialect][allan]") {
  // 200 Hz from 1.4e18 ns: as doubles of seconds the period would come out 0.004999876 s.
  std::string text = "t_ns,gz_rads\n";
  uint64_t state = 12345;
  for (int i = 0; i < 400; ++i) {
    state = state * 6364136223846793005ULL + 1442695040888963407ULL;
    const double noise = static_cast<double>(state >> 11) / 9007199254740992.0 - 0.5;
    text +=
        std::to_string(1403636579758555392LL + 5000000LL * i) + "," + std::to_string(noise) + "\n";
  }
  TempFile file(text);
  SessionAnalysisOptions options;
  options.allan = true;
  SessionAnalysis a = AnalyzeSession(file.path(), options);
  REQUIRE(a.ok);
  nlohmann::ordered_json report_a = ToJsonValue(a.report);
  const auto& period = report_a["sensors"][0]["quantities"]["gz_rads"]["allan"]["sample_period"];
  CHECK(period["tau0_s"].get<double>() == 0.005);
  CHECK(period["jitter_rms_s"].get<double>() == 0.0);
}

}  // namespace
}  // namespace metro
