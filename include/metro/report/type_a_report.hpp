// The Type A report ("metro.report/1", docs/report-schema.md): JSON for machines and a
// readable table for people.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "metro/io/session.hpp"
#include "metro/io/tag_registry.hpp"
#include "metro/report/session_report.hpp"
#include "metro/stats/session_type_a.hpp"

namespace metro {

// Builds the report. `options` is echoed under "options" so a report says how it was made.
nlohmann::ordered_json TypeAReportJson(const Session& session, const SessionTypeA& result,
                                       const SessionTypeAOptions& options,
                                       const TagRegistry& registry);

// A fixed-width table: one row per tag and quantity, values rounded per GUM 7.2.6.
// Ends with the report's warnings (TypeAReportWarnings).
std::string TypeAReportTable(const nlohmann::ordered_json& report);

// The report's warnings (input, per tag, per quantity), one line each under a "warnings:"
// heading; empty when there are none. The programs print it to stderr when the table is
// not printed (--quiet, or the JSON on stdout), so a warning is never only in the JSON.
std::string TypeAReportWarnings(const nlohmann::ordered_json& report);

}  // namespace metro
