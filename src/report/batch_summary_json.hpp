// The value-level JSON halves of the batch summary model (metro/report/batch_summary.hpp).
// Private to the library; the public codec is ToJson and BatchSummaryFromJson.
#pragma once

#include <nlohmann/json.hpp>

#include "core/json_reader.hpp"
#include "metro/report/batch_summary.hpp"

namespace metro {

nlohmann::ordered_json ToJsonValue(const BatchSummaryReport& summary);

// Reads straight through; the cursor's first error (cursor.ok(), cursor.error()) says what
// was wrong and where. A "schema" other than kBatchSummarySchema is such an error, and so are
// sessions_total and sessions_failed that disagree with "sessions".
BatchSummaryReport BatchSummaryFromJsonValue(const JsonCursor& cursor);

}  // namespace metro
