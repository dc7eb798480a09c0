// `characterize capture` end to end against the simulated central receiver
// (metro_sim_receiver) on a pseudo-terminal: every whole line the receiver sent is in the
// file, in order, unchanged; the cut first line and non-receiver lines are kept out of the
// body and counted; per-tag counts equal what was sent; unplug and replug; clean ends on
// SIGINT, SIGTERM and --duration-s; bad ports and outputs exit 2. Every wait is bounded.
#if defined(METRO_SIM_RECEIVER_EXE) && defined(METRO_CHARACTERIZE_EXE)

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "metro/io/session_io.hpp"
#include "metro/serial/serial_port.hpp"
#include "support/run_program.hpp"

extern char** environ;

namespace metro::capture {
namespace {

using Clock = std::chrono::steady_clock;

std::string Unique(const std::string& what) {
  static int counter = 0;
  return "metro_cap_" + what + "_" + std::to_string(::getpid()) + "_" + std::to_string(++counter);
}

std::string Slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::vector<std::string> Lines(const std::string& text) {
  std::vector<std::string> out;
  size_t pos = 0;
  while (pos < text.size()) {
    size_t nl = text.find('\n', pos);
    if (nl == std::string::npos) nl = text.size() - 1;
    out.push_back(text.substr(pos, nl + 1 - pos));
    pos = nl + 1;
  }
  return out;
}

std::vector<std::string> Body(const std::string& text) {
  std::vector<std::string> out;
  for (std::string& l : Lines(text)) {
    if (l[0] != '#') out.push_back(std::move(l));
  }
  return out;
}

// A spawned program; stdout to a pipe (readable line by line) or a file, stderr to a file.
// Killed (SIGKILL) and reaped on destruction if still running.
class Proc {
 public:
  Proc(std::vector<std::string> args, bool stdout_pipe) {
    err_path_ = Unique("stderr") + ".txt";
    out_path_ = Unique("stdout") + ".txt";
    std::vector<char*> argv;
    for (std::string& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    int fds[2] = {-1, -1};
    if (stdout_pipe) {
      REQUIRE(::pipe(fds) == 0);
      posix_spawn_file_actions_adddup2(&fa, fds[1], STDOUT_FILENO);
      posix_spawn_file_actions_addclose(&fa, fds[0]);
      posix_spawn_file_actions_addclose(&fa, fds[1]);
    } else {
      posix_spawn_file_actions_addopen(&fa, STDOUT_FILENO, out_path_.c_str(),
                                       O_WRONLY | O_CREAT | O_TRUNC, 0644);
    }
    posix_spawn_file_actions_addopen(&fa, STDERR_FILENO, err_path_.c_str(),
                                     O_WRONLY | O_CREAT | O_TRUNC, 0644);
    const int rc = ::posix_spawn(&pid_, argv[0], &fa, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&fa);
    if (stdout_pipe) {
      ::close(fds[1]);
      out_fd_ = fds[0];
    }
    REQUIRE(rc == 0);
  }
  ~Proc() {
    if (pid_ > 0) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, nullptr, 0);
    }
    if (out_fd_ >= 0) ::close(out_fd_);
    std::remove(err_path_.c_str());
    std::remove(out_path_.c_str());
  }
  // The next stdout line (without LF), or "" after timeout_s or at the end.
  std::string ReadLine(double timeout_s) {
    const auto deadline = Clock::now() + std::chrono::duration<double>(timeout_s);
    std::string line;
    while (Clock::now() < deadline) {
      pollfd p{out_fd_, POLLIN, 0};
      if (::poll(&p, 1, 50) <= 0) continue;
      char c;
      if (::read(out_fd_, &c, 1) != 1) break;
      if (c == '\n') return line;
      line += c;
    }
    return "";
  }
  // Sends `sig` (0: none) and waits up to timeout_s; then SIGKILL. Returns the exit code
  // (-1 when killed by a signal).
  int Stop(int sig, double timeout_s = 30.0) {
    if (pid_ <= 0) return exit_code_;
    if (sig != 0) ::kill(pid_, sig);
    const auto deadline = Clock::now() + std::chrono::duration<double>(timeout_s);
    int status = 0;
    while (::waitpid(pid_, &status, WNOHANG) == 0) {
      if (Clock::now() > deadline) {
        ::kill(pid_, SIGKILL);
        ::waitpid(pid_, &status, 0);
        break;
      }
      ::poll(nullptr, 0, 20);
    }
    pid_ = -1;
    exit_code_ = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    return exit_code_;
  }
  std::string err() const { return Slurp(err_path_); }
  std::string out() const { return Slurp(out_path_); }

 private:
  pid_t pid_ = -1;
  int out_fd_ = -1;
  int exit_code_ = -1;
  std::string err_path_, out_path_;
};

// The simulated receiver; ready once it printed its pty.
struct Receiver {
  std::string link = Unique("port");
  std::string record = Unique("record") + ".txt";
  std::unique_ptr<Proc> proc;
  explicit Receiver(std::vector<std::string> options) {
    std::vector<std::string> args = {METRO_SIM_RECEIVER_EXE, "--port-link", link, "--record",
                                     record};
    args.insert(args.end(), options.begin(), options.end());
    proc = std::make_unique<Proc>(args, true);
    REQUIRE(proc->ReadLine(30.0).rfind("pty: /dev/pts/", 0) == 0);
  }
  ~Receiver() {
    proc.reset();
    std::remove(record.c_str());
    std::remove(link.c_str());
  }
  // Waits for the last frame ("done"), bounded.
  void WaitDone() { REQUIRE(proc->ReadLine(120.0) == "done"); }
};

std::unique_ptr<Proc> StartCapture(const std::vector<std::string>& options) {
  std::vector<std::string> args = {METRO_CHARACTERIZE_EXE, "capture"};
  args.insert(args.end(), options.begin(), options.end());
  return std::make_unique<Proc>(args, false);
}

// Waits (bounded) until `path` holds at least `n` body lines.
void WaitForBody(const std::string& path, size_t n) {
  const auto deadline = Clock::now() + std::chrono::seconds(60);
  while (Body(Slurp(path)).size() < n && Clock::now() < deadline) ::poll(nullptr, 0, 50);
  REQUIRE(Body(Slurp(path)).size() >= n);
}

struct Counts {
  int64_t frames = 0, fresh = 0, stale = 0, never = 0;
};

// Per-tag counts read from receiver lines by their first four characters.
std::map<int, Counts> CountsOf(const std::vector<std::string>& lines) {
  std::map<int, Counts> out;
  for (const std::string& l : lines) {
    Counts& c = out[std::stoi(l.substr(0, 2), nullptr, 16)];
    ++c.frames;
    const std::string flag = l.substr(2, 2);
    if (flag == "01") ++c.fresh;
    if (flag == "00") ++c.stale;
    if (flag == "ff") ++c.never;
  }
  return out;
}

// The capture's own per-tag counts, from its closing `# sensor N: ...` lines.
std::map<int, Counts> FooterCounts(const std::string& text) {
  std::map<int, Counts> out;
  for (const std::string& l : Lines(text)) {
    int s = 0;
    long long f = 0, fr = 0, st = 0, nv = 0;
    if (std::sscanf(l.c_str(), "# sensor %d: frames %lld, fresh %lld, stale %lld, never %lld", &s,
                    &f, &fr, &st, &nv) == 5) {
      out[s] = Counts{f, fr, st, nv};
    }
  }
  return out;
}

bool WholeReceiverLine(const std::string& l) {
  if (l.size() != 55 || l.back() != '\n') return false;
  for (size_t i = 0; i < 54; ++i) {
    if (!std::isxdigit(static_cast<unsigned char>(l[i]))) return false;
  }
  return true;
}

}  // namespace

TEST_CASE("pty capture: every whole line sent is in the file in order with per-tag counts",
          "[capture][pty]") {
  Receiver rx({"--tags", "5", "--never", "4", "--join", "2:1.0", "--packet-loss", "0.1",
               "--frame-period-s", "0.02", "--duration-s", "3", "--seed", "7", "--cut-first-line",
               "20", "--banner", "nRF52840 central ready"});
  const std::string cap = Unique("capture") + ".txt";
  auto capture = StartCapture({"--port", rx.link, "-o", cap});
  rx.WaitDone();
  const std::vector<std::string> sent = Lines(Slurp(rx.record));
  // 3 s / 0.02 s = 150 frames (floor of the simulator's steps) x 5 tags.
  REQUIRE(sent.size() == 750);
  WaitForBody(cap, sent.size());
  CHECK(capture->Stop(SIGTERM) == 0);
  const std::string text = Slurp(cap);
  const std::vector<std::string> body = Body(text);
  CHECK(body == sent);
  for (const std::string& l : body) REQUIRE(WholeReceiverLine(l));
  CHECK(text.rfind("# metro capture of the central receiver", 0) == 0);
  CHECK(text.find("# port: " + rx.link + "\n# baud: 230400\n# start_utc: 20") != std::string::npos);
  CHECK(text.find("cut_first_lines: 1, other_lines: 1,") != std::string::npos);
  CHECK(text.find("# not a receiver line (receiver line has 22 characters: expected 54 hex "
                  "characters (sensor, NewData flag, 25 payload bytes)): nRF52840 central "
                  "ready\n") != std::string::npos);
  const std::map<int, Counts> want = CountsOf(sent);
  const std::map<int, Counts> got = FooterCounts(text);
  REQUIRE(got.size() == 5);
  for (const auto& [sensor, c] : want) {
    INFO("sensor " << sensor);
    CHECK(got.at(sensor).frames == c.frames);
    CHECK(got.at(sensor).fresh == c.fresh);
    CHECK(got.at(sensor).stale == c.stale);
    CHECK(got.at(sensor).never == c.never);
  }
  // What the receiver was told to do, counted in the lines it sent.
  CHECK(want.at(4).never == 150);
  CHECK(want.at(2).never >= 50);  // ff until t = 1.0 s = frame 50
  CHECK(want.at(1).stale > 0);    // 10 % loss over 150 frames
  // The capture loads as a receiver capture with the same counts.
  LoadOptions lo;
  lo.frame_period_s = 0.02;
  Result<Session> session = LoadSession(cap, lo);
  REQUIRE(session.ok());
  CHECK(session.value().tags.size() == 5);
  CHECK(session.value().tags[0].counts.fresh == want.at(1).fresh);
  // The final table: the never-connected tag first.
  const std::string table = capture->out();
  CHECK(table.find("never delivered a packet") != std::string::npos);
  CHECK(table.find("     4 ") < table.find("     1 "));
  std::remove(cap.c_str());
}

TEST_CASE("pty capture: an unplugged receiver is reopened when it returns", "[capture][pty]") {
  Receiver rx({"--tags", "3", "--frame-period-s", "0.02", "--duration-s", "2", "--unplug-at-s",
               "0.6", "--replug-after-s", "0.5", "--cut-first-line", "30", "--seed", "3"});
  const std::string cap = Unique("capture") + ".txt";
  auto capture = StartCapture({"--port", rx.link, "-o", cap});
  rx.WaitDone();
  const std::vector<std::string> sent = Lines(Slurp(rx.record));
  REQUIRE(sent.size() == 300);
  WaitForBody(cap, sent.size());
  CHECK(capture->Stop(SIGTERM) == 0);
  const std::string text = Slurp(cap);
  CHECK(Body(text) == sent);
  CHECK(text.find("# port lost at ") != std::string::npos);
  CHECK(text.find("# port reopened at ") != std::string::npos);
  CHECK(text.find("cut_first_lines: 2, other_lines: 0,") != std::string::npos);
  CHECK(text.find("port_lost: 1, reopened: 1") != std::string::npos);
  const std::string err = capture->err();
  CHECK(err.find(rx.link + ": the port disappeared") != std::string::npos);
  CHECK(err.find(rx.link + ": the port is back") != std::string::npos);
  std::remove(cap.c_str());
}

TEST_CASE("pty capture: with --duration-s an unplug ends the capture with exit 1",
          "[capture][pty]") {
  Receiver rx({"--tags", "2", "--frame-period-s", "0.02", "--unplug-at-s", "0.4",
               "--replug-after-s", "30", "--seed", "4"});
  const std::string cap = Unique("capture") + ".txt";
  auto capture = StartCapture({"--port", rx.link, "-o", cap, "--duration-s", "60"});
  // No reconnect by default with a duration: the capture ends on its own when the port goes.
  CHECK(capture->Stop(0, 60.0) == 1);
  const std::string text = Slurp(cap);
  // 0.4 s / 0.02 s = 20 frames of 2 tags were sent before the unplug, all of them kept.
  CHECK(Body(text) == Lines(Slurp(rx.record)));
  CHECK(Body(text).size() == 40);
  CHECK(text.find("# port lost at ") != std::string::npos);
  CHECK(text.find("# end_utc: ") != std::string::npos);
  CHECK(capture->err().find("error: " + rx.link + ": the port disappeared after ") !=
        std::string::npos);
  std::remove(cap.c_str());
}

TEST_CASE("pty capture: SIGINT and --duration-s finish the file cleanly", "[capture][pty]") {
  Receiver rx({"--tags", "2", "--frame-period-s", "0.02", "--seed", "5"});
  const std::string cap = Unique("capture") + ".txt";
  {
    auto capture = StartCapture({"--port", rx.link, "-o", cap});
    WaitForBody(cap, 40);
    CHECK(capture->Stop(SIGINT) == 0);
  }
  std::string text = Slurp(cap);
  CHECK(text.back() == '\n');
  CHECK(text.find("# end_utc: ") != std::string::npos);
  std::vector<std::string> first = Body(text);
  CHECK(first.size() >= 40);
  for (const std::string& l : first) REQUIRE(WholeReceiverLine(l));
  // The same file again: refused without --force, unchanged.
  const testing::ProgramRun again = testing::RunProgram(
      METRO_CHARACTERIZE_EXE, "capture --port " + rx.link + " -o " + cap + " --duration-s 1");
  CHECK(again.exit_code == 2);
  CHECK(again.err.find(cap + ": exists: a capture is never replaced; pass --force") !=
        std::string::npos);
  CHECK(Slurp(cap) == text);
  // --duration-s ends by itself, exit 0, whole lines only.
  const testing::ProgramRun timed =
      testing::RunProgram(METRO_CHARACTERIZE_EXE,
                          "capture --port " + rx.link + " -o " + cap + " --duration-s 1 --force");
  CHECK(timed.exit_code == 0);
  CHECK(timed.err.find("(--force: replacing the existing file)") != std::string::npos);
  text = Slurp(cap);
  CHECK(text.find("# end_utc: ") != std::string::npos);
  for (const std::string& l : Body(text)) REQUIRE(WholeReceiverLine(l));
  std::remove(cap.c_str());
}

TEST_CASE("pty capture: bad ports exit 2 naming the port", "[capture][pty]") {
  const std::string cap = Unique("capture") + ".txt";
  testing::ProgramRun r = testing::RunProgram(
      METRO_CHARACTERIZE_EXE, "capture --port metro_no_such_tty --duration-s 5 -o " + cap);
  CHECK(r.exit_code == 2);
  CHECK(r.err.find("error: metro_no_such_tty: cannot open: No such file or directory") !=
        std::string::npos);
  std::FILE* f = std::fopen(cap.c_str(), "r");
  CHECK(f == nullptr);
  if (f != nullptr) std::fclose(f);
  const std::string plain = Unique("plain") + ".txt";
  { std::ofstream(plain) << "x"; }
  r = testing::RunProgram(METRO_CHARACTERIZE_EXE,
                          "capture --port " + plain + " -o " + cap + " --duration-s 5");
  CHECK(r.exit_code == 2);
  CHECK(r.err.find("error: " + plain + ": not a serial port (tcgetattr)") != std::string::npos);
  std::remove(plain.c_str());
  {
    Receiver rx({"--tags", "1", "--frame-period-s", "0.05"});
    Result<std::unique_ptr<serial::SerialPort>> held = serial::SerialPort::Open(rx.link);
    REQUIRE(held.ok());
    r = testing::RunProgram(METRO_CHARACTERIZE_EXE,
                            "capture --port " + rx.link + " -o " + cap + " --duration-s 5");
    CHECK(r.exit_code == 2);
    CHECK(r.err.find("error: " + rx.link + ": in use by another program (flock)") !=
          std::string::npos);
  }
  r = testing::RunProgram(METRO_CHARACTERIZE_EXE, "capture --port x --analyze -o r.json");
  CHECK(r.exit_code == 2);
  CHECK(r.err.find("--analyze: name the capture with --capture FILE") != std::string::npos);
  r = testing::RunProgram(METRO_CHARACTERIZE_EXE, "capture -o " + cap);
  CHECK(r.exit_code == 2);
  CHECK(r.err.find("--port is required") != std::string::npos);
  f = std::fopen(cap.c_str(), "r");
  CHECK(f == nullptr);
  if (f != nullptr) std::fclose(f);
}

TEST_CASE("pty capture: --analyze writes the Type A report of the capture", "[capture][pty]") {
  Receiver rx({"--tags", "2", "--frame-period-s", "0.02", "--duration-s", "4", "--seed", "9",
               "--packet-loss", "0"});
  const std::string cap = Unique("capture") + ".txt";
  const std::string report = Unique("report") + ".json";
  auto capture = StartCapture({"--port", rx.link, "--analyze", "--capture", cap, "-o", report});
  rx.WaitDone();
  WaitForBody(cap, 400);
  CHECK(capture->Stop(SIGTERM) == 0);
  const nlohmann::json j = nlohmann::json::parse(Slurp(report));
  REQUIRE(j["sensors"].size() == 2);
  // 4 s / 0.02 s = 200 frames, no loss: 200 fresh observations per tag.
  CHECK(j["sensors"][0]["sensor"] == 1);
  CHECK(j["sensors"][0]["fresh"] == 200);
  CHECK(j["sensors"][1]["frames"] == 200);
  std::remove(cap.c_str());
  std::remove(report.c_str());
}

}  // namespace metro::capture

#endif
