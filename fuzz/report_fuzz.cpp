// libFuzzer target: `characterize report REPORT.json --html`: any saved JSON document,
// dispatched on its "schema" (session report, calibration certificate, accuracy report,
// generic view). The session named inside a report is not reloaded (an explicit session
// path that does not exist is given), so an input costs one parse and one render.
#include <cstddef>
#include <cstdint>

#include "fuzz_input.hpp"
#include "metro/report/html_report.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string& path = metro_fuzz::WriteInput(data, size, "report.json");
  metro::HtmlReportOptions options;
  options.max_series_points = 200;
  (void)metro::RenderJsonFileHtml(path, path + ".no-session", options);
  return 0;
}
