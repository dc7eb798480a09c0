// The value-level JSON halves of the Allan report models (noise/allan_report.hpp), embedded
// in a session report as a quantity's "allan" and "allan_type_a_link" (docs/noise.md). NaN
// is written as null and read back from null. Private to the library.
#pragma once

#include <nlohmann/json.hpp>

#include "core/json_reader.hpp"
#include "metro/noise/allan_report.hpp"

namespace metro {

nlohmann::ordered_json ToJsonValue(const AllanReport& allan);
AllanReport AllanReportFromJsonValue(const JsonCursor& cursor);

nlohmann::ordered_json ToJsonValue(const AllanTypeALink& link);
AllanTypeALink AllanTypeALinkFromJsonValue(const JsonCursor& cursor);

}  // namespace metro
