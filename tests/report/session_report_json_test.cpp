// The session report's one codec (issue #25 point 7): what metro writes reads back into
// SessionReport and is written again byte for byte; a wrong value is named at its own
// file:line:column with its path; reports written before later keys existed still load.
#include "report/session_report_json.hpp"

#include <catch2/catch.hpp>
#include <cmath>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "core/json_text.hpp"
#include "metro/report/session_analysis.hpp"
#include "metro/report/session_report.hpp"

namespace metro {
namespace {

const std::string kDatasets = std::string(METRO_SOURCE_DIR) + "/datasets/";

// The text `characterize SESSION -o R.json` writes for `analysis` (without its newline).
std::string WrittenText(const SessionAnalysis& analysis) { return ToJson(analysis.report); }

SessionAnalysis Analyze(const std::string& dataset, SessionAnalysisOptions options) {
  options.type_a.threads = 1;
  SessionAnalysis a = AnalyzeSession(kDatasets + dataset, options);
  INFO(a.error.ToString());
  REQUIRE(a.ok);
  return a;
}

// text == ToJson(FromJson(text)), and the typed report holds what the text says.
SessionReport RoundTrip(const std::string& text) {
  Result<SessionReport> read = SessionReportFromJson(text, "r.json");
  INFO((read.ok() ? std::string() : read.error().ToString()));
  REQUIRE(read.ok());
  const std::string again = ToJson(read.value());
  CHECK(again.size() == text.size());
  CHECK(again == text);
  return read.value();
}

TEST_CASE("session report round trip: settle auto and Allan with gaps and a budget",
          "[report][session_report]") {
  SessionAnalysisOptions options;
  options.type_a.window.settle_auto = true;
  options.allan = true;
  options.allan_options.quantities = {"pitch_deg", "yaw_deg"};
  options.budget_path = kDatasets + "budgets/tag_static_angle_session.json";
  const SessionAnalysis a = Analyze("static_chest.csv", options);
  const std::string text = WrittenText(a);
  const SessionReport r = RoundTrip(text);
  // Independent reading of the same text.
  const nlohmann::ordered_json j = nlohmann::ordered_json::parse(text);
  REQUIRE(r.sensors.size() == j["sensors"].size());
  const QuantityReport* pitch = r.sensors[0].Find("pitch_deg");
  REQUIRE(pitch != nullptr);
  const auto& jp = j["sensors"][0]["quantities"]["pitch_deg"];
  REQUIRE(pitch->type_a.has_value());
  CHECK(pitch->type_a->mean == jp["type_a"]["mean"].get<double>());
  CHECK(pitch->type_a->U_mean == jp["type_a"]["U_mean"].get<double>());
  REQUIRE(pitch->settle.has_value());
  CHECK(pitch->settle->samples == jp["settle"]["samples"].get<int64_t>());
  REQUIRE(pitch->allan.has_value());
  CHECK(pitch->allan->ok());
  CHECK(pitch->allan->tau_s.size() == jp["allan"]["tau_s"].size());
  CHECK(pitch->allan->gaps.has_value() == jp["allan"].contains("gaps"));
  REQUIRE(pitch->allan_type_a_link.has_value());
  CHECK(r.options.settle_scope == std::optional<std::string>("quantity"));
  REQUIRE(r.budget.has_value());
  CHECK(r.budget->measurand.name == j["budget"]["measurand"]["name"].get<std::string>());
  CHECK(r.budget->result.value == j["budget"]["result"]["value"].get<double>());
}

TEST_CASE("session report round trip: 14 tags with settle scope tag", "[report][session_report]") {
  SessionAnalysisOptions options;
  options.type_a.window.settle_auto = true;
  options.type_a.window.settle_tag_wide = true;
  const SessionReport r = RoundTrip(WrittenText(Analyze("capture_15tags.csv", options)));
  REQUIRE(r.sensors.size() == 14);  // Tag 13 of the capture sent no fresh packet.
  CHECK(r.FindSensor(13) == nullptr);
  REQUIRE(r.sensors[0].window.settle.has_value());
  CHECK(r.sensors[0].window.settle->scope == std::optional<std::string>("tag"));
}

TEST_CASE("session report round trip: split and refused gaps give curves and error forms",
          "[report][session_report]") {
  for (AllanGapPolicy policy : {AllanGapPolicy::kSplit, AllanGapPolicy::kRefuse}) {
    SessionAnalysisOptions options;
    options.allan = true;
    options.allan_options.quantities = {"pitch_deg"};
    options.allan_options.gaps = policy;
    const SessionAnalysis a = AnalyzeSession(kDatasets + "capture_15tags.csv", options);
    REQUIRE(a.ok);
    const SessionReport r = RoundTrip(WrittenText(a));
    int errors = 0;
    for (const SensorReport& s : r.sensors) {
      const QuantityReport* q = s.Find("pitch_deg");
      if (q != nullptr && q->allan && !q->allan->ok()) ++errors;
    }
    CHECK((errors > 0) == (policy == AllanGapPolicy::kRefuse));
  }
}

TEST_CASE("session report round trip: an accelerometer and gyroscope session with Allan",
          "[report][session_report]") {
  SessionAnalysisOptions options;
  options.type_a.window.settle_auto = true;
  options.allan = true;
  const SessionReport r = RoundTrip(WrittenText(Analyze("static_imu_100hz.csv", options)));
  const QuantityReport* gx = r.sensors.at(0).Find("gx_dps");
  REQUIRE(gx != nullptr);
  REQUIRE(gx->allan.has_value());
  CHECK(gx->allan->term(NoiseTerm::kRandomWalk).density.has_value());
  CHECK(!gx->allan->term(NoiseTerm::kBiasInstability).density.has_value());
}

TEST_CASE("session report round trip: receiver input with a dead tag and a window",
          "[report][session_report]") {
  SessionAnalysisOptions options;
  options.type_a.window.skip_samples = 5;
  options.type_a.window.skip_seconds = 1.5;
  options.type_a.window.from_s = 2.0;
  options.type_a.window.to_s = 25.0;
  options.type_a.sensors = {3, 13};
  const SessionReport r = RoundTrip(WrittenText(Analyze("capture_15tags_receiver.txt", options)));
  CHECK(r.input.format == "receiver");
  // Tag 13 sent no fresh packet: a sensor without quantities.
  const SensorReport* dead = r.FindSensor(13);
  REQUIRE(dead != nullptr);
  CHECK(dead->fresh == 0);
  CHECK(dead->quantities.empty());
  CHECK(r.input.frame_period_s.has_value());
  CHECK(!r.input.dialect.has_value());
  CHECK(r.options.from_s == 2.0);
  CHECK(r.options.sensors == std::vector<int64_t>{3, 13});
}

TEST_CASE("session report round trip: a quantity that could not be evaluated",
          "[report][session_report]") {
  SessionAnalysisOptions options;
  options.type_a.window.to_s = 0.005;  // One observation per quantity: n < 2.
  const SessionReport r = RoundTrip(WrittenText(Analyze("static_imu_100hz.csv", options)));
  const QuantityReport* ax = r.sensors.at(0).Find("ax_g");
  REQUIRE(ax != nullptr);
  CHECK(!ax->type_a.has_value());
  CHECK(!ax->error.empty());
  CHECK(r.input.dialect.has_value());
  CHECK(r.input.time.has_value());
}

TEST_CASE("session report round trip: a batch session without rate quantities",
          "[report][session_report]") {
  SessionAnalysisOptions options;
  options.allan = true;
  options.allan_skip_without_rates = true;
  const SessionReport r = RoundTrip(WrittenText(Analyze("static_chest.csv", options)));
  CHECK(r.allan_skipped.has_value());
}

// A small report, one key per line where the tests below point, so positions are counted by
// hand: line 1 is "{".
std::string SmallReport(const std::string& mean_text, bool with_later_keys) {
  std::string later =
      with_later_keys ? ",\n\"coverage\": 0.95, \"k\": 12.7, \"U_mean\": 0.127" : "";
  std::string scope = with_later_keys ? ", \"settle_scope\": \"quantity\"" : "";
  return "{\n"
         "\"schema\": \"metro.report/1\",\n"
         "\"tool\": {\"name\": \"metro\", \"version\": \"0.1.0\"},\n"
         "\"input\": {\"path\": \"s.csv\", \"sha256\": \"00\", \"format\": \"csv\", \"rows\": 2,"
         " \"rejected_rows\": 0, \"rejected\": [], \"columns\": [\"t_s\", \"sensor\", \"gz_dps\"],"
         " \"unknown_columns\": []},\n"
         "\"options\": {\"skip_samples\": 0, \"skip_seconds\": 0.0, \"from_s\": null, \"to_s\": "
         "null,"
         " \"settle\": \"none\", \"sensors\": [], \"quantities\": [], \"autocorrelation\":"
         " {\"method\": \"m\", \"band_confidence\": 0.95, \"max_lag_fraction\": 0.25}" +
         scope +
         "},\n"
         "\"sensors\": [{\"sensor\": 1, \"name\": \"Forehead\", \"frames\": 2, \"fresh\": 2,"
         " \"stale\": 0, \"never\": 0, \"packet_loss_ratio\": 0.0,\n"
         "\"window\": {\"n_total\": 2, \"n\": 2, \"first_index\": 0, \"end_index\": 2,"
         " \"t_first_s\": 0.0, \"t_last_s\": 0.1, \"first_line\": 2, \"last_line\": 3},\n"
         "\"quantities\": {\"gz_dps\": {\"unit\": \"deg/s\", \"origin\": \"file\","
         " \"angle_handling\": \"linear\",\n"
         "\"type_a\": {\"n\": 2,\n"
         "  \"mean\": " +
         mean_text +
         ",\n"
         "\"variance\": 0.02, \"std\": 0.1414, \"variance_of_mean\": 0.01, \"std_of_mean\": 0.1,"
         " \"dof\": 1, \"n_eff\": null, \"std_of_mean_autocorr\": null, \"autocorr_cutoff_lag\":"
         " null, \"rho1\": null, \"autocorr_note\": \"n <= 3\"" +
         later +
         "},\n"
         "\"warnings\": []}},\n"
         "\"warnings\": []}]\n"
         "}";
}

TEST_CASE("session report reading names the wrong value at its line and column",
          "[report][session_report]") {
  // Line 10 is '  "mean": "2",': the value's quote is column 11.
  const Result<SessionReport> r = SessionReportFromJson(SmallReport("\"2\"", true), "r.json");
  REQUIRE(!r.ok());
  CHECK(r.error().ToString() ==
        "r.json:10:11: sensors[0].quantities.gz_dps.type_a.mean: expected a number or null, "
        "found the string \"2\"");
}

TEST_CASE("session report reading names a missing member at its object",
          "[report][session_report]") {
  std::string text = SmallReport("2.0", true);
  const std::string rows = "\"rows\": 2,";
  text.erase(text.find(rows), rows.size());
  const Result<SessionReport> r = SessionReportFromJson(text, "r.json");
  REQUIRE(!r.ok());
  // The "input" object opens at line 4, column 10.
  CHECK(r.error().ToString() ==
        "r.json:4:10: input.rows: expected an integer, found nothing (the member is missing)");
}

TEST_CASE("session report reading refuses another schema and bad JSON",
          "[report][session_report]") {
  std::string text = SmallReport("2.0", true);
  text.replace(text.find("metro.report/1"), 14, "metro.calibration/1");
  const Result<SessionReport> r = SessionReportFromJson(text, "r.json");
  REQUIRE(!r.ok());
  CHECK(r.error().ToString() ==
        "r.json:2:11: schema: expected \"metro.report/1\", found the string "
        "\"metro.calibration/1\"");
  const Result<SessionReport> bad = SessionReportFromJson("{\n\"schema\": ]", "r.json");
  REQUIRE(!bad.ok());
  CHECK(bad.error().ToString().rfind("r.json:2:", 0) == 0);
}

TEST_CASE("a report written before coverage k U_mean and settle_scope still loads",
          "[report][session_report]") {
  const std::string text = SmallReport("2.0", false);
  const Result<SessionReport> r = SessionReportFromJson(text, "old.json");
  INFO((r.ok() ? std::string() : r.error().ToString()));
  REQUIRE(r.ok());
  const TypeAReport& a = *r.value().sensors.at(0).Find("gz_dps")->type_a;
  CHECK(a.mean == 2.0);
  CHECK(!a.coverage.has_value());
  CHECK(std::isnan(a.U_mean));
  CHECK(!a.has_u_mean);
  CHECK(!r.value().options.settle_scope.has_value());
  // Written again without the keys it did not have.
  const std::string again = ToJson(r.value());
  CHECK(again.find("coverage") == std::string::npos);
  CHECK(again.find("settle_scope") == std::string::npos);
  CHECK(again.find("\"u_mean\"") == std::string::npos);
  // The same report with the later keys: they are read.
  const Result<SessionReport> now = SessionReportFromJson(SmallReport("2.0", true), "r.json");
  REQUIRE(now.ok());
  CHECK(now.value().sensors.at(0).Find("gz_dps")->type_a->coverage == 0.95);
  CHECK(now.value().sensors.at(0).Find("gz_dps")->type_a->U_mean == 0.127);
}

TEST_CASE("a report written by an older metro loads and is written back with the same keys",
          "[report][session_report]") {
  // Saved before u_mean, coverage, settle_scope and plot data existed, with Allan error forms.
  std::ifstream in(std::string(METRO_SOURCE_DIR) + "/fuzz/seeds/report_fuzz/session_report.json");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  REQUIRE(!text.empty());
  const Result<SessionReport> r = SessionReportFromJson(text, "old.json");
  INFO((r.ok() ? std::string() : r.error().ToString()));
  REQUIRE(r.ok());
  const QuantityReport* yaw = r.value().sensors.at(0).Find("yaw_deg");
  REQUIRE(yaw != nullptr);
  CHECK(!yaw->type_a->has_u_mean);
  CHECK(yaw->allan.has_value());
  CHECK(!yaw->allan->ok());
  CHECK(!yaw->plot.has_value());
  // Nothing added, nothing lost: the same document (metro writes it indented).
  CHECK(nlohmann::ordered_json::parse(ToJson(r.value())) == nlohmann::ordered_json::parse(text));
}

}  // namespace
}  // namespace metro
