// The value-level halves of calibration.json's codec (calibration_io.hpp has the text
// functions): private to the library, for a document that embeds a calibration or part of
// one (the registry's export). The writer's value is an nlohmann::json, whose object keys are
// sorted: calibration.json has always been written with its keys in that order.
#pragma once

#include <nlohmann/json.hpp>

#include "core/json_reader.hpp"
#include "metro/calibration/calibration_io.hpp"
#include "metro/calibration/conformity.hpp"

namespace metro {

nlohmann::json ToJsonValue(const Calibration& calibration);
// Reads a calibration at `cursor` (the root of calibration.json); an error is recorded on the
// cursor (JsonCursor::ok(), error()) at the offending value's file:line:column with its path.
Calibration CalibrationFromJsonValue(const JsonCursor& cursor);

// calibration.json's `conformity` (the entries) and `conformity_rule` (docs/conformity.md).
nlohmann::json ConformityEntriesToJson(const ConformityStatement& statement);
nlohmann::json ConformityRuleToJson(const ConformityStatement& statement);
ConformityStatement ConformityFromJsonValue(const JsonCursor& entries, const JsonCursor& rule);

}  // namespace metro
