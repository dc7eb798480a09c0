#include "noise_export_options.hpp"

#include "metro/core/file.hpp"
#include "metro/report/noise_export_input.hpp"
#include "metro/report/session_report.hpp"

namespace metro::apps {

std::vector<std::string> NoiseExportFormatNames() {
  std::vector<std::string> names;
  for (NoiseExportFormat f : kAllNoiseExportFormats) names.emplace_back(NoiseExportFormatName(f));
  return names;
}

std::string DefaultSpecLibrary() { return METRO_SPEC_LIBRARY; }

Result<NoiseExportInput> LoadNoiseExportInput(const NoiseExportCliOptions& o) {
  std::string why;
  if (!o.library.IsValid(&why)) return MakeError(why);
  Result<std::string> text = ReadFile(o.report);
  if (!text.ok()) return text.error();
  Result<SessionReport> report = SessionReportFromJson(text.value(), o.report);
  if (!report.ok()) return report.error();
  return NoiseExportInputFromReport(report.value(), o.report, o.sensor);
}

}  // namespace metro::apps
