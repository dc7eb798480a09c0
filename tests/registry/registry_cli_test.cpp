// calibrate fit --spec / --registry, calibrate blob --registry and calibrate registry ...
// through the program (docs/conformity.md, docs/registry.md).
#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "metro/core/file.hpp"
#include "metro/io/session_io.hpp"
#include "metro/sim/calibration_session.hpp"
#include "registry/postgres_server.hpp"
#include "registry/sql_backend.hpp"
#include "support/run_program.hpp"

namespace metro {
namespace {

namespace fs = std::filesystem;

testing::ProgramRun Calibrate(const std::string& args) {
  return testing::RunProgram(METRO_CALIBRATE_EXE, args);
}

std::string Slurp(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// A working directory of its own, removed at the end.
struct Dir {
  Dir() : path(fmt::format("metro_registry_cli_{}_{}", ::getpid(), counter++)) {
    fs::create_directory(path);
  }
  ~Dir() { fs::remove_all(path); }
  std::string operator/(const std::string& name) const { return path + "/" + name; }
  std::string path;
  static inline int counter = 0;
};

// A simulated static-pose session of tag 4 (accelerometer only is fitted).
std::string WriteSession(const Dir& d) {
  SimulationOptions so;
  so.seed = 21;
  so.sensor = 4;
  Result<SimulatedSession> sim = SimulateCalibrationSession(so);
  REQUIRE(sim.ok());
  const std::string path = d / "session.csv";
  std::ofstream(path) << FormatSessionCsv(sim.value().session);
  return path;
}

TEST_CASE(
    "calibrate fit --spec: conformity in calibration.json and the certificate, exit 1 on fail",
    "[registry][conformity][apps]") {
  Dir d;
  const std::string session = WriteSession(d);
  // b_x within +-2000 LSB: passes; k_x above 1 g/LSB: impossible, fails.
  std::ofstream(d / "spec.json") << R"({"decision_rule": "guarded", "tolerances": [
  {"constant": "accel.b_x", "lower": -2000, "upper": 2000, "unit": "LSB"},
  {"constant": "accel.k_x", "lower": 1, "unit": "g_n/LSB"}]})";
  const std::string common = fmt::format(
      "fit {} -o {} --accel-only --spec {} --registry {} --station line-2 --operator ops --html {}",
      session, d / "cal.json", d / "spec.json", d / "reg.sqlite", d / "cert.html");
  testing::ProgramRun r = Calibrate(common);
  INFO(r.err);
  CHECK(r.exit_code == 0);  // A fail without --fail-on-nonconformity is reported, not fatal.
  CHECK(r.err.find("accel.k_x") != std::string::npos);
  const nlohmann::json cal = nlohmann::json::parse(Slurp(d / "cal.json"));
  REQUIRE(cal["conformity"].size() == 2);
  CHECK(cal["conformity"][0]["constant"] == "accel.b_x");
  CHECK(cal["conformity"][0]["decision"] == "pass");
  CHECK(cal["conformity"][1]["decision"] == "fail");
  CHECK(cal["conformity"][1]["p_conformance"].get<double>() == 0.0);
  CHECK(cal["conformity_rule"]["decision_rule"] == "guarded");
  const std::string html = Slurp(d / "cert.html");
  CHECK(html.find("6. Statement of conformity") != std::string::npos);
  CHECK(html.find("guarded acceptance with guard band w = U = 2 u") != std::string::npos);
  // calibrate report renders the statement from calibration.json alone.
  r = Calibrate(fmt::format("report {} --html {}", d / "cal.json", d / "cert2.html"));
  CHECK(r.exit_code == 0);
  CHECK(Slurp(d / "cert2.html").find("6. Statement of conformity") != std::string::npos);

  // Without the registry, so that it keeps one calibration (a second fit is another
  // calibration: its date differs once the clock passes a second).
  r = Calibrate(fmt::format("fit {} -o {} --accel-only --spec {} --fail-on-nonconformity", session,
                            d / "cal2.json", d / "spec.json"));
  CHECK(r.exit_code == 1);
  CHECK(r.err.find("1 constant(s) do not conform") != std::string::npos);

  // The registry holds the calibration (recorded again by blob: once, same certificate) with
  // station and operator; it belongs to a device once a blob is made.
  r = Calibrate(fmt::format("blob {} --sensor 4 --device-id 9ABCDEF012345678 -o {} --registry {}",
                            d / "cal.json", d / "tag.bin", d / "reg.sqlite"));
  INFO(r.err);
  CHECK(r.exit_code == 0);
  r = Calibrate(fmt::format("registry history --device-id 9ABCDEF012345678 --json --registry {}",
                            d / "reg.sqlite"));
  CHECK(r.exit_code == 0);
  const nlohmann::json h = nlohmann::json::parse(r.out);
  CHECK(h["device_id"] == "9ABCDEF012345678");
  REQUIRE(h["calibrations"].size() == 1);
  CHECK(h["calibrations"][0]["station"] == "line-2");
  // One certificate id everywhere: fit's certificate, report's certificate, the registry.
  const std::string id = h["calibrations"][0]["certificate_id"];
  CHECK(Slurp(d / "cert.html").find("certificate " + id) != std::string::npos);
  CHECK(Slurp(d / "cert2.html").find("certificate " + id) != std::string::npos);
  CHECK(h["calibrations"][0]["operator"] == "ops");
  CHECK(h["calibrations"][0]["conformity"].size() == 2);
  CHECK(h["calibrations"][0]["blobs"][0]["seq"] == 1);
  // Drift needs two calibrations: exit 2 with the reason.
  r = Calibrate(
      fmt::format("registry drift --device-id 9ABCDEF012345678 --registry {}", d / "reg.sqlite"));
  CHECK(r.exit_code == 2);
  CHECK(r.err.find("drift needs two") != std::string::npos);
  // Unknown device: exit 2.
  r = Calibrate(
      fmt::format("registry history --device-id 0000000000000001 --registry {}", d / "reg.sqlite"));
  CHECK(r.exit_code == 2);
  CHECK(r.err.find("device 0000000000000001 is not in the registry") != std::string::npos);
  // Export as CSV: a header with units' column, one row per constant (9: accel b, k, m).
  r = Calibrate(fmt::format("registry export --format csv --registry {}", d / "reg.sqlite"));
  CHECK(r.exit_code == 0);
  CHECK(r.out.rfind("registry_id,certificate_id,sensor,date_utc,recorded_utc,station,operator,"
                    "devices,constant,value,u,unit\n",
                    0) == 0);
  CHECK(std::count(r.out.begin(), r.out.end(), '\n') == 1 + 9);
  // Export as JSON to a file: every calibration as history gives it.
  r = Calibrate(fmt::format("registry export --format json -o {} --registry {}", d / "all.json",
                            d / "reg.sqlite"));
  CHECK(r.exit_code == 0);
  const nlohmann::json all = nlohmann::json::parse(Slurp(d / "all.json"));
  CHECK(all["schema_version"] == 2);
  REQUIRE(all["calibrations"].size() == 1);
  CHECK(all["calibrations"][0]["certificate_id"] == id);
  CHECK(all["calibrations"][0]["constants"].size() == 9);
  // Due, judged 400 days on: listed.
  r = Calibrate(
      fmt::format("registry due --registry {} --at 2099-01-01T00:00:00Z --json", d / "reg.sqlite"));
  CHECK(r.exit_code == 0);
  CHECK(nlohmann::json::parse(r.out)["devices"].size() == 1);
  // METRO_REGISTRY in the environment.
  r = testing::RunProgram("METRO_REGISTRY=" + d / "reg.sqlite" + " " + METRO_CALIBRATE_EXE,
                          "registry due --all");
  CHECK(r.exit_code == 0);
  CHECK(r.out.find("9ABCDEF012345678") != std::string::npos);
}

TEST_CASE("calibrate fit --spec and --registry: bad input exits 2 and writes nothing",
          "[registry][conformity][apps]") {
  Dir d;
  const std::string session = WriteSession(d);
  std::ofstream(d / "bad.json") << "{\"decision_rule\": \"simple\",\n  \"tolerances\": [\n"
                                   "  {\"constant\": \"accel.b_x\", \"lower\": 3, \"upper\": 1, "
                                   "\"unit\": \"LSB\"}]}";
  testing::ProgramRun r = Calibrate(
      fmt::format("fit {} -o {} --accel-only --spec {}", session, d / "cal.json", d / "bad.json"));
  CHECK(r.exit_code == 2);
  CHECK(r.err.find("bad.json:3:3: tolerances[0]: 'accel.b_x': lower 3 > upper 1") !=
        std::string::npos);
  CHECK_FALSE(fs::exists(d / "cal.json"));
  // A constant the fit does not have (no gyroscope with --accel-only): after the fit, still
  // exit 2 and nothing written.
  std::ofstream(d / "gyro.json") << R"({"decision_rule": "simple", "tolerances": [
  {"constant": "gyro.b_x", "upper": 1, "unit": "LSB"}]})";
  r = Calibrate(
      fmt::format("fit {} -o {} --accel-only --spec {}", session, d / "cal.json", d / "gyro.json"));
  CHECK(r.exit_code == 2);
  CHECK(r.err.find("sensor 4 has no constant 'gyro.b_x'") != std::string::npos);
  CHECK_FALSE(fs::exists(d / "cal.json"));
  // A registry that cannot be opened: exit 2 before any work.
  std::ofstream(d / "text.sqlite") << "this is not a database at all, it is plain text\n";
  r = Calibrate(fmt::format("fit {} -o {} --accel-only --registry {}", session, d / "cal.json",
                            d / "text.sqlite"));
  CHECK(r.exit_code == 2);
  CHECK(r.err.find("cannot open the SQLite registry") != std::string::npos);
  CHECK_FALSE(fs::exists(d / "cal.json"));
  r = Calibrate(fmt::format("registry history --device-id 9ABCDEF012345678 --registry {}",
                            d / "missing.sqlite"));
  CHECK(r.exit_code == 2);
  CHECK(r.err.find("no such registry file") != std::string::npos);
  CHECK_FALSE(fs::exists(d / "missing.sqlite"));
}

const std::string kGoldenCal =
    std::string(METRO_SOURCE_DIR) + "/datasets/golden/calibration_sensor2.json";

// One statement on a SQLite file, outside the registry's checks.
void Sql(const std::string& path, const std::string& sql) {
  Result<std::unique_ptr<registry_internal::SqlBackend>> db = registry_internal::OpenBackend(path);
  REQUIRE(db.ok());
  INFO(sql);
  REQUIRE(db.value()->Execute(sql, {}).ok());
}

// A registry holding one blob of the golden calibration (device 9ABCDEF012345678).
std::string MakeLineRegistry(const Dir& d) {
  const std::string line = d / "line.sqlite";
  testing::ProgramRun r =
      Calibrate(fmt::format("blob {} --sensor 2 --device-id 9ABCDEF012345678 -o {} --registry {}",
                            kGoldenCal, d / "first.bin", line));
  INFO(r.err);
  REQUIRE(r.exit_code == 0);
  return line;
}

TEST_CASE("The registry is never an output: -o, --hex, --html, METRO_REGISTRY, export -o",
          "[registry][apps][security]") {
  Dir d;
  const std::string line = MakeLineRegistry(d);
  const std::string before = Slurp(line);
  REQUIRE(before.size() > 540);
  WriteSession(d);
  const std::string blob =
      fmt::format("blob {} --sensor 2 --device-id 9ABCDEF012345678 ", kGoldenCal);
  const std::string refused = " is the file the command updates in place (";
  struct Case {
    std::string args, output;
  };
  fs::create_symlink(fs::absolute(line), d / "link.sqlite");
  for (const Case& c : {
           Case{blob + "-o " + line + " --registry " + line, "-o " + line},
           Case{blob + "-o " + d / "t.bin --hex " + line + " --registry " + line, "--hex " + line},
           Case{blob + "-o " + d / "link.sqlite --registry " + line, "-o " + d / "link.sqlite"},
           Case{"apply " + kGoldenCal + " " + d / "session.csv -o " + line + " --registry " + line,
                "-o " + line},
           Case{"fit " + d / "session.csv --accel-only -o " + d / "c.json --html " + line +
                    " --registry " + line,
                "--html " + line},
       }) {
    INFO(c.args);
    testing::ProgramRun r = Calibrate(c.args);
    CHECK(r.exit_code == 2);
    CHECK(r.err == "error: " + c.output + refused + "--registry " + line +
                       "): refusing to overwrite it; name another output file\n");
    CHECK(r.err.find("registry: recorded") == std::string::npos);
  }
  // METRO_REGISTRY names it the same way.
  testing::ProgramRun r = testing::RunProgram("METRO_REGISTRY=" + line + " " + METRO_CALIBRATE_EXE,
                                              blob + "-o " + line);
  CHECK(r.exit_code == 2);
  CHECK(r.err == "error: -o " + line + refused + "METRO_REGISTRY " + line +
                     "): refusing to overwrite it; name another output file\n");
  // The export reads it: its -o cannot be it.
  r = Calibrate(fmt::format("registry export --format json -o {} --registry {}", line, line));
  CHECK(r.exit_code == 2);
  CHECK(r.err == "error: -o " + line + " is the input file: refusing to overwrite it (--registry " +
                     line + "); name another output file\n");
  CHECK(Slurp(line) == before);
  CHECK_FALSE(fs::exists(d / "t.bin"));
  CHECK_FALSE(fs::exists(d / "c.json"));
  // Nor a device, a FIFO or the calibration it reads.
  REQUIRE(::mkfifo((d / "fifo").c_str(), 0600) == 0);
  for (const std::string& reg : {std::string("/dev/null"), d / "fifo"}) {
    r = Calibrate(blob + "-o " + d / "t.bin --registry " + reg);
    CHECK(r.exit_code == 2);
    CHECK(r.err.find("error: --registry " + reg + " is a") == 0);
  }
  r = Calibrate(blob + "-o " + d / "t.bin --registry " + kGoldenCal);
  CHECK(r.exit_code == 2);
  CHECK(r.err.find("is also an input of the command (CALIBRATION") != std::string::npos);
  CHECK_FALSE(fs::exists(d / "t.bin"));
}

TEST_CASE("A registry with a bad schema_version exits 2 naming the value, never aborts or loops",
          "[registry][apps][security]") {
  Dir d;
  const std::string line = MakeLineRegistry(d);
  for (const std::string value : {"'abc'", "99999999999", "-1"}) {
    INFO(value);
    Sql(line, "UPDATE schema_version SET version = " + value);
    const std::string before = Slurp(line);
    for (const std::string& args :
         {"registry history --device-id 9ABCDEF012345678 --registry " + line,
          fmt::format("blob {} --sensor 2 --device-id 9ABCDEF012345678 -o {} --registry {}",
                      kGoldenCal, d / "t.bin", line)}) {
      testing::ProgramRun r =
          testing::RunProgram("timeout 20 " + std::string(METRO_CALIBRATE_EXE), args);
      CHECK(r.exit_code == 2);
      CHECK(r.err.rfind("error: " + line + ": ", 0) == 0);
      CHECK(r.err.find(value == "99999999999" ? "version 99999999999, newer than this program's 2"
                                              : "expected one row holding a whole number from "
                                                "1 to 2") != std::string::npos);
      CHECK(r.err.find("terminate") == std::string::npos);
    }
    CHECK(Slurp(line) == before);
    CHECK_FALSE(fs::exists(d / "t.bin"));
  }
}

TEST_CASE("A read-only registry (file 0444 in a read-only folder) can be queried",
          "[registry][apps][security]") {
  Dir d;
  const std::string made = MakeLineRegistry(d);
  // A folder of its own under /tmp, which another user can reach.
  char tmpl[] = "/tmp/metro_ro_registry_XXXXXX";
  REQUIRE(::mkdtemp(tmpl) != nullptr);
  const std::string dir = tmpl;
  const std::string line = dir + "/line.sqlite";
  fs::copy_file(made, line);
  REQUIRE(::chmod(line.c_str(), 0444) == 0);
  REQUIRE(::chmod(dir.c_str(), 0555) == 0);
  const std::string before = Slurp(line);
  // As root the permissions do not bind: run the query as nobody then.
  const std::string as = ::geteuid() == 0 ? "runuser -u nobody -- " : "";
  testing::ProgramRun r = testing::RunProgram(
      as + METRO_CALIBRATE_EXE,
      "registry history --device-id 9ABCDEF012345678 --json --registry " + line);
  INFO(r.err);
  CHECK(r.exit_code == 0);
  CHECK(r.out.find("\"device_id\": \"9ABCDEF012345678\"") != std::string::npos);
  r = testing::RunProgram(as + METRO_CALIBRATE_EXE, "registry due --all --registry " + line);
  CHECK(r.exit_code == 0);
  CHECK(Slurp(line) == before);
  size_t entries = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir)) ++entries;
  CHECK(entries == 1);  // Nothing made beside it.
  ::chmod(dir.c_str(), 0755);
  fs::remove_all(dir);
}

TEST_CASE("A foreign SQLite file is refused by queries and recordings, never migrated",
          "[registry][apps][security]") {
  Dir d;
  const std::string foreign = d / "parts.sqlite";
  Sql(foreign, "CREATE TABLE parts (id INTEGER)");
  Sql(foreign, "INSERT INTO parts VALUES (1)");
  const std::string before = Slurp(foreign);
  for (const std::string& args :
       {"registry history --device-id 9ABCDEF012345678 --registry " + foreign,
        "registry export --registry " + foreign,
        fmt::format("blob {} --sensor 2 --device-id 9ABCDEF012345678 -o {} --registry {}",
                    kGoldenCal, d / "t.bin", foreign)}) {
    INFO(args);
    testing::ProgramRun r = Calibrate(args);
    CHECK(r.exit_code == 2);
    CHECK(r.err == "error: " + foreign +
                       ": not a metro registry: it has tables (parts) but no schema_version; "
                       "metro changes nothing in it: name a new file for the registry\n");
  }
  CHECK(Slurp(foreign) == before);
  CHECK_FALSE(fs::exists(d / "t.bin"));
}

}  // namespace
}  // namespace metro

namespace metro {
namespace {

TEST_CASE("calibrate blob --registry postgresql://... and registry history on PostgreSQL",
          "[registry][apps]") {
  std::string why;
  testing::PostgresServer* pg = testing::PostgresServer::Get(&why);
  if (pg == nullptr) {
    if (testing::PostgresServer::Required()) FAIL(why);
    WARN(why);
    return;
  }
  const std::string url = pg->NewDatabase();
  Dir d;
  const std::string golden =
      std::string(METRO_SOURCE_DIR) + "/datasets/golden/calibration_sensor2.json";
  testing::ProgramRun r =
      Calibrate(fmt::format("blob {} --sensor 2 --device-id 9ABCDEF012345678 -o {} --registry '{}'",
                            golden, d / "tag.bin", url));
  INFO(r.err);
  CHECK(r.exit_code == 0);
  r = testing::RunProgram("METRO_REGISTRY='" + url + "' " + METRO_CALIBRATE_EXE,
                          "registry history --device-id 9ABCDEF012345678 --json");
  CHECK(r.exit_code == 0);
  const nlohmann::json h = nlohmann::json::parse(r.out);
  REQUIRE(h["calibrations"].size() == 1);
  CHECK(h["calibrations"][0]["blobs"].size() == 1);
  CHECK(h["calibrations"][0]["constants"].size() == 27);
}

}  // namespace
}  // namespace metro
