// The value-level JSON halves of the session report model (metro/report/session_report.hpp),
// for documents that embed one. Private to the library; the public codec is ToJson and
// SessionReportFromJson in session_report.hpp.
#pragma once

#include <nlohmann/json.hpp>

#include "core/json_reader.hpp"
#include "metro/report/session_report.hpp"

namespace metro {

nlohmann::ordered_json ToJsonValue(const SessionReport& report);

// Reads straight through; the cursor's first error (cursor.ok(), cursor.error()) says what
// was wrong and where. A "schema" other than kReportSchema is such an error.
SessionReport SessionReportFromJsonValue(const JsonCursor& cursor);

}  // namespace metro
