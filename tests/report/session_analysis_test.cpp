#include "metro/report/session_analysis.hpp"

#include <catch2/catch.hpp>
#include <string>

namespace metro {
namespace {

const std::string kAngles = std::string(METRO_SOURCE_DIR) + "/datasets/static_chest.csv";
const std::string kImu = std::string(METRO_SOURCE_DIR) + "/datasets/static_imu_100hz.csv";

TEST_CASE("AnalyzeSession: --allan on an angle-only session fails unless skipping is asked",
          "[report][analysis]") {
  SessionAnalysisOptions options;
  options.allan = true;
  const SessionAnalysis strict = AnalyzeSession(kAngles, options);
  REQUIRE_FALSE(strict.ok);
  CHECK(strict.input_error);
  CHECK_THAT(strict.error.message, Catch::Contains("no rate quantity"));

  options.allan_skip_without_rates = true;
  const SessionAnalysis skipped = AnalyzeSession(kAngles, options);
  REQUIRE(skipped.ok);
  CHECK(skipped.report.allan_skipped.has_value());
  CHECK(skipped.report.sensors.size() == 1);
}

TEST_CASE("AnalyzeSession: skipping leaves sessions with rate quantities analysed",
          "[report][analysis]") {
  SessionAnalysisOptions options;
  options.allan = true;
  options.allan_skip_without_rates = true;
  const SessionAnalysis a = AnalyzeSession(kImu, options);
  REQUIRE(a.ok);
  CHECK_FALSE(a.report.allan_skipped.has_value());
  REQUIRE(a.report.sensors.at(0).Find("gx_dps") != nullptr);
  CHECK(a.report.sensors.at(0).Find("gx_dps")->allan.has_value());
}

}  // namespace
}  // namespace metro
