// The "metro.accuracy-report/1" codec: what MakeAccuracyReport writes reads back into the same
// text byte for byte (bundled table sweep under several option sets, a tags file with a device
// ID, a separate reference log, a session without the other two angles), reports written
// before input.tag still load, and a damaged report is refused at the offending value's own
// line and column with its path.
#include "accuracy/accuracy_report_json.hpp"

#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "core/json_text.hpp"
#include "metro/accuracy/accuracy_report.hpp"
#include "metro/io/session_io.hpp"
#include "metro/report/accuracy_page.hpp"
#include "metro/report/html_report.hpp"
#include "metro/sim/table_session.hpp"
#include "metro/uncertainty/budget_report.hpp"
#include "report/html_dispatch.hpp"
#include "support/run_program.hpp"
#include "support/session_text.hpp"
#include "support/temp_file.hpp"
#include "support/text_position.hpp"

namespace metro {
namespace {

using nlohmann::ordered_json;
using testing::Into;
using testing::Load;
using testing::TempFile;

const std::string kSweep = std::string(METRO_SOURCE_DIR) + "/datasets/table_sweep.csv";

AccuracyResult Evaluate(const Session& session, const AccuracyOptions& options,
                        const Session* reference = nullptr) {
  Result<AccuracyResult> r = EvaluateAccuracy(session, reference, options);
  if (!r.ok()) FAIL(r.error().ToString());
  return r.value();
}

const Session& Sweep() {
  static const Session session = [] {
    Result<Session> s = LoadSession(kSweep);
    REQUIRE(s.ok());
    return s.value();
  }();
  return session;
}

void CheckRoundTrip(const std::string& text, const std::string& what) {
  INFO(what);
  Result<AccuracyReport> read = AccuracyReportFromJson(text, "a.json");
  if (!read.ok()) FAIL(read.error().ToString());
  CHECK(ToJson(read.value()) == text);
  CHECK(JsonText(ToJsonValue(read.value()), 2) == text);
  // The table of the report read back is the table of the report made.
  Result<AccuracyReport> again = AccuracyReportFromJson(ToJson(read.value()), "a.json");
  REQUIRE(again.ok());
  CHECK(AccuracyReportTable(again.value()) == AccuracyReportTable(read.value()));
}

using testing::LineColumn;

TEST_CASE("Accuracy reports of the bundled table sweep read back byte for byte",
          "[accuracy][report][json]") {
  struct Set {
    const char* what;
    std::function<void(AccuracyOptions*)> set;
  };
  const std::vector<Set> sets = {
      {"defaults", [](AccuracyOptions*) {}},
      {"reference u, settle auto, harmonic1",
       [](AccuracyOptions* o) {
         o->reference.u_deg = 0.01;
         o->reference.dof = 12.0;
         o->reference.source = "--reference-u";
         o->plateaus.settle_auto = true;
         o->model = ErrorModel::kHarmonic1;
       }},
      {"window, no lag model, departures kept",
       [](AccuracyOptions* o) {
         o->window.skip_seconds = 5.0;
         o->window.to_s = 400.0;
         o->model_lag = false;
         o->plateaus.trim_departures = false;
       }},
      {"given lag", [](AccuracyOptions* o) { o->lag_tau_s = 0.25; }},
  };
  for (const Set& s : sets) {
    AccuracyOptions options;
    s.set(&options);
    const AccuracyResult r = Evaluate(Sweep(), options);
    const std::string text = ToJson(MakeAccuracyReport(r, Sweep(), nullptr));
    CHECK(text.find("\"column\": \"table_angle_deg\"") != std::string::npos);
    CheckRoundTrip(text, s.what);
  }
}

TEST_CASE("Accuracy report names the tag from a tags file and reads it back",
          "[accuracy][report][json]") {
  TempFile tags_file(R"({"2": {"name": "Chest", "device_id": "0x1234abcd 0x0000fe01"}})", ".json");
  Result<TagRegistry> tags = TagRegistry::Load(tags_file.path());
  if (!tags.ok()) FAIL(tags.error().ToString());
  const AccuracyResult r = Evaluate(Sweep(), AccuracyOptions{});
  const std::string text = ToJson(MakeAccuracyReport(r, Sweep(), nullptr, tags.value()));
  CheckRoundTrip(text, "tags file");
  Result<AccuracyReport> read = AccuracyReportFromJson(text, "a.json");
  REQUIRE(read.ok());
  REQUIRE(read.value().input.tag);
  CHECK(read.value().input.tag->name == "Chest");
  REQUIRE(read.value().input.tag->device_id);
  // The thesis' default names have no device ID: null, read back as none.
  const std::string plain = ToJson(MakeAccuracyReport(r, Sweep(), nullptr));
  CHECK(plain.find("\"device_id\": null") != std::string::npos);
  Result<AccuracyReport> read_plain = AccuracyReportFromJson(plain, "a.json");
  REQUIRE(read_plain.ok());
  REQUIRE(read_plain.value().input.tag);
  CHECK_FALSE(read_plain.value().input.tag->device_id);
}

TEST_CASE("Accuracy report with a separate reference log reads back byte for byte",
          "[accuracy][report][json]") {
  TableSimulationOptions o;
  o.sweeps = 1;
  o.seed = 4;
  o.reference_clock_offset_s = 2.0;
  o.lag_tau_s = 0.3;
  std::string capture, ref_text;
  TableTruth truth;
  REQUIRE(SimulateTableSession(o, SessionFormat::kReceiver, Into(&capture), Into(&ref_text), &truth)
              .ok());
  const Session session = Load(capture);
  const Session reference = Load(ref_text);
  const AccuracyResult r = Evaluate(session, AccuracyOptions{}, &reference);
  REQUIRE(r.alignment);
  const std::string text = ToJson(MakeAccuracyReport(r, session, &reference));
  CHECK(text.find("\"alignment\"") != std::string::npos);
  CheckRoundTrip(text, "reference log");
  Result<AccuracyReport> read = AccuracyReportFromJson(text, "a.json");
  REQUIRE(read.ok());
  REQUIRE(read.value().input.reference_log);
  // The clock offset as simulated (2 s), as the evaluation found it.
  CHECK(read.value().input.reference_log->alignment.offset_s == r.alignment->offset_s);
  CHECK(read.value().input.reference_log->alignment.offset_s == Approx(2.0).margin(0.05));
}

TEST_CASE("Accuracy report of a session without the other two angles reads back",
          "[accuracy][report][json]") {
  // The sweep's yaw alone (derived from its quaternion), without pitch and roll: the cross-axis
  // section is not evaluated and the points' other-axis values are null.
  std::ostringstream csv;
  csv.precision(17);
  csv << "t_s,sensor,yaw_deg,table_angle_deg\n";
  const Session& sweep = Sweep();
  REQUIRE(sweep.tags.size() == 1);
  const Tag& tag = sweep.tags.front();
  const Quantity* yaw = tag.Find("yaw_deg");
  const Quantity* table = tag.Find("table_angle_deg");
  REQUIRE(yaw != nullptr);
  REQUIRE(table != nullptr);
  for (size_t i = 0; i < tag.size(); ++i) {
    csv << tag.t_s[i] << "," << tag.sensor << "," << yaw->values[i] << "," << table->values[i]
        << "\n";
  }
  const Session session = Load(csv.str());
  const AccuracyResult r = Evaluate(session, AccuracyOptions{});
  REQUIRE_FALSE(r.cross_axis_available);
  const std::string text = ToJson(MakeAccuracyReport(r, session, nullptr));
  CHECK(text.find("\"evaluated\": false") != std::string::npos);
  CheckRoundTrip(text, "no cross axis");
}

std::string SweepText() {
  static const std::string text =
      ToJson(MakeAccuracyReport(Evaluate(Sweep(), AccuracyOptions{}), Sweep(), nullptr));
  return text;
}

TEST_CASE("A damaged accuracy report is refused at the value's line and column with its path",
          "[accuracy][report][json]") {
  const ordered_json good = ordered_json::parse(SweepText());
  struct Case {
    std::function<void(ordered_json*)> damage;
    std::string token;    // Where the reported value starts: its first occurrence in the text.
    std::string message;  // After "a.json:LINE:COLUMN: ".
  };
  const std::vector<Case> cases = {
      {[](ordered_json* j) { (*j)["points"][3]["type_a"]["u_deg"] = "small"; }, "\"small\"",
       "points[3].type_a.u_deg: expected a number or null, found the string \"small\""},
      {[](ordered_json* j) { (*j)["options"]["settle"] = "sometimes"; }, "\"sometimes\"",
       "options.settle: expected \"auto\" or \"none\", found the string \"sometimes\""},
      {[](ordered_json* j) { (*j)["input"]["table_axis"] = "tilt"; }, "\"tilt\"",
       "input.table_axis: expected one of \"yaw\", \"pitch\", \"roll\", found the string "
       "\"tilt\""},
      {[](ordered_json* j) { (*j)["fit"]["params"][1]["name"] = "zz"; }, "\"zz\"",
       "fit.params[1].name: expected a parameter name (c0_deg, scale, a1_deg, b1_deg, a2_deg, "
       "b2_deg, h_deg), found the string \"zz\""},
      {[](ordered_json* j) { (*j)["points"][0]["direction"] = "sideways"; }, "\"sideways\"",
       "points[0].direction: expected one of \"up\", \"down\", \"first\", found the string "
       "\"sideways\""},
      {[](ordered_json* j) { (*j)["budget"]["corrected"]["inputs"][2]["dof"] = true; },
       "true,\n          \"percent\"",
       "budget.corrected.inputs[2].dof: expected a number or null (infinite degrees of "
       "freedom), found true"},
      // A missing member is reported at the object it belongs to.
      {[](ordered_json* j) { (*j)["window"].erase("n"); }, "{\n    \"skip_samples\"",
       "window.n: expected an integer, found nothing (the member is missing)"},
  };
  for (const Case& c : cases) {
    ordered_json j = good;
    c.damage(&j);
    const std::string damaged = JsonText(j, 2);
    const size_t offset = damaged.find(c.token);
    REQUIRE(offset != std::string::npos);
    INFO(c.message);
    Result<AccuracyReport> read = AccuracyReportFromJson(damaged, "a.json");
    REQUIRE_FALSE(read.ok());
    CHECK(read.error().ToString() == "a.json:" + LineColumn(damaged, offset) + ": " + c.message);
    Result<std::string> page = RenderAccuracyReportHtml(std::string_view(damaged), "a.json");
    REQUIRE_FALSE(page.ok());
    CHECK(page.error().ToString() == read.error().ToString());
  }
}

// `html` without its footer (it carries the time the page was made).
std::string WithoutFooter(const std::string& html) {
  return std::regex_replace(html, std::regex("<footer>[^<]*</footer>"), "");
}

TEST_CASE("An accuracy report written before input.tag still loads and renders",
          "[accuracy][report][json]") {
  ordered_json j = ordered_json::parse(SweepText());
  REQUIRE(j["input"].contains("tag"));
  j["input"].erase("tag");
  const std::string old_text = JsonText(j, 2);
  Result<AccuracyReport> read = AccuracyReportFromJson(old_text, "old.json");
  if (!read.ok()) FAIL(read.error().ToString());
  CHECK_FALSE(read.value().input.tag);
  // Written back as it was: without input.tag.
  CHECK(ToJson(read.value()) == old_text);
  Result<std::string> page = RenderAccuracyReportHtml(read.value(), "old.json");
  REQUIRE(page.ok());
  CHECK(page.value().find("<th>tag</th>") == std::string::npos);
  // The page of the model is the page the JSON dispatch renders.
  Result<std::string> dispatched = RenderJsonHtml(j, "old.json");
  REQUIRE(dispatched.ok());
  CHECK(WithoutFooter(dispatched.value()) == WithoutFooter(page.value()));
}

#ifdef METRO_CHARACTERIZE_EXE
TEST_CASE("What characterize accuracy and budget write reads back byte for byte",
          "[accuracy][report][json][apps]") {
  TempFile tags_file(R"({"2": {"name": "Chest", "device_id": "0x1234abcd 0x0000fe01"}})", ".json");
  for (const std::string& options :
       {std::string(""), "--tags " + tags_file.path() + " --reference-u 0.01 --settle auto",
        std::string("--error-model harmonic1 --skip-seconds 5 --no-lag-model")}) {
    INFO(options);
    const testing::ProgramRun r =
        testing::RunProgram(METRO_CHARACTERIZE_EXE, "accuracy " + kSweep + " " + options);
    INFO(r.err);
    REQUIRE(r.exit_code == 0);
    REQUIRE(r.out.size() > 1);
    REQUIRE(r.out.back() == '\n');
    CheckRoundTrip(r.out.substr(0, r.out.size() - 1), "characterize accuracy " + options);
    if (!options.empty() && options.find("--tags") == 0) {
      CHECK(r.out.find("\"name\": \"Chest\"") != std::string::npos);
    }
  }
  const testing::ProgramRun b =
      testing::RunProgram(METRO_CHARACTERIZE_EXE, "budget " + std::string(METRO_SOURCE_DIR) +
                                                      "/datasets/budgets/gum_h1_end_gauge.json");
  INFO(b.err);
  REQUIRE(b.exit_code == 0);
  REQUIRE(b.out.size() > 1);
  const std::string text = b.out.substr(0, b.out.size() - 1);
  Result<BudgetReport> read = BudgetReportFromJson(text, "b.json");
  if (!read.ok()) FAIL(read.error().ToString());
  CHECK(ToJson(read.value()) == text);
}

TEST_CASE("characterize report refuses a damaged accuracy report at the value's position",
          "[accuracy][report][json][apps]") {
  ordered_json j = ordered_json::parse(SweepText());
  j["points"][3]["type_a"]["u_deg"] = "small";
  const std::string text = JsonText(j, 2) + "\n";
  TempFile file(text, ".json");
  const testing::ProgramRun r = testing::RunProgram(
      METRO_CHARACTERIZE_EXE, "report " + file.path() + " --html " + file.path() + ".html");
  CHECK(r.exit_code == 2);
  CHECK(r.err == "error: " + file.path() + ":" + LineColumn(text, text.find("\"small\"")) +
                     ": points[3].type_a.u_deg: expected a number or null, found the string "
                     "\"small\"\n");
  std::remove((file.path() + ".html").c_str());
}
#endif

}  // namespace
}  // namespace metro
