#include "metro/report/noise_export_input.hpp"

#include <fmt/format.h>

namespace metro {
namespace {

bool HasAllan(const SensorReport& s) {
  for (const QuantityReport& q : s.quantities) {
    if (q.allan && IsRateQuantity(q.name)) return true;
  }
  return false;
}

}  // namespace

Result<NoiseExportInput> NoiseExportInputFromReport(const SessionReport& report,
                                                    const std::string& report_path,
                                                    std::optional<int64_t> sensor) {
  std::vector<const SensorReport*> with_allan;
  for (const SensorReport& s : report.sensors) {
    if (HasAllan(s)) with_allan.push_back(&s);
  }
  const SensorReport* chosen = nullptr;
  if (sensor) {
    chosen = report.FindSensor(*sensor);
    if (chosen == nullptr || !HasAllan(*chosen)) {
      return MakeError(report_path, 0,
                       fmt::format("sensor {} has no Allan section for its rate quantities in "
                                   "this report",
                                   *sensor));
    }
  } else if (with_allan.size() == 1) {
    chosen = with_allan.front();
  } else if (with_allan.empty()) {
    return MakeError(report_path, 0,
                     "no tag has an Allan section: make the report with characterize SESSION "
                     "--allan");
  } else {
    std::string numbers;
    for (const SensorReport* s : with_allan) {
      numbers += (numbers.empty() ? "" : ", ") + std::to_string(s->sensor);
    }
    return MakeError(report_path, 0,
                     fmt::format("tags {} have Allan sections; choose one with --sensor", numbers));
  }
  NoiseExportInput input;
  input.source = fmt::format("{} (sha256 {}), sensor {}{}, via {} ({} {})", report.input.path,
                             report.input.sha256, chosen->sensor,
                             chosen->name.empty() ? "" : " " + chosen->name, report_path,
                             report.tool.name, report.tool.version);
  for (const QuantityReport& q : chosen->quantities) {
    if (q.allan && IsRateQuantity(q.name)) input.axes.push_back({q.name, q.unit, *q.allan});
  }
  return input;
}

}  // namespace metro
