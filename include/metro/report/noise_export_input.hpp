// The record a noise export or comparison reads (noise/noise_export.hpp) taken from a session
// report (metro.report/1): one tag's rate quantities with their Allan reports, and a source
// line naming the session file, its SHA-256 and the tag (issue #40).
#pragma once

#include <cstdint>
#include <optional>

#include "metro/core/status.hpp"
#include "metro/noise/noise_export.hpp"
#include "metro/report/session_report.hpp"

namespace metro {

// The axes of `sensor` (nullopt: the one tag whose rate quantities have an Allan section).
// `report_path` names the report in the source line. Errors (input): no tag with an Allan
// section (run characterize SESSION --allan), several and no sensor chosen (the numbers are
// listed), a sensor the report does not have.
Result<NoiseExportInput> NoiseExportInputFromReport(const SessionReport& report,
                                                    const std::string& report_path,
                                                    std::optional<int64_t> sensor);

}  // namespace metro
