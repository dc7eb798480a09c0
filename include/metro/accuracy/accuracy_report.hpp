// The accuracy report: "metro.accuracy-report/1" JSON (every key and its unit in
// docs/accuracy.md) and a readable table for people.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "metro/accuracy/accuracy.hpp"
#include "metro/io/session.hpp"
#include "metro/io/tag_registry.hpp"

namespace metro {

// `session` and `reference` (may be null) name the inputs in the report's `input` section;
// `tags` names the evaluated tag there (`input.tag`: its name, and its device ID when the tags
// file gives one; docs/formats.md "Tags file").
nlohmann::ordered_json AccuracyReportJson(const AccuracyResult& result, const Session& session,
                                          const Session* reference,
                                          const TagRegistry& tags = TagRegistry::Default());
std::string AccuracyReportTable(const AccuracyResult& result);

}  // namespace metro
