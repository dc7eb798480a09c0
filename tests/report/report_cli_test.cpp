// End-to-end: characterize --html, characterize report, characterize batch, calibrate --html.
#ifdef METRO_CHARACTERIZE_EXE
#include <sys/wait.h>

#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "metro/core/rounding.hpp"
#include "support/run_program.hpp"

namespace metro {
namespace {

namespace fs = std::filesystem;

using Run = testing::ProgramRun;

Run Exec(const std::string& exe, const std::string& args) { return testing::RunProgram(exe, args); }

Run Characterize(const std::string& args) { return Exec(METRO_CHARACTERIZE_EXE, args); }

std::string Slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

size_t Count(const std::string& text, const std::string& what) {
  size_t n = 0;
  for (size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

const std::string kDatasets = std::string(METRO_SOURCE_DIR) + "/datasets/";

struct Dir {
  explicit Dir(const std::string& name) : path(name) {
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~Dir() { fs::remove_all(path); }
  fs::path path;
};

TEST_CASE("characterize --html writes the JSON and the HTML report", "[apps][report]") {
  Dir d("metro_cli_html");
  const std::string json = (d.path / "r.json").string(), html = (d.path / "r.html").string();
  Run r = Characterize(kDatasets + "static_chest.csv --type-a --settle auto -o " + json +
                       " --html " + html);
  REQUIRE(r.exit_code == 0);
  const std::string h = Slurp(html);
  CHECK(h.find("<title>Session report: static_chest.csv</title>") != std::string::npos);
  CHECK(Count(h, "<svg") >= 3);
  // From the saved JSON alone: every plot from the report's plot data.
  const std::string html2 = (d.path / "r2.html").string();
  r = Characterize("report " + json + " --html " + html2);
  REQUIRE(r.exit_code == 0);
  const std::string h2 = Slurp(html2);
  CHECK(h2.find("drawn from the plot data computed when the session was analysed") !=
        std::string::npos);
  CHECK(Count(h2, "<svg") == Count(h, "<svg"));
  // --session of older scripts: the same page, and a note that the session is not read.
  const std::string html3 = (d.path / "r3.html").string();
  r = Characterize("report " + json + " --html " + html3 + " --session " + kDatasets +
                   "static_chest.csv");
  REQUIRE(r.exit_code == 0);
  CHECK(r.err.find("note: --session " + kDatasets + "static_chest.csv is not read") !=
        std::string::npos);
  CHECK(Count(Slurp(html3), "<svg") == Count(h, "<svg"));
  // Refuses to write over its input; a file that is not JSON is an input error.
  r = Characterize("report " + json + " --html " + json);
  CHECK(r.exit_code == 2);
  CHECK(r.err.find("refusing to overwrite") != std::string::npos);
  r = Characterize("report " + kDatasets + "static_chest.csv --html " + html2);
  CHECK(r.exit_code == 2);
  CHECK(r.err.find("invalid JSON") != std::string::npos);
  // A saved report with a wrong value is read through SessionReportFromJson: the value's line
  // and column with its path, exit 2. Line 2 of this file is ' "tool": {"name": 7}}'.
  const std::string bad = (d.path / "bad.json").string();
  { std::ofstream(bad) << "{\"schema\": \"metro.report/1\",\n \"tool\": {\"name\": 7}}\n"; }
  r = Characterize("report " + bad + " --html " + html2);
  CHECK(r.exit_code == 2);
  CHECK(r.err.find(bad + ":2:19: tool.name: expected a string, found the number 7") !=
        std::string::npos);
}

TEST_CASE("characterize batch exits 1 and names the broken session", "[apps][report]") {
  Dir in("metro_cli_batch_in"), out("metro_cli_batch_out");
  fs::copy_file(kDatasets + "static_chest.csv", in.path / "chest.csv");
  fs::copy_file(kDatasets + "capture_15tags.csv", in.path / "capture.csv");
  { std::ofstream(in.path / "broken.csv") << "t_s,sensor,pitch_deg\n0.0,1,0.5\n0.1,1,zzz\n"; }
  Run r =
      Characterize("batch " + in.path.string() + " --type-a -o " + out.path.string() + " --jobs 2");
  CHECK(r.exit_code == 1);
  CHECK(r.err.find("broken.csv:3") != std::string::npos);
  CHECK(r.err.find("2 of 3 sessions analysed") != std::string::npos);
  CHECK(r.out.find("3 sessions, 1 failed") != std::string::npos);
  CHECK(r.err.find("batch [") == std::string::npos);  // No progress bar: stderr is a file.
  const auto summary = nlohmann::json::parse(Slurp(out.path / "summary.json"));
  CHECK(summary["sessions_failed"] == 1);
  CHECK(fs::exists(out.path / "chest.report.json"));
  CHECK(fs::exists(out.path / "capture.report.json"));
  // Without the broken file: exit 0.
  fs::remove(in.path / "broken.csv");
  r = Characterize("batch " + (in.path / "*.csv").string() + " -o " + out.path.string());
  CHECK(r.exit_code == 0);
  // Nothing to do is a usage error.
  r = Characterize("batch " + (in.path / "*.nothing").string() + " -o " + out.path.string());
  CHECK(r.exit_code == 2);
  CHECK(r.err.find("pattern matches no file") != std::string::npos);
}

TEST_CASE("characterize budget --html writes the budget page with the statement of its JSON",
          "[apps][report][budget]") {
  Dir d("metro_cli_budget_html");
  const std::string json = (d.path / "b.json").string(), html = (d.path / "b.html").string();
  const std::string budget = kDatasets + "budgets/jcgm101_9_3_mass.json";
  Run r = Characterize("budget " + budget + " -q -o " + json + " --html " + html);
  REQUIRE(r.exit_code == 0);
  const auto report = nlohmann::json::parse(Slurp(json));
  const std::string h = Slurp(html);
  // The GUF statement on the page is the JSON's result rounded per GUM 7.2.6; JCGM 101 9.3's
  // GUF is not validated, so the headline is the JSON's stated Monte Carlo result.
  const RoundedResult s = RoundForStatement(report["result"]["value"].get<double>(),
                                            report["result"]["U"].get<double>());
  const std::string unit = report["measurand"]["unit"].get<std::string>();
  const std::string guf = report["measurand"]["name"].get<std::string>() + " = (" + s.value +
                          " \u00b1 " + s.uncertainty + ")" + (unit.empty() ? "" : " " + unit);
  CHECK(h.find("<span id=\"guf-statement\">" + guf + "</span>") != std::string::npos);
  REQUIRE(report["stated"]["method"] == "monte_carlo");
  const std::string statement = report["stated"]["statement"].get<std::string>();
  CHECK(h.find("<strong id=\"statement\">" + statement + "</strong>") != std::string::npos);
  CHECK(Count(h, "<svg") == 2);
  // The saved report renders as the same page; the budget definition is refused.
  const std::string html2 = (d.path / "b2.html").string();
  r = Characterize("report " + json + " --html " + html2);
  REQUIRE(r.exit_code == 0);
  CHECK(Slurp(html2).find("<strong id=\"statement\">" + statement + "</strong>") !=
        std::string::npos);
  r = Characterize("report " + budget + " --html " + html2);
  CHECK(r.exit_code == 2);
  CHECK(r.err.find("budget definition") != std::string::npos);
  CHECK(r.err.find("characterize budget " + budget + " --html") != std::string::npos);
  // Both to stdout cannot be.
  r = Characterize("budget " + budget + " -q --html -");
  CHECK(r.exit_code == 2);
}

TEST_CASE("characterize batch --html writes the batch page and a page per session",
          "[apps][report][batch]") {
  Dir d("metro_cli_batch_html");
  const std::string out = (d.path / "out").string(), page = (d.path / "batch.html").string();
  Run r = Characterize("batch " + kDatasets + "static_chest.csv " + kDatasets +
                       "capture_15tags.csv -q -o " + out + " --html " + page);
  REQUIRE(r.exit_code == 0);
  const std::string h = Slurp(page);
  for (const char* name : {"static_chest", "capture_15tags"}) {
    CHECK(fs::exists(d.path / "out" / (std::string(name) + ".report.html")));
    CHECK(h.find("href=\"out/" + std::string(name) + ".report.html\"") != std::string::npos);
  }
  CHECK(Slurp(d.path / "out" / "static_chest.report.html").find("<title>Session report: ") !=
        std::string::npos);
  const auto summary = nlohmann::json::parse(Slurp(d.path / "out" / "summary.json"));
  CHECK(summary["sessions"][0]["page"] == "capture_15tags.report.html");
  // A row per session and tag: capture_15tags has 14 tags, static_chest 1.
  CHECK(Count(h, "<td><code>") == 15);
  // The page is never written over a session.
  const std::string session = (d.path / "s.csv").string();
  fs::copy_file(kDatasets + "static_chest.csv", session);
  r = Characterize("batch " + session + " -q -o " + out + " --html " + session);
  CHECK(r.exit_code == 2);
  CHECK(r.err.find("refusing to overwrite") != std::string::npos);
  CHECK(Slurp(session) == Slurp(kDatasets + "static_chest.csv"));
}

#ifdef METRO_CALIBRATE_EXE
TEST_CASE("calibrate fit and report write the certificate", "[apps][report][slow]") {
  Dir d("metro_cli_certificate");
  // imu_tk's public Xsens record (an accelerometer and a gyroscope file).
  const std::string dir = std::string(METRO_EXTERNAL_DATA_DIR) + "/imu_tk_xsens/";
  const std::string session = "--imutk " + dir + "xsens_acc.mat " + dir + "xsens_gyro.mat";
  const std::string cal = (d.path / "calibration.json").string();
  const std::string html = (d.path / "certificate.html").string();
  Run r = Exec(METRO_CALIBRATE_EXE,
               "fit " + session + " --gravity-mps2 9.81744 -o " + cal + " --html " + html);
  REQUIRE(r.exit_code == 0);
  const std::string h = Slurp(html);
  CHECK(h.find("<title>Calibration certificate</title>") != std::string::npos);
  CHECK(Count(h, "<svg") == 2);
  // An Xsens record is described from the data, never as an MPU6050; the gravity was given.
  CHECK(h.find("MPU6050") == std::string::npos);
  CHECK(h.find("imu_tk accelerometer + gyroscope file pair") != std::string::npos);
  CHECK(h.find("9.81744 m/s^2, given: calibrate fit --gravity-mps2 9.81744") != std::string::npos);
  const std::string json = Slurp(cal);
  CHECK(json.find("\"gravity_source\": \"given\"") != std::string::npos);
  CHECK(json.find("\"format\": \"imutk\"") != std::string::npos);
  const std::string html2 = (d.path / "certificate2.html").string();
  r = Exec(METRO_CALIBRATE_EXE, "report " + cal + " --html " + html2);
  REQUIRE(r.exit_code == 0);
  // From calibration.json alone: the residuals and conditions the fit recorded, no reload.
  CHECK(Slurp(html2).find("as computed from the input records by the fit") != std::string::npos);
  CHECK(Count(Slurp(html2), "<svg") == 2);
}
#endif

}  // namespace
}  // namespace metro
#endif
