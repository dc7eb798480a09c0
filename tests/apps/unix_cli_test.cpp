// The programs as Unix tools (apps/unix_cli.hpp, docs/unix.md): --version, `-o -` (the
// JSON on stdout, the table on stderr), --quiet, and `-` reading a session from stdin.
#include <sys/stat.h>

#include <catch2/catch.hpp>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "metro/core/file.hpp"
#include "metro/core/version.hpp"
#include "metro/io/session_io.hpp"
#include "metro/sim/calibration_session.hpp"
#include "support/run_program.hpp"
#include "support/temp_file.hpp"

namespace metro {
namespace {

using Run = testing::ProgramRun;
using testing::StdinFrom;
using testing::TempFile;

const std::string kDatasets = std::string(METRO_SOURCE_DIR) + "/datasets/";
const std::string kChest = kDatasets + "static_chest.csv";

Run Characterize(const std::string& args) {
  return testing::RunProgram(METRO_CHARACTERIZE_EXE, args);
}

Run CharacterizeStdin(const std::string& args, const std::string& input,
                      StdinFrom from = StdinFrom::kPipe) {
  return testing::RunProgramWithStdin(METRO_CHARACTERIZE_EXE, args, input, from);
}

bool Exists(const std::string& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0;
}

std::string Slurp(const std::string& path) {
  Result<std::string> text = ReadFile(path);
  REQUIRE(text.ok());
  return text.value();
}

nlohmann::json Json(const std::string& text) {
  INFO(text.substr(0, 200));
  REQUIRE(nlohmann::json::accept(text));
  return nlohmann::json::parse(text);
}

std::string AfterFirstLine(const std::string& text) {
  const size_t nl = text.find('\n');
  return nl == std::string::npos ? std::string() : text.substr(nl + 1);
}

// The report numbers a run must not change: mean and s(mean) of pitch_deg of the first tag.
void CheckSameNumbers(const nlohmann::json& a, const nlohmann::json& b) {
  const auto& qa = a["sensors"][0]["quantities"]["pitch_deg"]["type_a"];
  const auto& qb = b["sensors"][0]["quantities"]["pitch_deg"]["type_a"];
  REQUIRE(qa.is_object());
  CHECK(qa["n"] == qb["n"]);
  CHECK(qa["mean"].get<double>() == qb["mean"].get<double>());
  CHECK(qa["std_of_mean"].get<double>() == qb["std_of_mean"].get<double>());
  CHECK(a["sensors"] == b["sensors"]);
  CHECK(a["input"]["sha256"] == b["input"]["sha256"]);
}

// ---------------------------------------------------------------------------- --version

TEST_CASE("Both programs: --version prints the program, metro and its version, exit 0",
          "[apps][unix]") {
  Run r = Characterize("--version");
  CHECK(r.exit_code == 0);
  CHECK(r.out == std::string("characterize (metro) ") + kVersion + "\n");
  CHECK(r.err.empty());
#ifdef METRO_CALIBRATE_EXE
  r = testing::RunProgram(METRO_CALIBRATE_EXE, "--version");
  CHECK(r.exit_code == 0);
  CHECK(r.out == std::string("calibrate (metro) ") + kVersion + "\n");
  CHECK(r.err.empty());
#endif
  CHECK(std::string(kVersion).find('.') != std::string::npos);  // "0.1.0", from CMake
}

// ------------------------------------------------------------------------------- -o -

TEST_CASE("characterize -o - puts the JSON on stdout and the table on stderr", "[apps][unix]") {
  const std::string out = "metro_unix_report.json";
  std::remove(out.c_str());
  Run file = Characterize(kChest + " --type-a --settle auto -o " + out);
  REQUIRE(file.exit_code == 0);
  Run dash = Characterize(kChest + " --type-a --settle auto -o -");
  REQUIRE(dash.exit_code == 0);
  CheckSameNumbers(Json(dash.out), Json(Slurp(out)));
  CHECK(dash.out == Slurp(out));
  CHECK(dash.err == file.out);  // The same table, on the other stream.
  CHECK(dash.err.find("pitch_deg") != std::string::npos);
  CHECK_FALSE(Exists("-"));
  std::remove(out.c_str());
}

TEST_CASE("budget -o - and --accuracy -o - follow the same rule", "[apps][unix]") {
  const std::string out = "metro_unix_budget.json";
  std::remove(out.c_str());
  const std::string budget = kDatasets + "budgets/gum_h1_end_gauge.json";
  Run file = Characterize("budget " + budget + " -o " + out);
  REQUIRE(file.exit_code == 0);
  Run dash = Characterize("budget " + budget + " -o -");
  REQUIRE(dash.exit_code == 0);
  const nlohmann::json a = Json(dash.out), b = Json(Slurp(out));
  // Monte Carlo is seeded: the whole report is the same.
  CHECK(a == b);
  CHECK(dash.err == file.out);
  std::remove(out.c_str());

  const std::string acc = "metro_unix_accuracy.json";
  std::remove(acc.c_str());
  const std::string sweep = kDatasets + "table_sweep.csv --accuracy --table-axis yaw";
  file = Characterize(sweep + " -o " + acc);
  REQUIRE(file.exit_code == 0);
  dash = Characterize(sweep + " -o -");
  REQUIRE(dash.exit_code == 0);
  CHECK(Json(dash.out) == Json(Slurp(acc)));
  CHECK(dash.err == file.out);
  CHECK_FALSE(Exists("-"));
  std::remove(acc.c_str());
}

TEST_CASE("convert -o - writes the session.csv to stdout", "[apps][unix]") {
  const std::string out = "metro_unix_convert.csv";
  std::remove(out.c_str());
  const std::string capture = kDatasets + "static_chest_receiver.txt";
  REQUIRE(Characterize("convert " + capture + " -o " + out).exit_code == 0);
  Run dash = Characterize("convert " + capture + " -o -");
  REQUIRE(dash.exit_code == 0);
  CHECK(dash.out == Slurp(out));
  CHECK(dash.err.find("wrote stdout: ") == 0);
  CHECK_FALSE(Exists("-"));
  std::remove(out.c_str());
}

TEST_CASE("Outputs that cannot go to stdout refuse - (exit 2, no file named -)", "[apps][unix]") {
  Run r = Characterize(kChest + " --type-a -o metro_unix_x.json --html -");
  CHECK(r.exit_code == 2);
  CHECK(r.err == "error: --html -: the HTML report goes to a file\n");
  r = Characterize(kChest + " --type-a --allan --allan-csv -");
  CHECK(r.exit_code == 2);
  CHECK(r.err == "error: --allan-csv -: the Allan curves go to a file\n");
  r = Characterize(kDatasets + "table_sweep.csv --accuracy --html -");
  CHECK(r.exit_code == 2);
  CHECK(r.err == "error: --html -: the HTML view goes to a file\n");
  r = Characterize("batch " + kChest + " -o -");
  CHECK(r.exit_code == 2);
  CHECK(r.err == "error: -o -: batch writes a report per session: name a directory\n");
  r = Characterize("simulate --kind table --sensor 2 --format receiver -o - --reference-output -");
  CHECK(r.exit_code == 2);
  CHECK(r.err == "error: -o and --reference-output both name stdout (-): give one a file\n");
  CHECK(r.out.empty());
  CHECK_FALSE(Exists("-"));
  CHECK_FALSE(Exists("metro_unix_x.json"));
}

// ---------------------------------------------------------------------------- --quiet

TEST_CASE("characterize --quiet: a good run prints nothing on stderr, results still print",
          "[apps][unix]") {
  const std::string out = "metro_unix_quiet.json";
  std::remove(out.c_str());
  // A report without warnings (the white-noise gyro of the IMU sample): stderr stays empty.
  const std::string white = kDatasets + "static_imu_100hz.csv --quantity gx_dps";
  Run r = Characterize(white + " --type-a --quiet -o " + out);
  REQUIRE(r.exit_code == 0);
  CHECK(r.out.empty());  // No table.
  CHECK(r.err.empty());
  // Replacing the report is a note, also silenced.
  r = Characterize(white + " --type-a -q -o " + out);
  REQUIRE(r.exit_code == 0);
  CHECK(r.err.empty());
  r = Characterize(white + " --type-a -o " + out);
  CHECK(r.err.find("note: replaced existing " + out + "\n") != std::string::npos);
  CHECK(r.out.find("warnings:") == std::string::npos);
  // A run that fails after the outputs were checked replaces nothing and says nothing of it.
  {
    std::ifstream before_in(out);
    std::stringstream before;
    before << before_in.rdbuf();
    TempFile budget("{ not json");
    r = Characterize(white + " --type-a -o " + out + " --budget " + budget.path());
    CHECK(r.exit_code == 2);
    CHECK(r.err.find("note: replaced") == std::string::npos);
    std::ifstream after_in(out);
    std::stringstream after;
    after << after_in.rdbuf();
    CHECK(after.str() == before.str());
  }

  // The chest tag's report has warnings (autocorrelated quaternions): a quiet run prints
  // them to stderr, as the table ends, and nothing else.
  std::remove(out.c_str());
  r = Characterize(kChest + " --type-a -o " + out);
  REQUIRE(r.exit_code == 0);
  const size_t at = r.out.find("\nwarnings:\n");
  REQUIRE(at != std::string::npos);
  const std::string warnings = r.out.substr(at + 1);
  // Near-identical warnings are grouped: the first whole, the others counted and named.
  CHECK(warnings.find("sensor 2 qw: n_eff = ") != std::string::npos);
  CHECK(warnings.find("more like it: sensor 2 qx, qy, qz") != std::string::npos);
  r = Characterize(kChest + " --type-a -q -o " + out);
  REQUIRE(r.exit_code == 0);
  CHECK(r.out.empty());
  CHECK(r.err == warnings);
  std::remove(out.c_str());

  r = Characterize(kChest + " --type-a --quiet -o -");
  REQUIRE(r.exit_code == 0);
  CHECK(Json(r.out)["schema"] == "metro.report/1");
  CHECK(r.err == warnings);

  // Before or after the subcommand's name.
  const std::string budget = kDatasets + "budgets/gum_h1_end_gauge.json";
  for (const std::string& args :
       {"--quiet budget " + budget + " -o -", "budget " + budget + " -o - --quiet"}) {
    r = Characterize(args);
    INFO(args);
    REQUIRE(r.exit_code == 0);
    CHECK(Json(r.out)["schema"] == "metro.budget-report/1");
    CHECK(r.err.empty());
  }
  const std::string csv = "metro_unix_quiet.csv";
  r = Characterize("convert " + kDatasets + "static_chest_receiver.txt -o " + csv + " -q");
  REQUIRE(r.exit_code == 0);
  CHECK(r.err.empty());
  std::remove(csv.c_str());
}

TEST_CASE("A quiet run still prints its errors an error", "[apps][unix]") {
  TempFile bad("t_s,pitch_deg\n0,1\n1,2\n2,oops\n");
  Run r = Characterize(bad.path() + " --type-a --quiet -o -");
  CHECK(r.exit_code == 2);
  CHECK(r.out.empty());
  CHECK(r.err.find("error: " + bad.path() + ":4:2: pitch_deg") == 0);
}

#ifdef METRO_CALIBRATE_EXE

// A record of one tag in static poses and rotations, with known calibration.
std::string CalibrationRecord() {
  SimulationOptions options;
  options.seed = 11;
  Result<SimulatedSession> sim = SimulateCalibrationSession(options);
  REQUIRE(sim.ok());
  return FormatSessionCsv(sim.value().session);
}

TEST_CASE("calibrate fit -o - writes calibration.json to stdout; --quiet", "[apps][unix]") {
  TempFile record(CalibrationRecord());
  const std::string out = "metro_unix_calibration.json";
  std::remove(out.c_str());
  Run file = testing::RunProgram(METRO_CALIBRATE_EXE, "fit " + record.path() + " -o " + out);
  REQUIRE(file.exit_code == 0);
  Run dash = testing::RunProgram(METRO_CALIBRATE_EXE, "fit " + record.path() + " -o - --quiet");
  REQUIRE(dash.exit_code == 0);
  nlohmann::json a = Json(dash.out), b = Json(Slurp(out));
  a.erase("date_utc");
  b.erase("date_utc");
  CHECK(a == b);
  CHECK(dash.err.find("sensor ") == std::string::npos);  // The summary is a note.
  CHECK(file.err.find("wrote " + out) != std::string::npos);
  CHECK_FALSE(Exists("-"));
  std::remove(out.c_str());

  Run r = testing::RunProgram(METRO_CALIBRATE_EXE, "fit - - -o -");
  CHECK(r.exit_code == 2);
  CHECK(r.err == "error: stdin (-) can be read only once: name the other inputs\n");
  r = testing::RunProgram(METRO_CALIBRATE_EXE, "fit " + record.path() + " -o x.json --html -");
  CHECK(r.exit_code == 2);
  CHECK(r.err == "error: --html -: the certificate goes to a file\n");
}

TEST_CASE("calibrate blob -o -: binary to stdout, --hex - to stdout", "[apps][unix]") {
  const std::string cal = kDatasets + "golden/calibration_sensor2.json";
  const std::string args = "blob " + cal + " --sensor 2 --device-id 9abcdef012345678 --seq 3 ";
  Run r = testing::RunProgram(METRO_CALIBRATE_EXE, args + "-o - -q");
  REQUIRE(r.exit_code == 0);
  CHECK(r.out == Slurp(kDatasets + "golden/tag_sensor2.bin"));
  // -q leaves only the warnings: the golden calibration.json predates static_pose_temperature,
  // so its validity range is the operating range (issue #23).
  std::string warnings;
  for (const char* sensor : {"accel", "gyro"}) {
    warnings += std::string("warning: sensor 2 ") + sensor +
                ": calibration.json records no static_pose_temperature, so the span the "
                "temperature term was fitted on is unknown; the validity range is -40.00 .. 85.00 "
                "degC (from the MPU6050 operating range: no temperature span recorded), where the "
                "term may be extrapolated (refit with temp_c to record the span, or give "
                "--t-valid-min-c and --t-valid-max-c)\n";
  }
  CHECK(r.err == warnings);
  const std::string bin = "metro_unix_blob.bin";
  r = testing::RunProgram(METRO_CALIBRATE_EXE, args + "-o " + bin + " --hex -");
  REQUIRE(r.exit_code == 0);
  CHECK(r.out == Slurp(kDatasets + "golden/tag_sensor2.hex"));
  std::remove(bin.c_str());
  r = testing::RunProgram(METRO_CALIBRATE_EXE, args + "-o - --hex -");
  CHECK(r.exit_code == 2);
  CHECK(r.err == "error: -o and --hex both name stdout (-): give one a file\n");
}

#endif  // METRO_CALIBRATE_EXE

// --------------------------------------------------------- - reads stdin (LoadSession)
// These need LoadSession to read `-` from stdin (io/stdin_input.hpp).

TEST_CASE("A session piped to - gives the report of its file", "[apps][unix][stdin]") {
  const std::string chest = Slurp(kChest);
  Run file = Characterize(kChest + " --type-a --settle auto -o -");
  REQUIRE(file.exit_code == 0);
  for (StdinFrom from : {StdinFrom::kPipe, StdinFrom::kFile}) {
    Run in = CharacterizeStdin("- --type-a --settle auto -o -", chest, from);
    INFO(in.err);
    REQUIRE(in.exit_code == 0);
    CheckSameNumbers(Json(in.out), Json(file.out));
    CHECK(AfterFirstLine(in.err) == AfterFirstLine(file.err));  // The table, below the path.
  }
  // `characterize - --type-a`: no -o, the JSON on stdout.
  Run in = CharacterizeStdin("- --type-a --settle auto --quiet", chest);
  REQUIRE(in.exit_code == 0);
  CheckSameNumbers(Json(in.out), Json(file.out));
  // Only the report's warnings (the table's last lines), no table.
  const size_t at = file.err.find("\nwarnings:\n");
  REQUIRE(at != std::string::npos);
  CHECK(in.err == file.err.substr(at + 1));
}

TEST_CASE("convert - reads stdin; an empty stdin is an empty file", "[apps][unix][stdin]") {
  const std::string capture = kDatasets + "static_chest_receiver.txt";
  Run file = Characterize("convert " + capture + " -o -");
  REQUIRE(file.exit_code == 0);
  Run in = CharacterizeStdin("convert - -o -", Slurp(capture));
  INFO(in.err);
  REQUIRE(in.exit_code == 0);
  // The first line names the input; the rest is the same.
  CHECK(AfterFirstLine(in.out) == AfterFirstLine(file.out));

  Run empty = CharacterizeStdin("- --type-a", "");
  CHECK(empty.exit_code == 2);
  CHECK(empty.err.find("empty file") != std::string::npos);
  CHECK(empty.out.empty());
}

TEST_CASE("Standard input is read once: two - inputs are refused", "[apps][unix]") {
  Run r = Characterize("convert - - -o -");
  CHECK(r.exit_code == 2);
  CHECK(r.err == "error: stdin (-) can be read only once: name the other inputs\n");
  r = Characterize("convert --from imutk - " + kChest + " -o -");
  CHECK(r.exit_code == 2);
  CHECK(r.err ==
        "error: imu_tk files are read by name: stdin (-) takes a session.csv or a capture\n");
  r = Characterize("- --accuracy --reference -");
  CHECK(r.exit_code == 2);
  CHECK(r.err == "error: stdin (-) can be read only once: name the other inputs\n");
}

#ifdef METRO_CALIBRATE_EXE
TEST_CASE("calibrate fit - fits the record piped in", "[apps][unix][stdin]") {
  const std::string record = CalibrationRecord();
  TempFile file(record);
  Run a = testing::RunProgram(METRO_CALIBRATE_EXE, "fit " + file.path() + " -o - -q");
  REQUIRE(a.exit_code == 0);
  Run b = testing::RunProgramWithStdin(METRO_CALIBRATE_EXE, "fit - -o - -q", record);
  INFO(b.err);
  REQUIRE(b.exit_code == 0);
  const nlohmann::json ja = Json(a.out), jb = Json(b.out);
  CHECK(ja["tags"] == jb["tags"]);
}
#endif

}  // namespace
}  // namespace metro
