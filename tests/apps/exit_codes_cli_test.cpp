// Exit codes from the kind of the error (apps/exit_codes.hpp ExitCodeFor, docs/unix.md "Exit
// codes"; issue #25 point 7): 2 always means bad input or usage, 1 a run or a write that
// failed. Each case runs the built program.
#include <sys/stat.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include "support/bundled_fit.hpp"
#include "support/run_program.hpp"
#include "support/temp_file.hpp"

namespace metro {
namespace {

using Run = testing::ProgramRun;

const std::string kDatasets = std::string(METRO_SOURCE_DIR) + "/datasets/";

// A scratch folder for this file's outputs, removed when the test program ends.
const std::string& Scratch() {
  static const testing::ScratchFolder folder("metro_exit_codes");
  return folder.path();
}
// A folder that does not exist (and is never created by these tests).
const std::string kMissingDir = "metro_exit_codes_no_such_dir";

bool Exists(const std::string& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0;
}

Run Calibrate(const std::string& args) { return testing::RunProgram(METRO_CALIBRATE_EXE, args); }

#ifdef METRO_CHARACTERIZE_EXE
Run Characterize(const std::string& args) {
  return testing::RunProgram(METRO_CHARACTERIZE_EXE, args);
}
#endif

// calibration.json fitted from the bundled calibration session (once per build for all the
// test processes, support/bundled_fit.hpp).
const std::string& FittedCalibration() {
  static const std::string path = testing::BundledFit("");
  return path;
}

void CheckMissingFolder(const Run& r, const std::string& option) {
  INFO(r.err);
  CHECK(r.exit_code == 2);
  CHECK_THAT(r.err, Catch::Contains(option + " " + kMissingDir + "/"));
  CHECK_THAT(r.err, Catch::Contains("the directory " + kMissingDir + " does not exist"));
  CHECK_FALSE(Exists(kMissingDir));
}

// The bundled calibration session up to `t_end_s` (header kept), written to `path`.
void WriteSessionPrefix(const std::string& path, double t_end_s) {
  std::ifstream in(kDatasets + "calibration_session.csv");
  std::ofstream out(path);
  std::string line;
  REQUIRE(std::getline(in, line));
  out << line << "\n";
  while (std::getline(in, line) && std::stod(line.substr(0, line.find(','))) < t_end_s) {
    out << line << "\n";
  }
}

}  // namespace

TEST_CASE(
    "Exit codes: calibrate fit refuses a record too short for the model (2) and fails on "
    "a degenerate one (1)",
    "[apps][unix][exit]") {
  // The first 30 s hold 5 static poses: the full model's 9 parameters cannot be fitted from
  // them. The record is the problem, so the exit is 2 (docs/calibration-model.md "Refused
  // input").
  const std::string short_record = Scratch() + "metro_exit_codes_30s.csv";
  WriteSessionPrefix(short_record, 30.0);
  Run r = Calibrate("fit " + short_record + " --accel-only -q -o " + Scratch() +
                    "metro_exit_codes_fit.json");
  CHECK(r.exit_code == 2);
  CHECK_THAT(r.err, Catch::Contains("sensor 2: 5 static poses found"));
  // The first 100 s hold 16 poses in 8 orientations: enough poses, but the fit cannot
  // determine the 12 constants of the model with its temperature term. The fit failed: 1.
  const std::string degenerate = Scratch() + "metro_exit_codes_100s.csv";
  WriteSessionPrefix(degenerate, 100.0);
  r = Calibrate("fit " + degenerate + " --accel-only -q -o " + Scratch() +
                "metro_exit_codes_fit.json");
  CHECK(r.exit_code == 1);
  CHECK_THAT(r.err, Catch::Contains("sensor 2: degenerate calibration"));
  CHECK_FALSE(Exists(Scratch() + "metro_exit_codes_fit.json"));
  std::remove(short_record.c_str());
  std::remove(degenerate.c_str());
}

TEST_CASE(
    "Exit codes: calibrate inspect of a file it cannot read is 2 and of one with no calibration 1",
    "[apps][unix][exit]") {
  // Not a regular file (a FIFO): unreadable as a blob, exit 2 (and not waited on).
  const std::string fifo = Scratch() + "metro_exit_codes_fifo.bin";
  std::remove(fifo.c_str());
  REQUIRE(::mkfifo(fifo.c_str(), 0600) == 0);
  Run r = Calibrate("inspect " + fifo);
  CHECK(r.exit_code == 2);
  CHECK_THAT(r.err, Catch::Contains("not a regular file"));
  std::remove(fifo.c_str());

  // Larger than any blob or image: refused before it is read, exit 2.
  testing::TempFile big(std::string(70000, 'x'), ".bin");
  r = Calibrate("inspect " + big.path());
  CHECK(r.exit_code == 2);
  CHECK_THAT(r.err, Catch::Contains("calibrate inspect reads at most 65536 bytes"));

  // Intel HEX syntax error: the file is not what it says, exit 2 with line and column.
  testing::TempFile bad_hex(":zz\n", ".hex");
  r = Calibrate("inspect " + bad_hex.path());
  CHECK(r.exit_code == 2);
  CHECK_THAT(r.err, Catch::Contains(bad_hex.path() + ":1:1: Intel HEX"));

  // A readable .bin holding no valid calibration: the inspection ran and found none, exit 1
  // (docs/unix.md), with its verdict on stdout.
  testing::TempFile garbage(std::string(64, '\x5a'), ".bin");
  r = Calibrate("inspect " + garbage.path());
  CHECK(r.exit_code == 1);
  CHECK_THAT(r.out, Catch::Contains("result: NO VALID CALIBRATION"));
}

TEST_CASE("Exit codes: an output into a missing folder is 2 in every calibrate command",
          "[apps][unix][exit]") {
  const std::string& cal = FittedCalibration();
  const std::string session = kDatasets + "calibration_session.csv";
  CheckMissingFolder(Calibrate("fit " + session + " -q -o " + kMissingDir + "/cal.json"), "-o");
  CheckMissingFolder(Calibrate("fit " + session + " -q -o " + Scratch() +
                               "metro_exit_codes_cal2.json --html " + kMissingDir + "/cert.html"),
                     "--html");
  CHECK_FALSE(Exists(Scratch() + "metro_exit_codes_cal2.json"));  // refused before any work
  CheckMissingFolder(Calibrate("apply " + cal + " " + session + " -o " + kMissingDir + "/a.csv"),
                     "-o");
  CheckMissingFolder(Calibrate("blob " + cal + " --sensor 2 --device-id 0011223344556677 -o " +
                               kMissingDir + "/tag.bin"),
                     "-o");
  CheckMissingFolder(
      Calibrate("blob " + cal + " --sensor 2 --device-id 0011223344556677 -o " + Scratch() +
                "metro_exit_codes_tag.bin --hex " + kMissingDir + "/tag.hex"),
      "--hex");
  CHECK_FALSE(Exists(Scratch() + "metro_exit_codes_tag.bin"));  // neither is written
  CheckMissingFolder(Calibrate("report " + cal + " --html " + kMissingDir + "/cert.html"),
                     "--html");
}

#ifdef METRO_CHARACTERIZE_EXE
TEST_CASE("Exit codes: an output into a missing folder is 2 in every characterize command",
          "[apps][unix][exit]") {
  const std::string chest = kDatasets + "static_chest.csv";
  CheckMissingFolder(Characterize(chest + " --type-a -o " + kMissingDir + "/r.json"), "-o");
  CheckMissingFolder(Characterize("analyze " + chest + " -o " + kMissingDir + "/r.json"), "-o");
  CheckMissingFolder(Characterize(chest + " --type-a -o " + Scratch() +
                                  "metro_exit_codes_r.json --html " + kMissingDir + "/r.html"),
                     "--html");
  CHECK_FALSE(Exists(Scratch() + "metro_exit_codes_r.json"));
  CheckMissingFolder(
      Characterize(kDatasets + "table_sweep.csv --accuracy -o " + kMissingDir + "/a.json"), "-o");
  CheckMissingFolder(
      Characterize("accuracy " + kDatasets + "table_sweep.csv -o " + kMissingDir + "/a.json"),
      "-o");
  CheckMissingFolder(Characterize("budget " + kDatasets + "budgets/gum_h1_end_gauge.json -o " +
                                  kMissingDir + "/b.json"),
                     "-o");
  CheckMissingFolder(Characterize("convert " + kDatasets + "static_chest_receiver.txt -o " +
                                  kMissingDir + "/s.csv"),
                     "-o");
  CheckMissingFolder(Characterize("simulate -o " + kMissingDir + "/s.csv"), "-o");
  CheckMissingFolder(
      Characterize("report " + FittedCalibration() + " --html " + kMissingDir + "/c.html"),
      "--html");
}

TEST_CASE("Exit codes: a write that fails after it started is 1 and bad input 2",
          "[apps][unix][exit]") {
  const std::string chest = kDatasets + "static_chest.csv";
  // stdout on a full device: the report could not be written (io), exit 1.
  Run r = Characterize(chest + " --type-a > /dev/full");
  CHECK(r.exit_code == 1);
  CHECK_THAT(r.err, Catch::Contains("cannot write to stdout"));
  // A malformed row: input, exit 2 with file:line:column.
  testing::TempFile bad("t_s,sensor,pitch_deg\n0.0,1,1.0\n0.1,1,abc\n");
  r = Characterize(bad.path() + " --type-a");
  CHECK(r.exit_code == 2);
  CHECK_THAT(r.err, Catch::Contains(bad.path() + ":3:3: "));
  // An unknown option value: usage, exit 2.
  r = Characterize(chest + " --type-a --settle sometimes");
  CHECK(r.exit_code == 2);
}
#endif

}  // namespace metro
