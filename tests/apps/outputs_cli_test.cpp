// Issue #20 parts 2, 4 and 5 through the programs (docs/security.md): outputs never
// destroy (devices, FIFOs, directories, inputs, each other, modes, long names, stdout
// errors, JSON and HTML together), batch owns its folder, and data never reaches the
// terminal raw.
#include <sys/file.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "metro/blob/blob.hpp"
#include "metro/core/file.hpp"
#include "metro/report/batch.hpp"
#include "support/run_program.hpp"
#include "support/temp_file.hpp"

namespace metro {
namespace {

namespace fs = std::filesystem;
using Run = testing::ProgramRun;

const std::string kDatasets = std::string(METRO_SOURCE_DIR) + "/datasets/";
const std::string kChest = kDatasets + "static_chest.csv";
const std::string kSweep = kDatasets + "table_sweep.csv";
const std::string kBudget = kDatasets + "budgets/gum_h1_end_gauge.json";

Run Characterize(const std::string& args) {
  return testing::RunProgram(METRO_CHARACTERIZE_EXE, args);
}

using Dir = testing::WorkDir;
using testing::Put;

std::string Get(const std::string& path) {
  Result<std::string> text = ReadFile(path);
  REQUIRE(text.ok());
  return text.value();
}

mode_t TypeOf(const std::string& path) {
  struct stat st {};
  REQUIRE(::stat(path.c_str(), &st) == 0);
  return st.st_mode & S_IFMT;
}

mode_t ModeOf(const std::string& path) {
  struct stat st {};
  REQUIRE(::stat(path.c_str(), &st) == 0);
  return st.st_mode & 07777;
}

// No temporary (.metro-XXXXXX) left in `dir`.
bool NoTemporaries(const std::string& dir) {
  for (const auto& e : fs::directory_iterator(dir)) {
    const std::string name = e.path().filename().string();
    if (name.rfind(".metro-", 0) == 0 && name != kBatchLockName) return false;
  }
  return true;
}

// ---------------------------------------------------------------- 2. outputs never destroy

TEST_CASE("Outputs: -o on a device is refused before any work (exit 2), the device stays",
          "[apps][unix][security]") {
  const std::string expected =
      "error: -o /dev/full is a character device: metro writes an output to a new file and "
      "renames it into place, which would replace it; name a regular file (or - for stdout, "
      "redirected where you want it)\n";
  for (const std::string& args : std::vector<std::string>{
           kChest + " --type-a -o /dev/full", "convert " + kChest + " -o /dev/full",
           "simulate -o /dev/full", "budget " + kBudget + " -o /dev/full",
           kSweep + " --accuracy -o /dev/full"}) {
    INFO(args);
    Run r = Characterize(args);
    CHECK(r.exit_code == 2);
    CHECK(r.err == expected);
    CHECK(r.out.empty());
  }
  Run r = Characterize(kChest + " --type-a -o x.json --html /dev/null");
  CHECK(r.exit_code == 2);
  CHECK(r.err.find("error: --html /dev/null is a character device") == 0);
  r = Characterize("report " + kDatasets + "golden/calibration_sensor2.json --html /dev/zero");
  CHECK(r.exit_code == 2);
  CHECK(r.err.find("error: --html /dev/zero is a character device") == 0);
  CHECK(TypeOf("/dev/full") == S_IFCHR);
  CHECK(TypeOf("/dev/null") == S_IFCHR);
  CHECK_FALSE(fs::exists("x.json"));
}

TEST_CASE("Outputs: a FIFO, a socket, a directory or a path in /dev is refused (exit 2)",
          "[apps][unix][security]") {
  Dir d;
  const std::string fifo = d / "out.fifo";
  REQUIRE(::mkfifo(fifo.c_str(), 0600) == 0);
  Run r = Characterize(kChest + " --type-a -o " + fifo);
  CHECK(r.exit_code == 2);
  CHECK(r.err.find("error: -o " + fifo + " is a FIFO (named pipe): metro writes") == 0);
  CHECK(TypeOf(fifo) == S_IFIFO);

  const std::string sock = d / "out.sock";
  const int fd = ::socket(AF_UNIX, SOCK_STREAM, 0);
  REQUIRE(fd >= 0);
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  std::snprintf(addr.sun_path, sizeof addr.sun_path, "%s", sock.c_str());
  REQUIRE(::bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) == 0);
  r = Characterize("convert " + kChest + " -o " + sock);
  CHECK(r.exit_code == 2);
  CHECK(r.err.find("error: -o " + sock + " is a socket") == 0);
  CHECK(TypeOf(sock) == S_IFSOCK);
  ::close(fd);

  r = Characterize("simulate -o " + d.path);
  CHECK(r.exit_code == 2);
  CHECK(r.err.find("error: -o " + d.path + " is a directory") == 0);
  CHECK(fs::is_directory(d.path));

  r = Characterize("simulate -o /dev/metro_no_such_file");
  CHECK(r.exit_code == 2);
  CHECK(r.err.find("error: -o /dev/metro_no_such_file is in /dev") == 0);
  r = Characterize("simulate -o " + d.path + "/no/such/dir/x.csv");
  CHECK(r.exit_code == 2);
  CHECK(r.err == "error: -o " + d.path + "/no/such/dir/x.csv: the directory " + d.path +
                     "/no/such/dir does not exist: create it first\n");
  CHECK(NoTemporaries(d.path));
}

TEST_CASE("Outputs: no output is an input of the command (registry, budget, reference-u)",
          "[apps][unix][security]") {
  Dir d;
  const std::string reg = d / "reg.json";
  const std::string reg_text = "{\"2\": \"Chest\"}\n";
  Put(reg, reg_text);
  Run r = Characterize(kChest + " --type-a --tag-registry " + reg + " -o " + reg);
  CHECK(r.exit_code == 2);
  CHECK(r.err == "error: -o " + reg +
                     " is the input file: refusing to overwrite it (--tag-registry " + reg +
                     "); name another output file\n");
  CHECK(Get(reg) == reg_text);
  // Through a symlink and a hard link.
  fs::create_symlink(fs::absolute(reg), d / "reg_link.json");
  fs::create_hard_link(reg, d / "reg_hard.json");
  for (const std::string& out : {d / "reg_link.json", d / "reg_hard.json"}) {
    r = Characterize(kChest + " --type-a --tag-registry " + reg + " --html " + out);
    CHECK(r.exit_code == 2);
    CHECK(r.err.find("error: --html " + out + " is the input file") == 0);
  }
  CHECK(Get(reg) == reg_text);

  const std::string ru = d / "ru.json";
  const std::string ru_text = Get(kDatasets + "budgets/tag_static_angle.json");
  Put(ru, ru_text);
  r = Characterize(kSweep + " --accuracy --reference-u " + ru + " -o " + ru);
  CHECK(r.exit_code == 2);
  CHECK(r.err == "error: -o " + ru +
                     " is the input file: refusing to overwrite it (--reference-u " + ru +
                     "); name another output file\n");
  CHECK(Get(ru) == ru_text);
  // The budget through a symlink.
  fs::create_symlink(fs::absolute(ru), d / "ru_link.json");
  r = Characterize("budget " + ru + " -o " + d / "ru_link.json");
  CHECK(r.exit_code == 2);
  CHECK(r.err.find("(BUDGET " + ru + ")") != std::string::npos);
  CHECK(Get(ru) == ru_text);

  // A session the budget names (relative to the budget's folder) is an input too: the report
  // overwrote it.
  const std::string session = d / "s.csv";
  const std::string session_text = "t_s,pitch_deg\n0,1.0\n0.1,1.2\n0.2,0.9\n0.3,1.1\n";
  Put(session, session_text);
  const std::string sb = d / "sb.json";
  Put(sb, R"({"measurand": {"name": "p", "model": "p"},
              "inputs": [{"name": "p", "type_a": {"session": "s.csv",
                                                    "quantity": "pitch_deg"}}]})");
  r = Characterize("budget " + sb + " -o " + session);
  CHECK(r.exit_code == 2);
  CHECK(r.err == "error: -o " + session + " is the input file: refusing to overwrite it (a " +
                     "session of BUDGET " + session + "); name another output file\n");
  r = Characterize(kChest + " --type-a --budget " + sb + " --html " + session);
  CHECK(r.exit_code == 2);
  CHECK(r.err.find("(a session of --budget " + session + ")") != std::string::npos);
  CHECK(Get(session) == session_text);
  r = Characterize("budget " + sb + " -o " + d / "sb_report.json");
  INFO(r.err);
  CHECK(r.exit_code == 0);
  CHECK(NoTemporaries(d.path));
}

TEST_CASE("Outputs: two outputs of one command never name the same file",
          "[apps][unix][security]") {
  Dir d;
  const std::string x = d / "x";
  Run r = Characterize(kChest + " --type-a -o " + x + " --html " + x);
  CHECK(r.exit_code == 2);
  CHECK(r.err == "error: --html and -o name the same file (-o " + x + ", --html " + x +
                     "): give each output its own file\n");
  const std::string a = d / "a.json";
  r = Characterize(kChest + " --type-a --allan -o " + a + " --allan-csv " + a);
  CHECK(r.exit_code == 2);
  CHECK(r.err.find("error: --allan-csv and -o name the same file") == 0);
  // Not yet existing, but the same file: through a symlinked directory and `..`.
  fs::create_directories(d / "sub");
  fs::create_directory_symlink(fs::absolute(d / "sub"), d / "sublink");
  r = Characterize(kChest + " --type-a -o " + d / "sub/r.json" + " --html " +
                   d / "sublink/../sublink/r.json");
  CHECK(r.exit_code == 2);
  CHECK(r.err.find("error: --html and -o name the same file") == 0);
  r = Characterize("simulate --kind table --sensor 2 -o " + x + " --reference-output " + x);
  CHECK(r.exit_code == 2);
  CHECK(r.err.find("error: --reference-output and -o name the same file") == 0);
  CHECK_FALSE(fs::exists(x));
  CHECK_FALSE(fs::exists(a));
  CHECK_FALSE(fs::exists(d / "sub/r.json"));
}

TEST_CASE("Outputs: a replaced report keeps its mode, and a 254-character name works",
          "[apps][unix][security]") {
  Dir d;
  const std::string out = d / "report.json";
  Put(out, "old\n");
  REQUIRE(::chmod(out.c_str(), 0600) == 0);
  Run r = Characterize(kChest + " --type-a -q -o " + out);
  REQUIRE(r.exit_code == 0);
  CHECK(ModeOf(out) == 0600);
  CHECK(Get(out).find("\"schema\": \"metro.report/1\"") != std::string::npos);
  REQUIRE(::chmod(out.c_str(), 0640) == 0);
  r = Characterize("convert " + kChest + " -q -o " + out);
  REQUIRE(r.exit_code == 0);
  CHECK(ModeOf(out) == 0640);

  const std::string long_name = d / (std::string(249, 'r') + ".json");  // 254 characters.
  REQUIRE(fs::path(long_name).filename().string().size() == 254);
  r = Characterize(kChest + " --type-a -q -o " + long_name);
  INFO(r.err);
  CHECK(r.exit_code == 0);
  CHECK(fs::exists(long_name));
  r = Characterize(kChest + " --type-a -q -o " + long_name);  // Replacing it too.
  CHECK(r.exit_code == 0);
  CHECK(NoTemporaries(d.path));
}

TEST_CASE("Outputs: a failed write to stdout is exit 1 with a message, in every command",
          "[apps][unix][security]") {
  Dir d;
  const std::string expected_start = "error: cannot write to stdout: ";
  for (const std::string& args : std::vector<std::string>{
           kChest + " --type-a -q", kChest + " --type-a -o " + d / "r.json", "budget " + kBudget,
           "convert " + kChest + " -o -", "simulate -o -", "--version",
           "report " + kDatasets + "golden/calibration_sensor2.json --html -"}) {
    INFO(args);
    Run r = Characterize(args + " > /dev/full");
    CHECK(r.exit_code == 1);
    CHECK(r.err.rfind(expected_start, 0) == 0);
  }
#ifdef METRO_CALIBRATE_EXE
  const std::string cal = kDatasets + "golden/calibration_sensor2.json";
  for (const std::string& args : std::vector<std::string>{
           "report " + cal, "inspect " + kDatasets + "golden/tag_sensor2.bin", "--version",
           "blob " + cal + " --sensor 2 --device-id 9abcdef012345678 -o " + d / "t.bin" +
               " --hex -"}) {
    INFO(args);
    Run r = testing::RunProgram(METRO_CALIBRATE_EXE, args + " > /dev/full");
    CHECK(r.exit_code == 1);
    CHECK(r.err.find(expected_start) != std::string::npos);
  }
#endif
}

TEST_CASE("Outputs: the JSON and the HTML of one run are replaced together or not at all",
          "[apps][unix][security]") {
  Dir d;
  const std::string json = d / "r.json", html = d / "r.html";
  Put(json, "old json\n");
  Put(html, "old html\n");
  // A file size limit (SIGXFSZ ignored, so write() fails with EFBIG) that the JSON report
  // (about 370 KB with its plot data) fits in and the HTML (about 690 KB of plots) does not
  // (1000 blocks of 512 bytes, as /bin/sh counts them):
  // the disk is full when the second file is written.
  Run r = Characterize(kChest + " --type-a -q -o " + json + " --html " + html);
  REQUIRE(r.exit_code == 0);
  const auto json_size = fs::file_size(json), html_size = fs::file_size(html);
  REQUIRE(json_size < 450 * 1024);
  REQUIRE(html_size > 550 * 1024);
  Put(json, "old json\n");
  Put(html, "old html\n");
  r = testing::RunProgram(
      "trap '' XFSZ; ulimit -f 1000; exec " + std::string(METRO_CHARACTERIZE_EXE),
      kChest + " --type-a -q -o " + json + " --html " + html);
  CHECK(r.exit_code == 1);
  CHECK(r.err == "error: cannot write '" + html + "': File too large\n");
  CHECK(Get(json) == "old json\n");
  CHECK(Get(html) == "old html\n");
  CHECK(NoTemporaries(d.path));
}

#ifdef METRO_CALIBRATE_EXE
TEST_CASE("Outputs: calibrate blob -o x --hex x, -o /dev/full and fit/apply/report inputs",
          "[apps][unix][security]") {
  Dir d;
  const std::string cal = kDatasets + "golden/calibration_sensor2.json";
  const std::string args = "blob " + cal + " --sensor 2 --device-id 9abcdef012345678 ";
  const std::string bb = d / "bb.bin";
  Run r = testing::RunProgram(METRO_CALIBRATE_EXE, args + "-o " + bb + " --hex " + bb);
  CHECK(r.exit_code == 2);
  CHECK(r.err == "error: --hex and -o name the same file (-o " + bb + ", --hex " + bb +
                     "): give each output its own file\n");
  CHECK_FALSE(fs::exists(bb));
  r = testing::RunProgram(METRO_CALIBRATE_EXE, args + "-o /dev/full");
  CHECK(r.exit_code == 2);
  CHECK(r.err.find("error: -o /dev/full is a character device") == 0);
  CHECK(TypeOf("/dev/full") == S_IFCHR);

  const std::string copy = d / "cal.json";
  Put(copy, Get(cal));
  fs::create_hard_link(copy, d / "cal_hard.json");
  r = testing::RunProgram(METRO_CALIBRATE_EXE, "report " + copy + " --html " + d / "cal_hard.json");
  CHECK(r.exit_code == 2);
  CHECK(r.err == "error: --html " + d / "cal_hard.json" +
                     " is the input file: refusing to overwrite it (CALIBRATION " + copy +
                     "); name another output file\n");
  r = testing::RunProgram(METRO_CALIBRATE_EXE,
                          "apply " + copy + " " + kChest + " -o " + d / "cal_hard.json");
  CHECK(r.exit_code == 2);
  CHECK(r.err.find("(CALIBRATION " + copy + ")") != std::string::npos);
  r = testing::RunProgram(METRO_CALIBRATE_EXE, "fit " + kChest + " -o /dev/null");
  CHECK(r.exit_code == 2);
  CHECK(r.err.find("error: -o /dev/null is a character device") == 0);
  r = testing::RunProgram(METRO_CALIBRATE_EXE,
                          "fit " + kChest + " -o " + d / "c.json" + " --html " + d / "c.json");
  CHECK(r.exit_code == 2);
  CHECK(r.err.find("error: --html and -o name the same file") == 0);
  CHECK(Get(copy) == Get(cal));

  // The blob and its HEX are replaced together: with the .bin (540 bytes) fitting a 1 KiB
  // file size limit and the HEX (two slot pages, about 6 KiB) not, the old pair stays.
  const std::string bin = d / "t.bin", hex = d / "t.hex";
  r = testing::RunProgram(METRO_CALIBRATE_EXE, args + "--seq 3 -o " + bin + " --hex " + hex);
  REQUIRE(r.exit_code == 0);
  REQUIRE(fs::file_size(bin) < 1024);
  REQUIRE(fs::file_size(hex) > 1024);
  Put(bin, "old bin\n");
  Put(hex, "old hex\n");
  r = testing::RunProgram("trap '' XFSZ; ulimit -f 2; exec " + std::string(METRO_CALIBRATE_EXE),
                          args + "--seq 4 -o " + bin + " --hex " + hex);
  CHECK(r.exit_code == 1);
  CHECK(r.err.find("error: cannot write '" + hex + "': File too large\n") != std::string::npos);
  CHECK(Get(bin) == "old bin\n");
  CHECK(Get(hex) == "old hex\n");
  CHECK(NoTemporaries(d.path));
}
#endif

// ------------------------------------- issue #37: the tags file, capture, signals, SIGXFSZ

TEST_CASE("Outputs: the tags file a command reads is never its output", "[apps][unix][security]") {
  Dir d;
  const std::string tags = d / "t.json";
  const std::string text = R"({"2": {"name": "Chest", "device_id": "9ABCDEF012345678"}})";
  Put(tags, text);
  fs::create_symlink(fs::absolute(tags), d / "link.json");
  const std::string refused = " is the input file: refusing to overwrite it (--tags " + tags +
                              "); name another output file\n";
  struct Case {
    std::string program, args, output;
  };
  std::vector<Case> cases = {
      {METRO_CHARACTERIZE_EXE, "accuracy " + kSweep + " --tags " + tags + " -o " + tags,
       "-o " + tags},
      {METRO_CHARACTERIZE_EXE, "accuracy " + kSweep + " --tags " + tags + " -o " + d / "link.json",
       "-o " + d / "link.json"},
      {METRO_CHARACTERIZE_EXE,
       "batch " + kChest + " -o " + d / "out --tags " + tags + " --html " + tags, "--html " + tags},
  };
#ifdef METRO_CALIBRATE_EXE
  const std::string cal = kDatasets + "golden/calibration_sensor2.json";
  cases.push_back({METRO_CALIBRATE_EXE,
                   "blob " + cal + " --sensor 2 --tags " + tags + " -o " + tags, "-o " + tags});
  cases.push_back(
      {METRO_CALIBRATE_EXE,
       "blob " + cal + " --sensor 2 --tags " + tags + " -o " + d / "t.bin --hex " + d / "link.json",
       "--hex " + d / "link.json"});
#endif
  for (const Case& c : cases) {
    INFO(c.args);
    Run r = testing::RunProgram(c.program, c.args);
    CHECK(r.exit_code == 2);
    CHECK(r.err == "error: " + c.output + refused);
    CHECK(Get(tags) == text);
  }
#ifdef METRO_CALIBRATE_EXE
  // --all: DIR/tag2.bin a symlink to the tags file; nothing written.
  fs::create_directories(d / "blobs");
  fs::create_symlink(fs::absolute(tags), d / "blobs/tag2.bin");
  Run r = testing::RunProgram(METRO_CALIBRATE_EXE,
                              "blob " + cal + " --all --tags " + tags + " -o " + d / "blobs");
  CHECK(r.exit_code == 2);
  CHECK(r.err == "error: -o (sensor 2) " + d / "blobs/tag2.bin" +
                     " is the input file: refusing to overwrite it (--tags " + tags +
                     "); name another output file (nothing written)\n");
  CHECK_FALSE(fs::exists(d / "blobs/tag2.hex"));
  CHECK(Get(tags) == text);
  CHECK_FALSE(fs::exists(d / "t.bin"));
#endif
  CHECK_FALSE(fs::exists(d / "out/summary.json"));
}

TEST_CASE("Outputs: capture -o follows the output rule before the port is opened",
          "[apps][unix][security][capture]") {
  Dir d;
  const std::string fifo = d / "c.fifo";
  REQUIRE(::mkfifo(fifo.c_str(), 0600) == 0);
  const std::string capture = "capture --duration-s 1 ";
  struct Case {
    std::string args, error;
  };
  std::vector<Case> cases = {
      // Without --force too: the device, not "pass --force".
      {capture + "--port /dev/null -o /dev/null", "-o /dev/null is a character device"},
      // The serial port itself (a character device), with --force.
      {capture + "--port /dev/zero -o /dev/zero --force", "-o /dev/zero is a character device"},
      {capture + "--port /dev/null -o " + fifo + " --force",
       "-o " + fifo + " is a FIFO (named pipe)"},
      // --analyze: the report is checked before anything is captured.
      {capture + "--port metro_no_such_port --analyze --capture " + d / "c.txt -o /dev/full",
       "-o /dev/full is a character device"},
      {capture + "--port metro_no_such_port --analyze --capture " + d / "c.txt -o " + d / "c.txt",
       "-o and --capture name the same file"},
  };
  // A block device, when the machine shows one.
  for (const char* disk : {"/dev/loop0", "/dev/sda", "/dev/vda", "/dev/nvme0n1"}) {
    struct stat st {};
    if (::stat(disk, &st) == 0 && S_ISBLK(st.st_mode)) {
      cases.push_back({capture + "--port /dev/null -o " + disk + " --force",
                       std::string("-o ") + disk + " is a block device"});
      break;
    }
  }
  for (const Case& c : cases) {
    INFO(c.args);
    Run r = Characterize(c.args);
    CHECK(r.exit_code == 2);
    CHECK(r.err.find("error: " + c.error) == 0);
  }
  CHECK(TypeOf(fifo) == S_IFIFO);
  CHECK(TypeOf("/dev/null") == S_IFCHR);
  CHECK_FALSE(fs::exists(d / "c.txt"));
  // The tags file is an input.
  Put(d / "t.json", "{\"1\": \"Forehead\"}");
  Run r = Characterize(capture + "--port metro_no_such_port --tags " + d / "t.json -o " +
                       d / "t.json --force");
  CHECK(r.exit_code == 2);
  CHECK(r.err.find("error: -o " + d / "t.json" + " is the input file") == 0);
  CHECK(Get(d / "t.json") == "{\"1\": \"Forehead\"}");
}

TEST_CASE("Outputs: under a file-size limit a run ends on the ENOSPC path, not SIGXFSZ",
          "[apps][unix][security]") {
  Dir d;
  const std::string json = d / "r.json", html = d / "r.html";
  Put(json, "old json\n");
  Put(html, "old html\n");
  // As "replaced together" above, but without `trap '' XFSZ`: the program ignores it itself.
  Run r = testing::RunProgram("ulimit -f 1000; exec " + std::string(METRO_CHARACTERIZE_EXE),
                              kChest + " --type-a -q -o " + json + " --html " + html);
  CHECK(r.exit_code == 1);
  CHECK(r.err == "error: cannot write '" + html + "': File too large\n");
  CHECK(Get(json) == "old json\n");
  CHECK(Get(html) == "old html\n");
  CHECK(NoTemporaries(d.path));
}

TEST_CASE("Outputs: SIGTERM or SIGINT while an output is written removes its temporary",
          "[apps][unix][security]") {
  Dir d;
  const std::string out = d / "big.csv";
  for (int signal : {SIGTERM, SIGINT}) {
    INFO(signal);
    Put(out, "old session\n");
    // A simulated session of 1e8 rows, streamed to its temporary for minutes.
    const pid_t pid = ::fork();
    REQUIRE(pid >= 0);
    if (pid == 0) {
      // As a program started from a terminal (a test runner may ignore some signals).
      for (int s : {SIGINT, SIGTERM, SIGHUP}) ::signal(s, SIG_DFL);
      ::execl(METRO_CHARACTERIZE_EXE, METRO_CHARACTERIZE_EXE, "simulate", "-q", "-o", out.c_str(),
              "--duration-s", "100000", "--rate-hz", "1000", static_cast<char*>(nullptr));
      ::_exit(127);
    }
    // Bounded wait until the temporary holds 1 MB.
    bool writing = false;
    for (int i = 0; i < 600 && !writing; ++i) {
      for (const auto& e : fs::directory_iterator(d.path)) {
        std::error_code ec;
        writing = writing || (e.path().filename().string().rfind(".metro-", 0) == 0 &&
                              fs::file_size(e.path(), ec) > (1u << 20));
      }
      if (!writing) ::usleep(50 * 1000);
    }
    CHECK(writing);
    REQUIRE(::kill(pid, signal) == 0);
    int status = 0;
    REQUIRE(::waitpid(pid, &status, 0) == pid);
    REQUIRE(WIFSIGNALED(status));
    CHECK(WTERMSIG(status) == signal);
    CHECK(NoTemporaries(d.path));
    CHECK(Get(out) == "old session\n");
  }
}

TEST_CASE("No escaped exception: values that would throw in tags, spec and budget files",
          "[apps][security]") {
  // Each class of input a command reads with a third-party parser: a value of the wrong type
  // or past an int is refused where it is read (file, what was expected), exit 2, never
  // "terminate called after throwing". The registry's class: tests/registry.
  Dir d;
  struct Case {
    std::string program, file, text, args, error;
  };
  const std::string budget_head = R"({"measurand": {"name": "y", "model": "x"}, "inputs": )";
  std::vector<Case> cases = {
      {METRO_CHARACTERIZE_EXE, "b1.json", R"({"measurand": {"name": 5}, "inputs": []})", "budget ",
       "b1.json: measurand: 'name' must be a string"},
      {METRO_CHARACTERIZE_EXE, "b2.json", budget_head + R"([{"name": "x", "value": "1", "u": 1}]})",
       "budget ", "b2.json: input 'x': 'value' must be a number"},
      {METRO_CHARACTERIZE_EXE, "b3.json",
       budget_head + R"([{"name": "x", "type_a": {"values": [1, "a"]}}]})", "budget ",
       "b3.json: input 'x': 'type_a.values' must be an array of numbers"},
      {METRO_CHARACTERIZE_EXE, "b4.json",
       budget_head +
           R"([{"name": "x", "value": 1, "u": 1}], "correlations": [{"a": "x", "b": "no", "r": 0.5}]})",
       "budget ", "b4.json: correlation x/no: input 'no' is not defined"},
      {METRO_CHARACTERIZE_EXE, "t1.json", R"({"99999999999999999999": "x"})",
       "analyze " + kChest + " --tag-registry ",
       "t1.json:1:26: key '99999999999999999999': expected a tag number 1..255"},
      {METRO_CHARACTERIZE_EXE, "t2.json", R"({"2": {"name": 5}})",
       "analyze " + kChest + " --tag-registry ", "t2.json:1:16: tag 2: name: expected a string"},
  };
#ifdef METRO_CALIBRATE_EXE
  cases.push_back(
      {METRO_CALIBRATE_EXE, "s1.json",
       R"({"decision_rule": "simple", "tolerances": [{"constant": "accel.b_x", "unit": "LSB", "lower": "x"}]})",
       "fit " + kChest + " -o " + d / "c.json --spec ",
       "s1.json:1:94: tolerances[0]: 'accel.b_x': 'lower' is 'x': expected a finite number"});
  cases.push_back({METRO_CALIBRATE_EXE, "s2.json", R"({"decision_rule": 7, "tolerances": []})",
                   "fit " + kChest + " -o " + d / "c.json --spec ",
                   "s2.json:1:19: decision_rule 7 is not simple, guarded or risk"});
#endif
  for (const Case& c : cases) {
    INFO(c.args + c.file);
    Put(d / c.file, c.text);
    Run r = testing::RunProgram(c.program, c.args + d / c.file);
    CHECK(r.exit_code == 2);
    CHECK(r.err.rfind("error: " + d / c.error, 0) == 0);
    CHECK(r.err.find("terminate") == std::string::npos);
  }
}

// ----------------------------------------------------------------- 4. batch owns its folder

TEST_CASE("Batch: a second run into a locked folder refuses, naming the holder",
          "[apps][batch][security]") {
  Dir d;
  fs::create_directories(d / "out");
  Result<FileLock> held = LockBatchDirectory(d / "out");
  REQUIRE(held.ok());
  Run r = Characterize("batch " + kChest + " -o " + d / "out");
  CHECK(r.exit_code == 2);
  const std::string prefix = "error: " + d / "out" +
                             ": the output directory is in use by another batch (pid " +
                             std::to_string(::getpid()) + " on ";
  CHECK(r.err.rfind(prefix, 0) == 0);
  CHECK(r.err.find(", since ") != std::string::npos);
  CHECK(r.err.find("): wait for it to finish or give another -o\n") != std::string::npos);
  CHECK_FALSE(fs::exists(d / "out/summary.json"));
  // Released: the next run goes ahead.
  { Result<FileLock> released = std::move(held); }
}

TEST_CASE("Batch: its own outputs are never read as sessions (batch DIR -o DIR twice)",
          "[apps][batch][security]") {
  Dir d;
  fs::copy_file(kChest, d / "chest.csv");
  fs::copy_file(kDatasets + "static_imu_100hz.csv", d / "imu.csv");
  Run first = Characterize("batch " + d.path + " -o " + d.path);
  INFO(first.err);
  REQUIRE(first.exit_code == 0);
  Run second = Characterize("batch " + d.path + " -o " + d.path);
  INFO(second.err);
  CHECK(second.exit_code == 0);
  CHECK(second.err.find("note: skipping " + d / "summary.txt" +
                        ": written by batch into its output directory\n") != std::string::npos);
  const nlohmann::json summary = nlohmann::json::parse(Get(d / "summary.json"));
  CHECK(summary["sessions_total"] == 2);
  CHECK(summary["sessions_failed"] == 0);
  // A pattern that also matches the reports and the summaries.
  Run third = Characterize("batch '" + d.path + "/*' -o " + d.path);
  CHECK(third.exit_code == 0);
  CHECK(nlohmann::json::parse(Get(d / "summary.json"))["sessions_total"] == 2);
}

TEST_CASE("Batch: symlinked inputs are followed, broken ones and FIFOs reported, never skipped",
          "[apps][batch][security]") {
  Dir d;
  fs::create_directories(d / "in");
  fs::copy_file(kChest, d / "chest.csv");
  fs::create_symlink(fs::absolute(d / "chest.csv"), d / "in/linked.csv");
  fs::create_symlink(fs::absolute(d / "missing.csv"), d / "in/dangling.csv");
  REQUIRE(::mkfifo((d / "in/pipe.csv").c_str(), 0600) == 0);
  Run r = Characterize("batch " + d / "in" + " -o " + d / "out");
  INFO(r.err);
  CHECK(r.exit_code == 1);
  CHECK(fs::exists(d / "out/linked.report.json"));
  CHECK(r.err.find("error: " + d / "in/dangling.csv" + ": a symlink to " +
                   fs::absolute(d / "missing.csv").string() +
                   " (No such file or directory): fix or remove the link\n") != std::string::npos);
  CHECK(r.err.find("error: " + d / "in/pipe.csv" +
                   ": is a FIFO, not a session file (batch reads named files)\n") !=
        std::string::npos);
  const nlohmann::json summary = nlohmann::json::parse(Get(d / "out/summary.json"));
  CHECK(summary["sessions_total"] == 3);
  CHECK(summary["sessions_failed"] == 2);
}

// ------------------------------------------------------------------- 5. terminal safety

bool HasRawControl(const std::string& text) {
  for (char c : text) {
    const auto u = static_cast<unsigned char>(c);
    if ((u < 0x20 && c != '\n') || u == 0x7F) return true;
  }
  return false;
}

TEST_CASE("Terminal: control characters in a file name are escaped in errors and notes",
          "[apps][unix][security]") {
  Dir d;
  const std::string name = "evil\x1b]0;owned\x07\nerror: fake.csv";
  const std::string path = d / name;
  Put(path, "t_s,pitch_deg\n0,1\n1,oops\n");
  Run r = Characterize("'" + path + "' --type-a -o -");
  CHECK(r.exit_code == 2);
  CHECK_FALSE(HasRawControl(r.err));
  CHECK(r.err == "error: " + d.path + "/evil\\x1b]0;owned\\x07\\nerror: fake.csv:3:2: " +
                     r.err.substr(r.err.find(":3:2: ") + 6));
  // One line: the newline in the name cannot forge a second "error:" line.
  CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
}

TEST_CASE("Terminal: tag-registry names and CSV header names are escaped",
          "[apps][unix][security]") {
  Dir d;
  const std::string reg = d / "reg.json";
  Put(reg, "{\"2\": \"Chest\\u001b[2J\\u009b31m\"}\n");
  Run r = Characterize(kChest + " --type-a --tag-registry " + reg + " -o " + d / "r.json");
  REQUIRE(r.exit_code == 0);
  CHECK_FALSE(HasRawControl(r.out));
  CHECK(r.out.find("Chest\\x1b[2J\\u009b31m") != std::string::npos);
  CHECK(r.out.find("\xc2\x9b") == std::string::npos);
  // The JSON keeps the name as given (JSON escapes it itself).
  CHECK(nlohmann::json::parse(Get(d / "r.json"))["sensors"][0]["name"] ==
        "Chest\x1b[2J\xc2\x9b"
        "31m");

  const std::string csv = d / "h.csv";
  Put(csv, "t_s,pitch\x1b[31m_deg\n0,1\n1,2\n2,x\n");
  r = Characterize(csv + " --type-a -o -");
  CHECK(r.exit_code == 2);
  INFO(r.err);
  CHECK_FALSE(HasRawControl(r.err));
  CHECK(r.err.find("\\x1b[31m") != std::string::npos);
}

#ifdef METRO_CALIBRATE_EXE
TEST_CASE("Terminal: blob metadata is escaped by calibrate inspect", "[apps][unix][security]") {
  Dir d;
  std::string bin = Get(kDatasets + "golden/tag_sensor2.bin");
  const size_t at = bin.find(std::string("tag2\0", 5));
  REQUIRE(at != std::string::npos);
  bin.replace(at, 7, std::string("\x1b[2J\x1b]0", 7));
  const uint32_t crc = blob::Crc32(reinterpret_cast<const uint8_t*>(bin.data()), bin.size() - 4);
  for (int i = 0; i < 4; ++i) bin[bin.size() - 4 + i] = static_cast<char>((crc >> (8 * i)) & 0xFF);
  const std::string path = d / "evil.bin";
  Put(path, bin);
  Run r = testing::RunProgram(METRO_CALIBRATE_EXE, "inspect " + path);
  INFO(r.out);
  CHECK_FALSE(HasRawControl(r.out));
  CHECK_FALSE(HasRawControl(r.err));
  CHECK(r.out.find("\\x1b[2J\\x1b]0") != std::string::npos);

  // Bytes that are not UTF-8 in the label: JSON cannot hold them, and nlohmann's dump threw
  // type_error 316 (std::terminate). Each bad byte is written as U+FFFD.
  bin.replace(at, 7, std::string("t\xe9g\xff\0\0\0", 7));
  const uint32_t crc2 = blob::Crc32(reinterpret_cast<const uint8_t*>(bin.data()), bin.size() - 4);
  for (int i = 0; i < 4; ++i) bin[bin.size() - 4 + i] = static_cast<char>((crc2 >> (8 * i)) & 0xFF);
  Put(path, bin);
  r = testing::RunProgram(METRO_CALIBRATE_EXE, "inspect --json " + path);
  INFO(r.err);
  CHECK(r.exit_code == 0);
  CHECK(r.out.find("t\xef\xbf\xbdg\xef\xbf\xbd") != std::string::npos);
  CHECK(nlohmann::json::parse(r.out)["ok"] == true);
}
#endif

#ifdef METRO_CALIBRATE_EXE
TEST_CASE("Terminal: calibrate push and blob escape port and file names",
          "[apps][unix][security]") {
  Dir d;
  const std::string cal = kDatasets + "golden/calibration_sensor2.json";
  // A port name with an OSC title sequence and a newline that forges a second line.
  const std::string port = d / "tty\x1b]0;owned\x07\nOK: pushed";
  Run r = testing::RunProgram(METRO_CALIBRATE_EXE,
                              "push " + cal + " --sensor 2 --any-device --port '" + port + "'");
  INFO(r.err);
  CHECK(r.exit_code != 0);
  CHECK_FALSE(HasRawControl(r.err));
  CHECK(r.err.find("tty\\x1b]0;owned\\x07\\nOK: pushed") != std::string::npos);
  // A calibration file name in calibrate blob's messages.
  const std::string evil_cal = d / "c\x1b[2J.json";
  Put(evil_cal, Get(cal));
  r = testing::RunProgram(
      METRO_CALIBRATE_EXE,
      "blob '" + evil_cal + "' --sensor 7 --device-id 9abcdef012345678 -o " + d / "b.bin");
  INFO(r.err);
  CHECK(r.exit_code == 2);
  CHECK_FALSE(HasRawControl(r.err));
  CHECK(r.err.find("c\\x1b[2J.json") != std::string::npos);
}
#endif

TEST_CASE("JSON outputs: a session named in Latin-1 is analysed, not a crash",
          "[apps][unix][security]") {
  // A file name (or a CSV header) is bytes; a report names it in JSON, which is UTF-8. The
  // name \xe9 made nlohmann's dump throw type_error 316 and characterize abort (SIGABRT).
  Dir d;
  const std::string path = d / "l\xe9t.csv";
  Put(path, "t_s,gx_dps\n0,1\n0.01,1.1\n0.02,1.2\n0.03,1.0\n");
  Run r = Characterize("'" + path + "' --type-a -o " + d / "r.json");
  INFO(r.err);
  REQUIRE(r.exit_code == 0);
  const nlohmann::json report = nlohmann::json::parse(Get(d / "r.json"));
  CHECK(report["input"]["path"].get<std::string>().find("l\xef\xbf\xbdt.csv") != std::string::npos);
  // The batch summary and per-session reports too.
  r = Characterize("batch " + d.path + " -o " + d / "out");
  INFO(r.err);
  CHECK(r.exit_code == 0);
  CHECK(nlohmann::json::parse(Get(d / "out/summary.json"))["sessions_total"] == 1);
}

}  // namespace
}  // namespace metro
