// libFuzzer target: `characterize report REPORT.json --html`: any saved JSON document,
// dispatched on its "schema" (session report, calibration certificate, accuracy report,
// generic view). A page is drawn from the document alone (no input is reloaded), so an input
// costs one parse and one render.
#include <cstddef>
#include <cstdint>

#include "fuzz_input.hpp"
#include "metro/report/html_report.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string& path = metro_fuzz::WriteInput(data, size, "report.json");
  (void)metro::RenderJsonFileHtml(path);
  return 0;
}
