#include "metro/report/session_report.hpp"

#include <fmt/format.h>

namespace metro {

const QuantityReport* SensorReport::Find(const std::string& quantity) const {
  for (const QuantityReport& q : quantities) {
    if (q.name == quantity) return &q;
  }
  return nullptr;
}

QuantityReport* SensorReport::Find(const std::string& quantity) {
  for (QuantityReport& q : quantities) {
    if (q.name == quantity) return &q;
  }
  return nullptr;
}

const SensorReport* SessionReport::FindSensor(int64_t number) const {
  for (const SensorReport& s : sensors) {
    if (s.sensor == number) return &s;
  }
  return nullptr;
}

std::vector<std::string> NoFreshPacketWarnings(const SessionReport& report,
                                               const std::string& prefix) {
  std::vector<std::string> out;
  for (const SensorReport& s : report.sensors) {
    if (s.frames <= 0 || s.fresh != 0) continue;
    out.push_back(
        fmt::format("{}WARNING sensor {} ({}): no fresh packet in {} frames (stale {}, never {}): "
                    "packet_loss_ratio 1.0, no observations; the tag never connected or was lost",
                    prefix, s.sensor, s.name, s.frames, s.stale, s.never));
  }
  return out;
}

}  // namespace metro
