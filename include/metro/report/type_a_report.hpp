// The Type A report ("metro.report/1", docs/report-schema.md): the typed report of a
// session's Type A evaluation (session_report.hpp) and a readable table for people.
#pragma once

#include <string>

#include "metro/io/session.hpp"
#include "metro/io/tag_registry.hpp"
#include "metro/report/session_report.hpp"
#include "metro/stats/session_type_a.hpp"

namespace metro {

// The report of `result`, the Type A evaluation of `session` with `options` (echoed under
// "options" so a report says how it was made): input, options, and per tag and quantity the
// window, the Type A terms with the mean's expanded uncertainty (coverage, k, U_mean) and the
// warnings. Each tag is named by `registry` for the session's format (TagRegistry::Name: a
// third-party file's sensor is "sensor N", not a thesis tag's body part). The settle and
// Allan stages add their keys (settle_report.hpp, allan_section.hpp).
SessionReport MakeSessionReport(const Session& session, const SessionTypeA& result,
                                const SessionTypeAOptions& options, const TagRegistry& registry);

// A fixed-width table: one row per tag and quantity, values rounded per GUM 7.2.6.
// Ends with the report's warnings (TypeAReportWarnings).
std::string TypeAReportTable(const SessionReport& report);

// The report's warnings (input, per tag, per quantity), one line each under a "warnings:"
// heading; empty when there are none. The programs print it to stderr when the table is
// not printed (--quiet, or the JSON on stdout), so a warning is never only in the JSON.
std::string TypeAReportWarnings(const SessionReport& report);

}  // namespace metro
