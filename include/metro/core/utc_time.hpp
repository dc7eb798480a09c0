// Times as metro writes them: ISO 8601 in UTC to the second, e.g. 2026-05-28T20:26:40Z (the
// one format of calibration.json's date_utc, report footers, capture headers and blob dates).
#pragma once

#include <ctime>
#include <optional>
#include <string>

namespace metro {

// `t` (seconds since 1970-01-01 UTC) as ISO 8601 UTC; empty when it cannot be represented.
std::string UtcIso8601(std::time_t t);

// The current time as ISO 8601 UTC.
std::string UtcIso8601Now();

// "2026-05-28T20:26:40Z" -> seconds since 1970-01-01 UTC; nullopt for any other form.
std::optional<std::time_t> ParseUtcIso8601(const std::string& text);

}  // namespace metro
