// The batch summary's codec (batch_summary.hpp): what `characterize batch` writes reads back
// and is written again byte for byte; a damaged summary is refused at the value's
// file:line:column with its path; a summary from before the later keys still loads.
#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "core/json_text.hpp"
#include "metro/report/batch.hpp"
#include "metro/report/batch_page.hpp"
#include "metro/report/batch_summary.hpp"
#include "support/html_checks.hpp"

#ifdef METRO_CHARACTERIZE_EXE
#include "support/run_program.hpp"
#endif

namespace metro {
namespace {

namespace fs = std::filesystem;
using nlohmann::ordered_json;

const std::string kDatasets = std::string(METRO_SOURCE_DIR) + "/datasets/";

struct TempDir {
  TempDir() {
    static int counter = 0;
    path = fs::path("metro_batch_summary_test_" + std::to_string(::getpid()) + "_" +
                    std::to_string(counter++));
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~TempDir() { fs::remove_all(path); }
  fs::path path;
};

std::string ReadText(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// summary.json as batch wrote it, without the trailing newline (ToJson writes none).
std::string SummaryText(const BatchOptions& o) {
  std::string text = ReadText(fs::path(o.output_dir) / "summary.json");
  REQUIRE(!text.empty());
  REQUIRE(text.back() == '\n');
  text.pop_back();
  return text;
}

TEST_CASE("Batch summary reads back byte for byte", "[report][batch]") {
  TempDir in, out;
  // Two copies of one session (std of means 0, circular pooling of the angles), the receiver
  // capture whose tag 13 never connects (a dead tag, its warning and loss 1.0), the 100 Hz
  // IMU record and a broken file (a failed session).
  fs::create_directories(in.path / "a");
  fs::create_directories(in.path / "b");
  fs::copy_file(kDatasets + "static_chest.csv", in.path / "a" / "chest.csv");
  fs::copy_file(kDatasets + "static_chest.csv", in.path / "b" / "chest.csv");
  fs::copy_file(kDatasets + "capture_15tags_receiver.txt", in.path / "a" / "capture.txt");
  fs::copy_file(kDatasets + "static_imu_100hz.csv", in.path / "a" / "imu.csv");
  { std::ofstream(in.path / "a" / "broken.csv") << "t_s,sensor,pitch_deg\n0.0,1,0.5\nnot,a,row\n"; }
  Result<std::vector<std::string>> inputs =
      ExpandBatchInputs({(in.path / "a").string(), (in.path / "b").string()});
  REQUIRE(inputs.ok());
  REQUIRE(inputs.value().size() == 5);

  struct Case {
    const char* name;
    bool session_pages;
    bool settle_auto;
  };
  for (const Case& c : {Case{"defaults", false, false}, Case{"--html pages", true, false},
                        Case{"--settle auto", false, true}}) {
    SECTION(c.name) {
      BatchOptions o;
      o.output_dir = (out.path / "reports").string();
      o.jobs = 2;
      o.session_pages = c.session_pages;
      o.analysis.type_a.window.settle_auto = c.settle_auto;
      const BatchSummary run = RunBatch(inputs.value(), o);
      REQUIRE(run.failed == 1);
      const std::string text = SummaryText(o);
      // What the run holds is what it wrote.
      CHECK(ToJson(run.summary) == text);
      Result<BatchSummaryReport> read = BatchSummaryFromJson(text, "summary.json");
      REQUIRE(read.ok());
      CHECK(ToJson(read.value()) == text);
      const BatchSummaryReport& s = read.value();
      // The cases this test means to cover are in the file.
      CHECK(s.sessions_total == 5);
      CHECK(s.sessions_failed == 1);
      size_t dead = 0, pages = 0;
      for (const BatchSessionEntry& e : s.sessions) {
        pages += e.page ? 1 : 0;
        if (e.tags) {
          for (const BatchSessionTag& t : *e.tags) dead += t.dead ? 1 : 0;
        }
      }
      CHECK(dead == 1);
      CHECK(pages == (c.session_pages ? 4u : 0u));
      REQUIRE(s.warnings);
      CHECK(s.warnings->size() >= 1);
      bool circular = false, pooled = false;
      for (const BatchQuantitySummary& q : s.quantities) {
        circular = circular || (q.statistics == "circular" && q.resultant_length.has_value());
        pooled = pooled || (q.sessions >= 2 && std::isfinite(q.std_of_means));
      }
      CHECK(circular);
      CHECK(pooled);
      // The page of the saved summary is the page of the run's summary.
      Result<std::string> from_file = RenderBatchSummaryHtml(text, "summary.json");
      Result<std::string> from_run = RenderBatchSummaryHtml(run.summary);
      REQUIRE(from_file.ok());
      REQUIRE(from_run.ok());
      CHECK(testing::WithoutFooter(from_file.value()) == testing::WithoutFooter(from_run.value()));
    }
  }
}

// A hand-written summary; each line is counted in the tests below.
const char* const kHandWritten =
    "{\n"                                                                                     // 1
    "  \"schema\": \"metro.batch-summary/1\",\n"                                              // 2
    "  \"tool\": {\"name\": \"characterize\", \"version\": \"0.1.0\"},\n"                     // 3
    "  \"output_dir\": \"out\",\n"                                                            // 4
    "  \"sessions_total\": 1,\n"                                                              // 5
    "  \"sessions_failed\": 0,\n"                                                             // 6
    "  \"sessions\": [\n"                                                                     // 7
    "    {\"input\": \"a.csv\", \"ok\": true, \"sha256\": \"ab\", \"report\": \"a.json\",\n"  // 8
    "     \"tags\": [{\"sensor\": 2, \"name\": \"Chest\", \"frames\": 50, \"fresh\": 48,\n"   // 9
    "               \"stale\": 2, \"never\": 0, \"dead\": false}],\n"                         // 10
    "     \"quantities\": []}\n"                                                              // 11
    "  ],\n"                                                                                  // 12
    "  \"quantities\": []\n"                                                                  // 13
    "}";                                                                                      // 14

std::string Replace(std::string text, const std::string& from, const std::string& to) {
  const size_t at = text.find(from);
  REQUIRE(at != std::string::npos);
  return text.replace(at, from.size(), to);
}

std::string ErrorOf(const std::string& text) {
  Result<BatchSummaryReport> r = BatchSummaryFromJson(text, "x.json");
  REQUIRE_FALSE(r.ok());
  return r.error().ToString();
}

TEST_CASE("Batch summary read back fails at the value's line and column", "[report][batch]") {
  REQUIRE(BatchSummaryFromJson(kHandWritten, "x.json").ok());
  // Line 9: 5 spaces, `"tags": [{` ends at column 15, `"sensor": 2, ` 16-28, `"name": "Chest", `
  // 29-45, `"frames": ` 46-55: the value at column 56.
  CHECK(ErrorOf(Replace(kHandWritten, "\"frames\": 50", "\"frames\": \"50\"")) ==
        "x.json:9:56: sessions[0].tags[0].frames: expected an integer, found the string \"50\"");
  // Line 10: 15 spaces, `"stale": 2, ` 16-27, `"never": 0, ` 28-39, `"dead": ` 40-47: column 48.
  CHECK(ErrorOf(Replace(kHandWritten, "\"dead\": false", "\"dead\": 0"))
            .rfind("x.json:10:48: "
                   "sessions[0].tags["
                   "0].dead: expected",
                   0) == 0);
  // Line 2: `  "schema": ` is 12 characters.
  CHECK(ErrorOf(Replace(kHandWritten, "metro.batch-summary/1", "metro.report/1"))
            .rfind("x.json:2:13: schema: expected \"metro.batch-summary/1\"", 0) == 0);
  // Line 5: `  "sessions_total": ` is 20 characters; one session is listed.
  CHECK(ErrorOf(Replace(kHandWritten, "\"sessions_total\": 1", "\"sessions_total\": 2")) ==
        "x.json:5:21: sessions_total: expected the number of \"sessions\" (1), found the number 2");
  CHECK(ErrorOf(Replace(kHandWritten, "\"sessions_failed\": 0", "\"sessions_failed\": 1")) ==
        "x.json:6:22: sessions_failed: expected the number of \"sessions\" with \"ok\": false "
        "(0), found the number 1");
  // A member left out: the error is at the object that lacks it (line 8, column 5).
  CHECK(ErrorOf(Replace(kHandWritten, "\"sha256\": \"ab\", ", "")) ==
        "x.json:8:5: sessions[0].sha256: expected a string, found nothing (the member is "
        "missing)");
  // A syntax error at its own position: line 13, the `]` is at column 17 after `  "quantities": `.
  CHECK(ErrorOf(Replace(kHandWritten, "\"quantities\": []\n}", "\"quantities\": ]\n}"))
            .rfind("x.json:13:17: ", 0) == 0);
}

TEST_CASE("A batch summary from before the later keys loads and is written as it was",
          "[report][batch]") {
  // What batch wrote before issue #21 (commit dfc08d8): no "warnings", no "tags", no
  // quantities[].statistics; nor, before issue #25, sessions[].page, .tags, .quantities. Made
  // from today's summary by taking those keys out.
  TempDir out;
  BatchOptions o;
  o.output_dir = (out.path / "reports").string();
  o.jobs = 1;
  const std::string capture = kDatasets + "capture_15tags_receiver.txt";
  const std::string broken = (out.path / "broken.csv").string();
  { std::ofstream(broken) << "t_s,sensor,pitch_deg\nx\n"; }
  const BatchSummary run = RunBatch({capture, broken}, o);
  REQUIRE(run.failed == 1);
  ordered_json old = ordered_json::parse(SummaryText(o));
  old.erase("warnings");
  old.erase("tags");
  for (ordered_json& s : old["sessions"]) {
    s.erase("page");
    s.erase("tags");
    s.erase("quantities");
  }
  for (ordered_json& q : old["quantities"]) {
    q.erase("statistics");
    q.erase("resultant_length");
  }
  const std::string text = JsonText(old, 2);
  Result<BatchSummaryReport> read = BatchSummaryFromJson(text, "old.json");
  REQUIRE(read.ok());
  CHECK_FALSE(read.value().warnings);
  CHECK_FALSE(read.value().tags);
  CHECK_FALSE(read.value().sessions[0].tags);
  CHECK(read.value().quantities.size() == run.summary.quantities.size());
  CHECK(ToJson(read.value()) == text);
  // Its page: the session as one row without tags, the failed one with its error, no plots
  // (the old summary holds no per-session means).
  Result<std::string> html = RenderBatchSummaryHtml(read.value());
  REQUIRE(html.ok());
  CHECK(html.value().find(">analysed<") != std::string::npos);
  CHECK(html.value().find("FAILED: ") != std::string::npos);
  CHECK(html.value().find("<svg") == std::string::npos);
}

#ifdef METRO_CHARACTERIZE_EXE
TEST_CASE("characterize report reads summary.json back and refuses a damaged one",
          "[apps][report][batch]") {
  TempDir d;
  const std::string out = (d.path / "out").string();
  const std::string exe = METRO_CHARACTERIZE_EXE;
  fs::create_directories(out);  // The page's folder exists before batch runs.
  // The page batch writes into its folder and the page of the saved summary are one page.
  testing::ProgramRun r = testing::RunProgram(
      exe, "batch " + kDatasets + "static_chest.csv " + kDatasets +
               "capture_15tags_receiver.txt -q -o " + out + " --html " + out + "/batch.html");
  REQUIRE(r.exit_code == 0);
  r = testing::RunProgram(exe, "report " + out + "/summary.json --html " + out + "/again.html");
  REQUIRE(r.exit_code == 0);
  // Apart from the footer's time of generation.
  CHECK(testing::WithoutFooter(ReadText(d.path / "out" / "again.html")) ==
        testing::WithoutFooter(ReadText(d.path / "out" / "batch.html")));
  // The first tag's frame count of the second session made a string: line and column of the
  // value counted here from the text.
  std::string text = ReadText(d.path / "out" / "summary.json");
  const size_t second = text.find("\"input\"", text.find("\"input\"") + 1);
  REQUIRE(second != std::string::npos);
  const size_t key = text.find("\"frames\": ", second);
  REQUIRE(key != std::string::npos);
  const size_t value = key + std::string("\"frames\": ").size();
  const size_t end = text.find(',', value);
  const std::string frames = text.substr(value, end - value);
  text.replace(value, end - value, "\"" + frames + "\"");
  const int64_t line = 1 + std::count(text.begin(), text.begin() + value, '\n');
  const int64_t column = static_cast<int64_t>(value - text.rfind('\n', value - 1));
  const std::string bad = (d.path / "bad.json").string();
  { std::ofstream(bad, std::ios::binary) << text; }
  r = testing::RunProgram(exe, "report " + bad + " --html " + (d.path / "bad.html").string());
  CHECK(r.exit_code == 2);
  CHECK(r.err == fmt::format("error: {}:{}:{}: sessions[1].tags[0].frames: expected an integer, "
                             "found the string \"{}\"\n",
                             bad, line, column, frames));
  CHECK_FALSE(fs::exists(d.path / "bad.html"));
}
#endif

}  // namespace
}  // namespace metro
