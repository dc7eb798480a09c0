// `calibrate station` end to end (issue #44): the simulated tag (metro_sim_raw_tag) streams
// raw counts into a growing file and onto a pseudo-terminal that disappears mid-session; the
// station guides, stops with every target met, and fit, certificate and blob follow; a stream
// that is not raw counts is refused at its first bad line.
#include <sys/types.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>

#include "support/run_program.hpp"
#include "support/sanitizer.hpp"

namespace fs = std::filesystem;
using metro::testing::RunProgram;

namespace {

const std::string kCalibrate = METRO_CALIBRATE_EXE;
// Under the sanitizers the station's live fits run several times slower: its timeouts and the
// test's waits are stretched, never its checks.
constexpr int kSlowdown = METRO_UNDER_SANITIZER ? 4 : 1;
const std::string kSimRawTag = METRO_SIM_RAW_TAG_EXE;

std::string Slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// A fresh directory with the tags file of sensor 2.
fs::path Workdir(const std::string& name) {
  const fs::path dir =
      fs::temp_directory_path() / ("metro_station_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream(dir / "tags.json")
      << R"({"2": {"name": "Chest", "device_id": "12345678 9ABCDEF0", "profile": "mpu6050"}})";
  return dir;
}

int CountLines(const std::string& text, const std::string& prefix) {
  int n = 0;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) n += line.rfind(prefix, 0) == 0 ? 1 : 0;
  return n;
}

}  // namespace

TEST_CASE("calibrate station follows a growing file to every target met", "[station][cli]") {
  const fs::path dir = Workdir("file");
  const std::string stream = (dir / "stream.txt").string();
  // The simulated operator's demo script, written as fast as possible (a file being written).
  const auto sim = RunProgram(kSimRawTag, "-o " + stream + " --demo --speed 0 --seed 3");
  REQUIRE(sim.exit_code == 0);
  const auto r = RunProgram(kCalibrate,
                            "station --port " + stream + " --format raw --rate-hz 100 --tags " +
                                (dir / "tags.json").string() + " --sensor 2 -o " + dir.string() +
                                " --idle-timeout-s 1 --registry " + (dir / "line.sqlite").string());
  INFO(r.out << r.err);
  CHECK(r.exit_code == 0);
  CHECK(CountLines(r.out, "stopped") == 1);
  CHECK_THAT(r.out, Catch::Contains("targets=met"));
  // The demo's faults: the hold cut short and the knock are rejected, the re-seat is too close.
  CHECK(CountLines(r.out, "pose_rejected") >= 2);
  CHECK(CountLines(r.out, "too_close") >= 1);
  CHECK(CountLines(r.out, "pose_accepted") >= 10);
  for (const char* f : {"calibration.json", "certificate.html", "tag.bin", "tag.hex",
                        "station_session.csv", "station_segments.csv"}) {
    CHECK(fs::exists(dir / f));
  }
  CHECK_THAT(r.err, Catch::Contains("station: fit -> "));
  CHECK_THAT(r.err, Catch::Contains("station: blob -> "));
  // calibration.json names the tag from the tags file and the record the station wrote.
  const std::string cal = Slurp(dir / "calibration.json");
  CHECK_THAT(cal, Catch::Contains("station_session.csv"));
  CHECK_THAT(cal, Catch::Contains("\"sensor\": 2"));
  // The same events as JSON.
  const auto j =
      RunProgram(kCalibrate, "station --port " + stream + " --format raw --rate-hz 100 --tags " +
                                 (dir / "tags.json").string() + " --sensor 2 -o " + dir.string() +
                                 " --idle-timeout-s 1 --json-events");
  CHECK(j.exit_code == 0);
  CHECK(CountLines(j.out, "{\"event\":\"pose_accepted\"") == CountLines(r.out, "pose_accepted"));
  fs::remove_all(dir);
}

TEST_CASE("calibrate station refuses a stream that is not raw counts at its first bad line",
          "[station][cli]") {
  const fs::path dir = Workdir("bad");
  const std::string stream = (dir / "stream.txt").string();
  std::ofstream(stream) << "# a comment\n-412,83,16390,-12,40,7\n-412,83,16x90,-12,40,7\n";
  const auto r =
      RunProgram(kCalibrate, "station --port " + stream + " --format raw --rate-hz 100 --tags " +
                                 (dir / "tags.json").string() + " --sensor 2 -o " + dir.string() +
                                 " --idle-timeout-s 1");
  CHECK(r.exit_code == 2);
  CHECK_THAT(r.err, Catch::Contains(stream + ":3:11: field 3 (az) \"16x90\" is not an integer"));
  CHECK_THAT(r.err, Catch::Contains("expected ax,ay,az,gx,gy,gz[,t_ms]"));
  CHECK_FALSE(fs::exists(dir / "calibration.json"));
  const auto f =
      RunProgram(kCalibrate, "station --port " + stream + " --format csv --rate-hz 100 --tags " +
                                 (dir / "tags.json").string() + " --sensor 2");
  CHECK(f.exit_code == 2);
  CHECK_THAT(f.err, Catch::Contains("the station reads the raw line format only"));
  fs::remove_all(dir);
}

// The port disappears mid-session (the simulator's `unplug`): the station keeps the poses taken,
// resumes in a new record when the port returns, and the fit takes both records.
TEST_CASE("calibrate station over a pseudo-terminal that disappears and returns",
          "[station][cli]") {
  const fs::path dir = Workdir("pty");
  const std::string link = (dir / "tag.pty").string();
  {
    std::ofstream script(dir / "script.txt");
    script << "hold 2.5\nmove X up 1.5\nhold 2.5\nmove Y up 1.5\nhold 2.5\nmove Z down 1.5\n"
              "hold 2.5\nmove X down 1\nunplug 1\nhold 3\nmove Y down 1.5\nhold 2.5\n";
    for (const char* corner :
         {"+X+Y+Z", "-X-Y+Z", "+X-Y-Z", "-X+Y-Z", "+X-Y+Z", "-X+Y+Z", "+X+Y-Z", "-X-Y-Z"}) {
      script << "move corner " << corner << " up 1.5\nhold 2.5\n";
    }
  }
  const std::string sim_out = (dir / "sim.txt").string();
  const std::string start = kSimRawTag + " --port-link " + link + " --script " +
                            (dir / "script.txt").string() + " --speed 10 --seed 5 >" + sim_out +
                            " 2>&1 & echo $!";
  FILE* p = ::popen(start.c_str(), "r");
  REQUIRE(p != nullptr);
  int pid = 0;
  REQUIRE(std::fscanf(p, "%d", &pid) == 1);
  ::pclose(p);
  for (int i = 0; i < 100 && !fs::exists(link); ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  REQUIRE(fs::exists(link));
  const auto r =
      RunProgram(kCalibrate, "station --port " + link + " --format raw --rate-hz 100 --tags " +
                                 (dir / "tags.json").string() + " --sensor 2 -o " + dir.string() +
                                 " --idle-timeout-s " + std::to_string(5 * kSlowdown) +
                                 " --reconnect-s " + std::to_string(10 * kSlowdown));
  ::kill(pid, SIGTERM);
  INFO(r.out << r.err << Slurp(sim_out));
  CHECK(r.exit_code == 0);
  CHECK(CountLines(r.out, "gap") == 1);
  CHECK_THAT(r.out, Catch::Contains("poses taken are kept"));
  CHECK_THAT(r.out, Catch::Contains("targets=met"));
  CHECK(fs::exists(dir / "station_session_1.csv"));
  CHECK(fs::exists(dir / "station_session_2.csv"));
  CHECK(fs::exists(dir / "tag.bin"));
  // The simulator removes its link as it stops: wait for that before cleaning up.
  for (int i = 0; i < 100 && fs::is_symlink(link); ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  std::error_code ec;
  fs::remove_all(dir, ec);
}

// The terminal view (stdout a terminal): driven in tmux, its screen read with capture-pane.
TEST_CASE("calibrate station draws its view on a terminal (tmux)", "[station][cli]") {
  if (std::system("command -v tmux >/dev/null 2>&1") != 0) {
    WARN("tmux not installed: the terminal view is not checked");
    return;
  }
  const fs::path dir = Workdir("tmux");
  const std::string stream = (dir / "stream.txt").string();
  REQUIRE(RunProgram(kSimRawTag, "-o " + stream + " --demo --speed 0 --seed 4").exit_code == 0);
  const std::string server = "-L metro_station_" + std::to_string(::getpid());
  const std::string station = kCalibrate + " station --port " + stream +
                              " --format raw --rate-hz 100 --tags " + (dir / "tags.json").string() +
                              " --sensor 2 -o " + dir.string() +
                              " --idle-timeout-s 1 2>/dev/null; echo EXIT=$?; sleep 60";
  REQUIRE(std::system(
              ("tmux " + server + " new-session -d -s v -x 120 -y 50 '" + station + "'").c_str()) ==
          0);
  std::string screen;
  for (int i = 0; i < 300 * kSlowdown && screen.find("EXIT=") == std::string::npos; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    screen = RunProgram("tmux", server + " capture-pane -p -t v").out;
  }
  const std::string colored = RunProgram("tmux", server + " capture-pane -p -e -t v").out;
  std::system(("tmux " + server + " kill-server").c_str());
  INFO(screen);
  CHECK_THAT(screen, Catch::Contains("metro calibration station: six-face protocol, sensor 2"));
  CHECK_THAT(screen, Catch::Contains("STOPPED: every target met"));
  CHECK_THAT(screen, Catch::Contains("Coverage: "));
  CHECK_THAT(screen, Catch::Contains("u (k = 1) against target:"));
  CHECK_THAT(screen, Catch::Contains("accel.a_yz"));
  CHECK_THAT(screen, Catch::Contains("EXIT=0"));
  CHECK_THAT(colored, Catch::Contains("\x1b[32m"));  // Met targets in green.
  std::error_code ec;
  fs::remove_all(dir, ec);
}
