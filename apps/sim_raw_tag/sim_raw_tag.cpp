// metro_sim_raw_tag: a simulated tag printing raw counts, moved by an operator script, on a
// pseudo-terminal or into a growing file: the calibration station's source for tests and
// demonstrations without hardware (docs/station.md "Simulator").
//
//   metro_sim_raw_tag (--port-link PATH | -o FILE) [--script FILE | --demo] [--seed N]
//                     [--rate-hz R] [--speed X] [--t-ms]
//
// Lines: ax,ay,az,gx,gy,gz[,t_ms] (the station's raw format), the tag's truth and noise from
// sim/raw_tag.hpp (seeded). The script, one action per line ('#' comments):
//   hold S            still for S seconds
//   move POSE S       a hand turn of S seconds to POSE: a protocol name ("Z up", "X down",
//                     "corner +X+Y+Z up", "edge +X-Y up") or a body direction "x,y,z"
//   knock G           an 80 ms jolt of peak G g
//   reseat S          lifted and set down on the same face within S seconds
//   unplug S          (pty) the port disappears for S seconds, then a new pty appears at PATH
//   garbage TEXT      a line that is not raw counts
// --demo: the built-in script (docs/station.md): the six faces in a shuffled order with one
// face skipped and taken last, a hold too short, a knock, a re-seat, then corners and edges.
// --speed X: X times real time (default 1; 0: as fast as the reader takes it).
// Prints "pty: /dev/pts/N" when PATH is ready (once a program opened it the stream starts),
// "done" after the script; then idles until SIGTERM/SIGINT. Exit 0 after a signal or, with -o,
// at the script's end; 2 for bad arguments or script, 1 for a system error.
#include <fmt/format.h>

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <vector>

#include "metro/sim/raw_tag.hpp"
#include "metro/station/protocol.hpp"
#include "metro/station/raw_line.hpp"
#include "sim_pty.hpp"

namespace {

using metro::apps::sim::g_stop;
using metro::apps::sim::InstallSignals;
using metro::apps::sim::Now;
using metro::apps::sim::Pty;
using metro::apps::sim::SleepUntil;

struct Action {
  std::string verb;
  Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
  double value = 0;
  std::string text;
  int line = 0;
};

const char* kDemoScript = R"(# The demonstration: faces shuffled, "Y down" skipped at first.
hold 3
move X up 1.5
hold 3
move Z down 2
hold 0.8
# Too short: moved on; the guide asks for it again.
move Y up 1.5
hold 3
move X down 1.5
hold 0.9
knock 0.6
hold 3
reseat 1.2
hold 2
move Z down 1.5
hold 3
move corner +X+Y+Z up 1.5
hold 3
move corner -X-Y+Z up 1.5
hold 3
move corner +X-Y-Z up 1.5
hold 3
move corner -X+Y-Z up 1.5
hold 3
move Y down 1.5
hold 3
move corner +X-Y+Z up 1.5
hold 3
move corner -X+Y+Z up 1.5
hold 3
move corner +X+Y-Z up 1.5
hold 3
move corner -X-Y-Z up 1.5
hold 3
move edge +X+Y up 1.5
hold 3
move edge +Y+Z up 1.5
hold 3
move edge +X+Z up 1.5
hold 3
move edge -X-Y up 1.5
hold 3
move edge -Y-Z up 1.5
hold 3
move edge -X-Z up 1.5
hold 3
)";

bool ParsePose(const std::string& text, Eigen::Vector3d* up) {
  for (const metro::station::ProtocolPose& p :
       metro::station::ProtocolPoses(metro::station::Protocol::kSixFace)) {
    if (p.name == text) {
      *up = p.up_body;
      return true;
    }
  }
  double x = 0, y = 0, z = 0;
  char c1 = 0, c2 = 0;
  std::istringstream in(text);
  if (in >> x >> c1 >> y >> c2 >> z && c1 == ',' && c2 == ',' &&
      Eigen::Vector3d(x, y, z).norm() > 0) {
    *up = Eigen::Vector3d(x, y, z).normalized();
    return true;
  }
  return false;
}

// The script's actions; an error names the line: "script:4: ...".
bool ParseScript(const std::string& text, const std::string& name, std::vector<Action>* out) {
  std::istringstream in(text);
  std::string line;
  int n = 0;
  while (std::getline(in, line)) {
    ++n;
    if (line.empty() || line[0] == '#') continue;
    Action a;
    a.line = n;
    std::istringstream ls(line);
    ls >> a.verb;
    std::string rest;
    std::getline(ls, rest);
    rest.erase(0, rest.find_first_not_of(' '));
    if (a.verb == "move") {
      const size_t sp = rest.find_last_of(' ');
      char* end = nullptr;
      a.value = sp == std::string::npos ? 0 : std::strtod(rest.c_str() + sp + 1, &end);
      if (sp == std::string::npos || !ParsePose(rest.substr(0, sp), &a.up) || !(a.value > 0)) {
        std::fprintf(stderr,
                     "metro_sim_raw_tag: %s:%d: expected 'move POSE SECONDS' (POSE "
                     "\"Z up\", \"corner +X+Y+Z up\" or x,y,z)\n",
                     name.c_str(), n);
        return false;
      }
    } else if (a.verb == "garbage") {
      a.text = rest;
    } else if (a.verb == "hold" || a.verb == "knock" || a.verb == "reseat" || a.verb == "unplug") {
      char* end = nullptr;
      a.value = std::strtod(rest.c_str(), &end);
      if (end == rest.c_str() || !(a.value > 0)) {
        std::fprintf(stderr, "metro_sim_raw_tag: %s:%d: expected '%s NUMBER' (> 0)\n", name.c_str(),
                     n, a.verb.c_str());
        return false;
      }
    } else {
      std::fprintf(stderr,
                   "metro_sim_raw_tag: %s:%d: unknown action '%s' (hold, move, knock, "
                   "reseat, unplug, garbage)\n",
                   name.c_str(), n, a.verb.c_str());
      return false;
    }
    out->push_back(a);
  }
  return true;
}

struct Sink {
  Pty pty;
  std::string link;
  std::FILE* file = nullptr;
  double speed = 1;
  double start = 0;

  bool Write(const std::string& text) {
    if (file != nullptr) {
      const bool ok = std::fputs(text.c_str(), file) >= 0 && std::fflush(file) == 0;
      return ok;
    }
    pty.Drain();
    return pty.Write(text);
  }
};

int Usage(const std::string& why) {
  std::fprintf(stderr, "metro_sim_raw_tag: %s\n", why.c_str());
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  metro::apps::sim::g_program = "metro_sim_raw_tag";
  std::string link, output, script_path;
  bool demo = false, t_ms = false;
  metro::RawTagOptions o;
  double speed = 1;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const bool has = i + 1 < argc;
    if (a == "--port-link" && has) {
      link = argv[++i];
    } else if (a == "-o" && has) {
      output = argv[++i];
    } else if (a == "--script" && has) {
      script_path = argv[++i];
    } else if (a == "--demo") {
      demo = true;
    } else if (a == "--t-ms") {
      t_ms = true;
    } else if (a == "--seed" && has) {
      o.seed = std::strtoull(argv[++i], nullptr, 10);
    } else if (a == "--rate-hz" && has) {
      o.rate_hz = std::atof(argv[++i]);
    } else if (a == "--speed" && has) {
      speed = std::atof(argv[++i]);
    } else {
      return Usage("unknown or incomplete argument '" + a +
                   "'; usage: metro_sim_raw_tag (--port-link PATH | -o FILE) [--script FILE | "
                   "--demo] [--seed N] [--rate-hz R] [--speed X] [--t-ms]");
    }
  }
  if (link.empty() == output.empty()) return Usage("give one of --port-link PATH and -o FILE");
  if (demo == !script_path.empty()) return Usage("give one of --script FILE and --demo");
  std::string why;
  if (!o.IsValid(&why) || !(speed >= 0)) return Usage(why.empty() ? "--speed must be >= 0" : why);
  std::string text = kDemoScript;
  if (!demo) {
    std::ifstream in(script_path);
    if (!in) return Usage("cannot read " + script_path);
    std::stringstream ss;
    ss << in.rdbuf();
    text = ss.str();
  }
  std::vector<Action> actions;
  if (!ParseScript(text, demo ? "demo" : script_path, &actions)) return 2;
  InstallSignals();
  Sink sink;
  sink.speed = speed;
  if (!output.empty()) {
    sink.file = std::fopen(output.c_str(), "w");
    if (sink.file == nullptr) return Usage("cannot write " + output);
  } else {
    if (!sink.pty.Open(link)) return 1;
    std::printf("pty: %s\n", sink.pty.SlaveName().c_str());
    std::fflush(stdout);
    if (!sink.pty.WaitForReader()) return 0;
  }
  metro::SimulatedRawTag tag(o);
  sink.start = Now();
  int64_t written = 0;
  for (const Action& a : actions) {
    if (g_stop) break;
    std::vector<metro::RawTagSample> samples;
    if (a.verb == "hold") tag.Hold(a.value, &samples);
    if (a.verb == "move") tag.Move(a.up, a.value, &samples);
    if (a.verb == "knock") tag.Knock(a.value, &samples);
    if (a.verb == "reseat") tag.Reseat(a.value, &samples);
    if (a.verb == "garbage" && !sink.Write(a.text + "\n")) return 1;
    if (a.verb == "unplug" && sink.file == nullptr) {
      sink.pty.Close();
      const double until = Now() + a.value;
      while (!g_stop && Now() < until) SleepUntil(std::min(until, Now() + 0.1));
      if (g_stop || !sink.pty.Open(link) || !sink.pty.WaitForReader()) break;
      sink.start = Now() - static_cast<double>(written) / o.rate_hz / std::max(speed, 1e-9);
    }
    for (const metro::RawTagSample& s : samples) {
      metro::station::RawSample r;
      for (int k = 0; k < 3; ++k) {
        r.accel_lsb[k] = s.counts[k];
        r.gyro_lsb[k] = s.counts[3 + k];
      }
      if (t_ms) r.t_ms = s.t_s * 1000.0;
      if (speed > 0) SleepUntil(sink.start + s.t_s / speed);
      if (g_stop) break;
      if (!sink.Write(metro::station::FormatRawLine(r) + "\n")) {
        if (sink.file != nullptr) return 1;
        break;  // The reader went away.
      }
      ++written;
    }
  }
  std::printf("done\n");
  std::fflush(stdout);
  if (sink.file != nullptr) {
    std::fclose(sink.file);
    return 0;
  }
  while (!g_stop) {
    sink.pty.Drain();
    SleepUntil(Now() + 0.1);
  }
  sink.pty.Close();
  return 0;
}
