#include "metro/report/session_report.hpp"

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

}  // namespace metro
