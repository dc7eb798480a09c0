// metro_sim_receiver: a simulated nRF52840 central receiver on a pseudo-terminal, for tests,
// benchmarks and users without hardware (docs/capture.md).
//
//   metro_sim_receiver --port-link PATH [--tags N] [--never S]... [--join S:T_S]...
//                      [--packet-loss P] [--frame-period-s P] [--duration-s S] [--seed N]
//                      [--cut-first-line CHARS] [--banner TEXT] [--unplug-at-s T]
//                      [--replug-after-s D] [--record FILE]
//
// Writes the thesis format (docs/formats.md, "Receiver capture") from the static simulator's
// model (sim/static_session.hpp) at the receiver's frame period: one line per tag per frame.
//   --tags N             tags 1..N (default 15); --never S: tag S never connects (ff rows)
//   --join S:T_S         tag S joins late: ff rows until t = T_S s
//   --packet-loss P      a frame has no new packet with probability P (stale row; default 0.02)
//   --cut-first-line C   the stream starts with the last C characters of a line and its LF
//                        (the port opened mid-line), after every (re)connection
//   --banner TEXT        a line that is not a receiver line, before the first frame
//   --unplug-at-s T      at frame time T the port disappears (the link PATH is removed and the
//                        pty closed) for --replug-after-s D seconds (default 1), then a new pty
//                        appears at PATH and the stream goes on with the next frame
//   --duration-s S       frames of S seconds (default: until stopped), then idle until stopped
//   --record FILE        every whole line written, in order (what a capture must contain)
// Streaming starts when a program opens the port (the receiver's output before that is lost,
// as on a real serial port): the simulator waits for the open's flush (pty packet mode).
// Prints "pty: /dev/pts/N" on stdout when PATH is ready, "done" after the last frame.
// Exit status: 0 after SIGTERM/SIGINT, 2 for bad arguments, 1 for a system error.
//
// main runs these stages, in this order: ParseArgs (the command line), SimOptionsOf (the
// simulator's options), InstallSignals, the Streamer's pty and record file, StreamFrames
// (the simulator's text, frame by frame, to the pty), then idles until stopped.
#include <fcntl.h>
#include <poll.h>
#include <pty.h>
#include <sys/ioctl.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "metro/io/receiver.hpp"
#include "metro/sim/limits.hpp"
#include "metro/sim/static_session.hpp"
#include "sim_pty.hpp"

namespace {

using metro::apps::sim::g_stop;
using metro::apps::sim::InstallSignals;
using metro::apps::sim::Now;
using metro::apps::sim::Pty;
using metro::apps::sim::SleepUntil;

struct Options {
  std::string link;
  int tags = 15;
  std::vector<int> never;
  std::map<int, double> join_s;
  double packet_loss = 0.02;
  double frame_period_s = metro::kReceiverFramePeriodS;
  double duration_s = 0.0;
  uint64_t seed = 1;
  int cut_chars = 0;
  std::string banner;
  double unplug_at_s = -1.0;
  double replug_after_s = 1.0;
  std::string record;
};

int Usage(const std::string& why) {
  std::fprintf(stderr, "metro_sim_receiver: %s\n", why.c_str());
  return 2;
}

bool ParseDouble(const char* text, double* out) {
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(text, &end);
  if (errno != 0 || end == text || *end != '\0' || !std::isfinite(v)) return false;
  *out = v;
  return true;
}

bool ParseInt(const char* text, int lo, int hi, int* out) {
  double v = 0;
  if (!ParseDouble(text, &v) || v != std::floor(v) || v < lo || v > hi) return false;
  *out = static_cast<int>(v);
  return true;
}

struct Streamer {
  Options opt;
  Pty pty;
  std::FILE* record = nullptr;
  double next_frame_time = 0.0;  // monotonic clock
  int64_t frame = 0;
  double max_lag_s = 0.0;  // Behind the frame schedule (a reader that does not keep up).
  bool unplugged_once = false;
  std::map<int, bool> joined_fresh;  // a late joiner sent a fresh packet since joining
  std::string first_line_tail;       // The line whose tail a (re)connection starts with.

  bool Connect(bool first) {
    if (!first && !pty.Open(opt.link)) return false;
    if (!pty.WaitForReader()) return false;
    if (opt.cut_chars > 0 && !first_line_tail.empty()) {
      const size_t c = std::min<size_t>(static_cast<size_t>(opt.cut_chars), first_line_tail.size());
      if (!pty.Write(std::string_view(first_line_tail).substr(first_line_tail.size() - c)) ||
          !pty.Write("\n")) {
        return false;
      }
    }
    if (first && !opt.banner.empty() && !pty.Write(opt.banner + "\r\n")) return false;
    next_frame_time = Now();
    return true;
  }

  // One frame's lines (each with its LF), late joiners rewritten to ff rows.
  bool SendFrame(std::vector<std::string_view>& lines) {
    const double t_s = static_cast<double>(frame) * opt.frame_period_s;
    if (!unplugged_once && opt.unplug_at_s >= 0.0 && t_s >= opt.unplug_at_s) {
      unplugged_once = true;
      // Between two frames, once the reader has what was sent (bytes in flight when a real
      // cable is pulled are lost; here every line sent must be in the capture).
      pty.WaitUntilRead(5.0);
      pty.Close();
      std::fprintf(stderr, "metro_sim_receiver: unplugged at t = %.3f s\n", t_s);
      const double until = Now() + opt.replug_after_s;
      while (!g_stop && Now() < until) SleepUntil(std::min(until, Now() + 0.1));
      if (g_stop) return false;
      std::fprintf(stderr, "metro_sim_receiver: replugged\n");
      if (!Connect(false)) return false;
    }
    SleepUntil(next_frame_time);
    if (g_stop) return false;
    max_lag_s = std::max(max_lag_s, Now() - next_frame_time);
    next_frame_time += opt.frame_period_s;
    std::string text;
    for (std::string_view line : lines) {
      const int sensor = std::stoi(std::string(line.substr(0, 2)), nullptr, 16);
      auto join = opt.join_s.find(sensor);
      std::string rewritten;
      if (join != opt.join_s.end()) {
        const bool fresh = line.substr(2, 2) == "01";
        bool& seen = joined_fresh[sensor];
        if (t_s < join->second || (!seen && !fresh)) {
          rewritten = metro::FormatReceiverLine(sensor, metro::NewDataFlag::kNever,
                                                metro::ReceiverPayload{}) +
                      "\n";
          line = rewritten;
        } else if (fresh) {
          seen = true;
        }
      }
      text.append(line.data(), line.size());
    }
    pty.Drain();
    if (!pty.Write(text)) return false;
    if (record != nullptr) {
      // Flushed per frame: a test reads it while the receiver is unplugged or running.
      std::fwrite(text.data(), 1, text.size(), record);
      std::fflush(record);
    }
    if (!lines.empty())
      first_line_tail = std::string(lines.back().substr(0, lines.back().size() - 1));
    ++frame;
    return true;
  }
};

// ---- main's stages ------------------------------------------------------------------------

// The command line into *o; 0, or the usage error's exit code.
int ParseArgs(int argc, char** argv, Options* options) {
  Options& o = *options;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (i + 1 >= argc) return Usage("missing value after " + a);
    const char* v = argv[++i];
    double d = 0;
    int n = 0;
    if (a == "--port-link") {
      o.link = v;
    } else if (a == "--tags") {
      if (!ParseInt(v, 1, 255, &o.tags)) return Usage("--tags takes 1..255");
    } else if (a == "--never") {
      if (!ParseInt(v, 1, 255, &n)) return Usage("--never takes a tag number 1..255");
      o.never.push_back(n);
    } else if (a == "--join") {
      const char* colon = std::strchr(v, ':');
      if (colon == nullptr || !ParseInt(std::string(v, colon).c_str(), 1, 255, &n) ||
          !ParseDouble(colon + 1, &d) || d < 0) {
        return Usage("--join takes TAG:T_S, e.g. 3:5.0");
      }
      o.join_s[n] = d;
    } else if (a == "--packet-loss") {
      if (!ParseDouble(v, &o.packet_loss)) return Usage("--packet-loss takes a number in [0, 1)");
    } else if (a == "--frame-period-s") {
      if (!ParseDouble(v, &o.frame_period_s)) return Usage("--frame-period-s takes seconds");
    } else if (a == "--duration-s") {
      if (!ParseDouble(v, &o.duration_s) || o.duration_s <= 0) {
        return Usage("--duration-s takes seconds > 0");
      }
    } else if (a == "--seed") {
      if (!ParseInt(v, 0, 2000000000, &n)) return Usage("--seed takes an integer");
      o.seed = static_cast<uint64_t>(n);
    } else if (a == "--cut-first-line") {
      if (!ParseInt(v, 1, metro::kReceiverLineHexChars - 1, &o.cut_chars)) {
        return Usage("--cut-first-line takes 1..53 characters");
      }
    } else if (a == "--banner") {
      o.banner = v;
    } else if (a == "--unplug-at-s") {
      if (!ParseDouble(v, &o.unplug_at_s) || o.unplug_at_s < 0) {
        return Usage("--unplug-at-s takes seconds >= 0");
      }
    } else if (a == "--replug-after-s") {
      if (!ParseDouble(v, &o.replug_after_s) || o.replug_after_s < 0 || o.replug_after_s > 600) {
        return Usage("--replug-after-s takes seconds in [0, 600]");
      }
    } else if (a == "--record") {
      o.record = v;
    } else {
      return Usage("unknown option " + a);
    }
  }
  if (o.link.empty()) return Usage("--port-link PATH is required");
  return 0;
}

// The static simulator's options for the tags, late joiners and timing asked for; 0, or
// the usage error's exit code.
int SimOptionsOf(const Options& o, metro::StaticSimulationOptions* out) {
  metro::StaticSimulationOptions& sim = *out;
  sim.seed = o.seed;
  sim.sensors.clear();
  for (int s = 1; s <= o.tags; ++s) {
    if (std::count(o.never.begin(), o.never.end(), s) == 0) sim.sensors.push_back(s);
  }
  for (int s : o.never) {
    if (s > o.tags) return Usage("--never " + std::to_string(s) + " is not one of the --tags");
    sim.never_sensors.push_back(s);
  }
  for (const auto& [s, t] : o.join_s) {
    if (s > o.tags) return Usage("--join " + std::to_string(s) + " is not one of the --tags");
  }
  sim.frame_period_s = o.frame_period_s;
  sim.packet_loss = o.packet_loss;
  const double lines_per_s = static_cast<double>(o.tags) / o.frame_period_s;
  sim.duration_s = o.duration_s > 0 ? o.duration_s
                                    : std::min(metro::kSimMaxDurationS,
                                               0.5 * metro::kSimMaxObservations / lines_per_s);
  if (std::string why; !sim.IsValid(&why)) return Usage(why);
  return 0;
}

// The simulator's text, frame by frame, to the pty at the frame period (connecting on the
// first chunk).
metro::Status StreamFrames(const metro::StaticSimulationOptions& sim, Streamer* streamer) {
  Streamer& st = *streamer;
  bool connected = false;
  const metro::TextSink pace = [&](std::string_view chunk) -> metro::Status {
    if (!connected) {
      st.first_line_tail = std::string(chunk.substr(0, chunk.find('\n')));
      if (!st.Connect(true)) return metro::MakeError("stopped");
      connected = true;
    }
    std::vector<std::string_view> frame;
    int previous = 256;
    size_t pos = 0;
    while (pos < chunk.size()) {
      size_t nl = chunk.find('\n', pos);
      if (nl == std::string_view::npos) nl = chunk.size() - 1;
      const std::string_view line = chunk.substr(pos, nl + 1 - pos);
      pos = nl + 1;
      const int sensor = std::stoi(std::string(line.substr(0, 2)), nullptr, 16);
      if (sensor <= previous && !frame.empty()) {
        if (!st.SendFrame(frame)) return metro::MakeError("stopped");
        frame.clear();
      }
      previous = sensor;
      frame.push_back(line);
    }
    if (!frame.empty() && !st.SendFrame(frame)) return metro::MakeError("stopped");
    return metro::Status::Ok();
  };
  return metro::SimulateStaticSession(sim, metro::SessionFormat::kReceiver, pace);
}

}  // namespace

int main(int argc, char** argv) {
  metro::apps::sim::g_program = "metro_sim_receiver";
  Options o;
  if (int code = ParseArgs(argc, argv, &o); code != 0) return code;
  metro::StaticSimulationOptions sim;
  if (int code = SimOptionsOf(o, &sim); code != 0) return code;
  InstallSignals();
  Streamer st;
  st.opt = o;
  if (!o.record.empty()) {
    st.record = std::fopen(o.record.c_str(), "wb");
    if (st.record == nullptr) {
      std::fprintf(stderr, "metro_sim_receiver: cannot create %s: %s\n", o.record.c_str(),
                   std::strerror(errno));
      return 1;
    }
  }
  if (!st.pty.Open(o.link)) return 1;
  std::printf("pty: %s\n", st.pty.SlaveName().c_str());
  std::fflush(stdout);

  bool failed = false;
  const metro::Status s = StreamFrames(sim, &st);
  if (st.record != nullptr) {
    if (std::fclose(st.record) != 0) failed = true;
    st.record = nullptr;
  }
  if (s.ok()) {
    std::fprintf(stderr, "metro_sim_receiver: %lld frames sent, at most %.1f ms behind schedule\n",
                 static_cast<long long>(st.frame), 1e3 * st.max_lag_s);
    std::printf("done\n");
    std::fflush(stdout);
    while (!g_stop) {
      st.pty.Drain();
      ::poll(nullptr, 0, 50);
    }
  } else if (!g_stop) {
    std::fprintf(stderr, "metro_sim_receiver: %s\n", s.error().message.c_str());
    failed = true;
  }
  st.pty.Close();
  return failed ? 1 : 0;
}
