// calibrate station: the live guide's events and view, then fit, blob and push on the record
// (station_command.hpp).
#include "station_command.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <deque>
#include <memory>

#include "commands.hpp"
#include "metro/core/file.hpp"
#include "metro/core/terminal_text.hpp"
#include "metro/io/session_io.hpp"
#include "metro/station/station.hpp"
#include "metro/station/stream_reader.hpp"
#include "registry_hooks.hpp"
#include "tags_cli.hpp"
#include "unix_cli.hpp"

namespace metro::calibrate_app {
namespace {

// What the operator and a station script see: the view on a terminal, else one line per event.
class EventOutput {
 public:
  EventOutput(const StationCliOptions& c, std::string title)
      : json_(c.json_events),
        view_(!c.json_events && !c.no_view && isatty(STDOUT_FILENO) == 1),
        title_(std::move(title)) {}

  void Events(const std::vector<station::StationEvent>& events) {
    for (const station::StationEvent& e : events) {
      const std::string text =
          EscapeControlChars(json_ ? station::EventJson(e) : station::EventText(e));
      if (view_) {
        recent_.push_back(text);
        if (recent_.size() > 6) recent_.pop_front();
      } else {
        std::fputs((text + "\n").c_str(), stdout);
        std::fflush(stdout);
      }
    }
  }
  // Redraws the view, at most 10 times a second unless `now`.
  void Draw(const station::Station& st, bool now) {
    if (!view_) return;
    const auto t = std::chrono::steady_clock::now();
    if (!now && t - last_draw_ < std::chrono::milliseconds(100)) return;
    last_draw_ = t;
    std::string screen = "\x1b[H\x1b[2J" + station::RenderStationView(st.View(), title_, true);
    screen += "\nEvents:\n";
    for (const std::string& r : recent_) screen += "  " + r.substr(0, 160) + "\n";
    std::fputs(screen.c_str(), stdout);
    std::fflush(stdout);
  }

 private:
  bool json_, view_;
  std::string title_;
  std::deque<std::string> recent_;
  std::chrono::steady_clock::time_point last_draw_{};
};

// Reads the stream into the station until its stop or the stream's end. Returns the exit code
// of a refused stream (a bad line), else -1.
int Guide(const StationCliOptions& c, station::Station* st, EventOutput* out) {
  Result<std::unique_ptr<station::RawStreamReader>> reader =
      station::RawStreamReader::Open(c.port, c.reader);
  if (!reader.ok()) return apps::PrintErrorExit(reader.error().WithContext("--port"));
  while (!st->Done()) {
    const station::RawStreamReader::Item item = reader.value()->Next(100);
    using K = station::RawStreamReader::Kind;
    if (item.kind == K::kLine) {
      if (station::IsSkippedRawLine(item.line)) continue;
      Result<station::RawSample> s = station::ParseRawLine(item.line, c.port, item.line_number);
      if (!s.ok()) {
        apps::PrintErrorText(s.error().ToString() + " (the stream is refused; nothing written)");
        return kExitUsage;
      }
      out->Events(st->Feed(s.value(), item.line_number));
    } else if (item.kind == K::kLost) {
      out->Events(st->Gap("the port disappeared (" + item.why + ")"));
    } else if (item.kind == K::kResumed) {
      apps::Note(fmt::format("{}: resumed\n", item.why));
    } else if (item.kind == K::kEnded) {
      out->Events(st->Finish("the stream ended: " + item.why));
    }
    out->Draw(*st, st->Done());
  }
  return -1;
}

// The record, the accepted poses, then fit, blob and push as their own commands run them.
int FitBlobPush(const StationCliOptions& c, const station::Station& st) {
  const std::vector<Session> sessions = st.Sessions();
  std::vector<std::pair<std::string, std::string>> files;
  std::vector<std::string> inputs;
  for (size_t i = 0; i < sessions.size(); ++i) {
    const std::string name =
        c.out_dir + (sessions.size() == 1 ? "/station_session.csv"
                                          : fmt::format("/station_session_{}.csv", i + 1));
    files.emplace_back(name, FormatSessionCsv(sessions[i]));
    inputs.push_back(name);
  }
  const std::string segments = c.out_dir + "/station_segments.csv";
  files.emplace_back(segments, station::SegmentsCsvText(st.Segments()));
  std::vector<std::pair<std::string, std::string_view>> views(files.begin(), files.end());
  if (Status w = apps::WriteOutputs(views); !w.ok()) return apps::PrintErrorExit(w.error());
  apps::Note(fmt::format("station: record -> {} ({} poses) and {}\n", inputs.front(),
                         st.AcceptedPoses(), segments));
  const std::string sensor = std::to_string(c.station.sensor);
  const std::string cal = c.out_dir + "/calibration.json";
  std::vector<std::string> registry;
  if (!c.registry.url.empty()) registry = {"--registry", c.registry.url};
  if (!c.registry.station.empty())
    registry.insert(registry.end(), {"--station", c.registry.station});
  if (!c.registry.operator_name.empty()) {
    registry.insert(registry.end(), {"--operator", c.registry.operator_name});
  }
  std::vector<std::string> fit = {"fit"};
  fit.insert(fit.end(), inputs.begin(), inputs.end());
  fit.insert(fit.end(), {"--segments", segments, "--sensor", sensor, "--model", c.model,
                         "--accel-fs-g", fmt::format("{}", c.station.accel_fs_g), "--gyro-fs-dps",
                         fmt::format("{}", c.station.gyro_fs_dps), "--tags", c.tags, "-o", cal,
                         "--html", c.out_dir + "/certificate.html"});
  fit.insert(fit.end(), registry.begin(), registry.end());
  int rc = c.run_calibrate(fit);
  apps::Note(
      fmt::format("station: fit -> {}, {}/certificate.html (exit {})\n", cal, c.out_dir, rc));
  if (rc != kExitOk) return rc;
  std::vector<std::string> blob = {"blob",     cal,
                                   "--sensor", sensor,
                                   "--tags",   c.tags,
                                   "-o",       c.out_dir + "/tag.bin",
                                   "--hex",    c.out_dir + "/tag.hex"};
  blob.insert(blob.end(), registry.begin(), registry.end());
  rc = c.run_calibrate(blob);
  apps::Note(fmt::format("station: blob -> {0}/tag.bin, {0}/tag.hex (exit {1})\n", c.out_dir, rc));
  if (rc != kExitOk || !c.push) return rc;
  const std::string port = c.push_port.empty() ? c.port : c.push_port;
  std::vector<std::string> push = {"push",     "--port", port,     cal,
                                   "--sensor", sensor,   "--tags", c.tags};
  push.insert(push.end(), registry.begin(), registry.end());
  rc = c.run_calibrate(push);
  apps::Note(fmt::format("station: push -> {} (exit {})\n", port, rc));
  return rc;
}

}  // namespace

int RunStation(StationCliOptions c) {
  if (c.format != "raw") {
    apps::PrintErrorText(
        fmt::format("--format {}: the station reads the raw line format only (--format raw: "
                    "ax,ay,az,gx,gy,gz[,t_ms] counts, docs/station.md)",
                    c.format));
    return kExitUsage;
  }
  c.station.protocol = *station::ParseProtocol(c.protocol);
  c.station.calibration.accel_model = *ParseModelKind(c.model);
  c.station.calibration.gyro_model = *ParseModelKind(c.model);
  std::string why;
  if (!c.station.IsValid(&why) || !c.reader.IsValid(&why)) {
    apps::PrintErrorText(why);
    return kExitUsage;
  }
  Result<std::optional<TagRegistry>> tags = LoadTagsOption(c.tags);
  if (!tags.ok()) return apps::PrintErrorExit(tags.error());
  OpenedRegistry registry = OpenRegistryOption(c.registry);  // Refused before the session.
  if (registry.exit_code != 0) return registry.exit_code;
  station::Station st(c.station, c.port);
  EventOutput out(c, fmt::format("metro calibration station: {} protocol, sensor {}, {}",
                                 c.protocol, c.station.sensor, EscapeControlChars(c.port)));
  if (int refused = Guide(c, &st, &out); refused >= 0) return refused;
  if (st.View().u.empty()) {
    apps::PrintErrorText("station: the calibration is not determined (" + st.View().stop_reason +
                         "); nothing fitted");
    return kExitFailed;
  }
  const int rc = FitBlobPush(c, st);
  return std::max(rc, st.TargetsMet() ? kExitOk : kExitFailed);
}

}  // namespace metro::calibrate_app
