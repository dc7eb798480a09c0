// The settle keys of a Type A report (docs/report-schema.md): per quantity its own window
// and fitted transient, per tag the driver of the tag window, and --settle-scope.
#include "metro/report/settle_report.hpp"

#include <fmt/format.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <random>
#include <string>

#include "metro/report/session_analysis.hpp"
#include "report/session_report_json.hpp"
#include "support/temp_file.hpp"

namespace metro {
namespace {

// 10 Hz for 300 s: gx_dps = 10 exp(-t / 4 s) + white noise of 0.5; temp_c warming by 3 degC
// with a 900 s time constant; az_g stationary.
std::string WarmUpCsv() {
  std::mt19937_64 rng(11);
  std::normal_distribution<double> w(0.0, 1.0);
  std::string text = "t_s,sensor,gx_dps,az_g,temp_c\n";
  for (int i = 0; i < 3000; ++i) {
    const double t_s = 0.1 * i;
    text += fmt::format("{:.1f},3,{:.6f},{:.6f},{:.6f}\n", t_s,
                        10.0 * std::exp(-t_s / 4.0) + 0.5 * w(rng), 1.0 + 0.002 * w(rng),
                        28.0 - 3.0 * std::exp(-t_s / 900.0) + 0.01 * w(rng));
  }
  return text;
}

TEST_CASE("Settle keys in the report: own windows, the fitted tau, the driver",
          "[report][settle]") {
  testing::TempFile file(WarmUpCsv(), ".csv");
  SessionAnalysisOptions o;
  o.type_a.window.settle_auto = true;
  const SessionAnalysis a = AnalyzeSession(file.path(), o);
  REQUIRE(a.ok);
  // Read in the report's JSON form, as a reader of the file would.
  nlohmann::ordered_json report = ToJsonValue(a.report);
  CHECK(report["options"]["settle_scope"] == "quantity");
  const auto& s = report["sensors"][0];
  const auto& window = s["window"];
  CHECK(window["settle"]["method"] == kSettleMethod);
  CHECK(window["settle"]["scope"] == "quantity");
  // The temperature's cut is its own: gx_dps drives the tag window.
  CHECK(window["settle"]["driver"] == "gx_dps");
  const auto& gx = s["quantities"]["gx_dps"];
  // The simulated time constant, 4 s, within 15 %.
  CHECK(gx["settle"]["tau_s"].get<double>() == Approx(4.0).epsilon(0.15));
  CHECK(gx["settle"]["amplitude"].get<double>() == Approx(10.0).epsilon(0.1));
  CHECK(gx["settle"]["bias_over_u_kept"].get<double>() <= 0.1);
  const int64_t cut = gx["settle_samples"].get<int64_t>();
  CHECK(gx["window_first_index"].get<int64_t>() == cut);
  CHECK(gx["type_a"]["n"].get<int64_t>() == 3000 - cut);
  CHECK(window["settle"]["samples"].get<int64_t>() == cut);
  CHECK(s["quantities"]["az_g"]["window_first_index"] == 0);
  CHECK(s["quantities"]["az_g"]["type_a"]["n"] == 3000);
  CHECK(s["quantities"]["temp_c"]["settle"]["at_limit"] == true);
  // --settle-scope tag: every quantity from gx's cut.
  o.type_a.window.settle_tag_wide = true;
  const SessionAnalysis b = AnalyzeSession(file.path(), o);
  REQUIRE(b.ok);
  nlohmann::ordered_json report_b = ToJsonValue(b.report);
  CHECK(report_b["options"]["settle_scope"] == "tag");
  for (const auto& [name, q] : report_b["sensors"][0]["quantities"].items()) {
    INFO(name);
    CHECK(q["window_first_index"].get<int64_t>() == cut);
    CHECK(q["type_a"]["n"].get<int64_t>() == 3000 - cut);
  }
}

}  // namespace
}  // namespace metro
