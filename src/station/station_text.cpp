// The station's events as plain lines and as JSON (docs/station.md "Events"), and its
// terminal view (docs/station.md "The view").
#include <fmt/format.h>

#include <cmath>
#include <nlohmann/json.hpp>

#include "metro/station/station.hpp"

namespace metro::station {

namespace {

std::string UList(const std::vector<ConstantU>& u) {
  std::string out;
  for (const ConstantU& c : u) {
    out += fmt::format(" {}={:.3g}/{:.3g}{}{}", c.name, c.u, c.target,
                       c.unit == "mg" ? "mg" : "dps", c.met ? "" : "!");
  }
  return out;
}

}  // namespace

std::string EventText(const StationEvent& e) {
  std::string s = fmt::format("{} t_s={:.2f}", StationEventKindName(e.kind), e.t_s);
  if (e.line > 0) s += fmt::format(" line={}", e.line);
  if (e.pose > 0) s += fmt::format(" pose={}", e.pose);
  if (!e.pose_name.empty()) s += fmt::format(" name=\"{}\"", e.pose_name);
  if (e.kind == StationEventKind::kStopped) {
    s += e.targets_met ? " targets=met" : " targets=not_met";
  }
  if (e.kind == StationEventKind::kTargetMet && e.u.size() == 1) {
    s += fmt::format(" constant={} u={:.3g} target={:.3g} unit={}", e.u[0].name, e.u[0].u,
                     e.u[0].target, e.u[0].unit);
  } else if (!e.u.empty()) {
    const int met = static_cast<int>(
        std::count_if(e.u.begin(), e.u.end(), [](const ConstantU& c) { return c.met; }));
    s += fmt::format(" met={}/{} u:{}", met, e.u.size(), UList(e.u));
  }
  if (!e.reason.empty()) s += " -- " + e.reason;
  return s;
}

std::string EventJson(const StationEvent& e) {
  nlohmann::ordered_json j;
  j["event"] = StationEventKindName(e.kind);
  j["t_s"] = e.t_s;
  if (e.line > 0) j["line"] = e.line;
  if (e.pose > 0) j["pose"] = e.pose;
  if (!e.pose_name.empty()) j["pose_name"] = e.pose_name;
  if (!e.reason.empty()) j["reason"] = e.reason;
  if (e.kind == StationEventKind::kStopped) j["targets_met"] = e.targets_met;
  if (!e.u.empty()) {
    nlohmann::ordered_json list = nlohmann::ordered_json::array();
    for (const ConstantU& c : e.u) {
      list.push_back(
          {{"name", c.name}, {"u", c.u}, {"target", c.target}, {"unit", c.unit}, {"met", c.met}});
    }
    j["u"] = list;
  }
  return j.dump();
}

namespace {

constexpr double kPi = 3.14159265358979323846;

std::string Colored(const std::string& text, const char* code, bool color) {
  return color ? fmt::format("\x1b[{}m{}\x1b[0m", code, text) : text;
}

// Row and column of an up direction on the coverage map (elevation rows 90 .. -90 in steps of
// 180 / (rows - 1), azimuth columns -180 .. 180).
std::pair<int, int> MapCell(const Eigen::Vector3d& up, int rows, int cols) {
  const double el = std::asin(std::clamp(up.z(), -1.0, 1.0)) * 180.0 / kPi;
  const double az = std::atan2(up.y(), up.x()) * 180.0 / kPi;
  const int r = static_cast<int>(std::lround((90.0 - el) / 180.0 * (rows - 1)));
  int c = static_cast<int>(std::lround((az + 180.0) / 360.0 * (cols - 1)));
  if (r == 0 || r == rows - 1) c = (cols - 1) / 2;  // The poles: one cell.
  return {r, c};
}

}  // namespace

std::vector<std::string> CoverageMap(const StationView& v, int rows, int cols) {
  std::vector<std::string> grid(static_cast<size_t>(rows),
                                std::string(static_cast<size_t>(cols), ' '));
  auto put = [&](const Eigen::Vector3d& up, char ch) {
    const auto [r, c] = MapCell(up.normalized(), rows, cols);
    char& cell = grid[static_cast<size_t>(r)][static_cast<size_t>(c)];
    if (ch == '#' || cell == ' ' || (ch == '@' && cell == '.')) cell = ch;
  };
  for (const ProtocolPose& p : v.poses) put(p.up_body, '.');
  if (!v.next_pose.empty()) put(v.next_up, '@');
  for (const Eigen::Vector3d& t : v.taken) put(t, '#');
  return grid;
}

std::string RenderStationView(const StationView& v, const std::string& title, bool color) {
  std::string out = title + "\n\n";
  if (v.done) {
    out += Colored("STOPPED: " + v.stop_reason, v.u.empty() ? "31" : "1", color) + "\n";
  } else {
    out += fmt::format("Next pose: {}   ({})\n", Colored(v.next_pose, "1;36", color), v.turn);
  }
  const int meter = static_cast<int>(std::lround(std::clamp(v.stillness, 0.0, 2.0) * 10));
  std::string bar;
  for (int i = 0; i < 20; ++i) bar += i < meter ? (i < 10 ? '=' : '!') : ' ';
  out +=
      fmt::format("Stillness: [{}] {:.2f} {}\n", bar, v.stillness,
                  v.stillness < 1 ? Colored("still", "32", color) : Colored("moving", "33", color));
  if (v.holding) {
    const double left = std::max(0.0, v.dwell_s - v.held_s);
    out += fmt::format(
        "Holding: {:.1f} s of {:.1f} s, {}\n", v.held_s, v.dwell_s,
        left > 0 ? fmt::format("{:.1f} s left", left) : Colored("complete: move on", "32", color));
  } else if (v.too_close) {
    out += Colored("Too close to a pose already taken: take the next pose", "33", color) + "\n";
  } else {
    out += "Holding: -\n";
  }
  int covered = 0;
  for (bool c : v.covered) covered += c ? 1 : 0;
  out += fmt::format("\nCoverage: {} poses taken, {} of {} protocol poses covered\n",
                     v.taken.size(), covered, v.poses.size());
  out +=
      "  (the body's up: elevation rows, azimuth -180 .. 180 deg; # taken, @ next, . protocol)\n";
  const std::vector<std::string> map = CoverageMap(v, 9, 37);
  for (size_t r = 0; r < map.size(); ++r) {
    out += fmt::format("  {:+4d} |{}|\n", 90 - static_cast<int>(r) * 180 / 8, map[r]);
  }
  out += "\nu (k = 1) against target:\n";
  if (v.u.empty()) out += "  " + v.u_status + "\n";
  for (size_t i = 0; i < v.u.size(); ++i) {
    const ConstantU& c = v.u[i];
    const std::string cell = fmt::format("{:<11}{:>8.3g} {:<5}", c.name, c.u, c.unit);
    out += "  " + Colored(cell, c.met ? "32" : "31", color) + ((i % 3 == 2) ? "\n" : "  ");
  }
  if (v.u.size() % 3 != 0) out += "\n";
  return out;
}

std::string SegmentsCsvText(const std::vector<AnnotatedSegment>& segments) {
  std::string out = "kind,start_s,end_s,input\n";
  for (const AnnotatedSegment& a : segments) {
    out += fmt::format("{},{},{},{}\n", SegmentKindName(a.kind), a.start_s, a.end_s, a.input + 1);
  }
  return out;
}

}  // namespace metro::station
