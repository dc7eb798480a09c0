// The value-level halves of the "metro.accuracy-report/1" codec (accuracy_report.hpp), for
// documents that embed an accuracy report and for the page. Private to the library.
#pragma once

#include <nlohmann/json.hpp>

#include "core/json_reader.hpp"
#include "metro/accuracy/accuracy_report.hpp"

namespace metro {

nlohmann::ordered_json ToJsonValue(const AccuracyReport& report);

// The report's "options" section for `options` (also the page's options table).
nlohmann::ordered_json AccuracyOptionsToJsonValue(const AccuracyOptions& options);

// Reads the report at `cursor`; errors are recorded in the cursor's reading (check ok()).
AccuracyReport AccuracyReportFromJsonValue(const JsonCursor& cursor);

}  // namespace metro
