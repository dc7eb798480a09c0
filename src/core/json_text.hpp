// JSON text from users' files (budgets, tag registries, calibration.json, reports): parsed
// with a nesting limit, errors at file:line:column. Private to the library and its tests: the
// public headers carry typed models, not JSON.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <utility>

#include "metro/core/status.hpp"

namespace metro {

// Deeper nesting than any metro file has (a report nests 6 levels) and far below what
// would exhaust the stack of code that walks a document recursively (a 70,000-level
// document crashed `characterize report`).
inline constexpr int kMaxJsonDepth = 64;

// More members in one object than any metro file has (a tags file holds at most 255 tags, a
// report's quantities a few dozen): an object's members are looked up one by one as it is
// read (nlohmann::ordered_json), so the bound keeps reading linear in the text (an object of
// 150,000 keys took 55 s).
inline constexpr size_t kMaxJsonObjectMembers = 4096;

// `text` as JSON, or an error `path:line:column: invalid JSON: ...` (the nlohmann parser's
// message), or `path:line:column: JSON nested deeper than 64 levels ...` at the bracket
// that goes beyond the limit, or `path:line:column: invalid JSON: ... number overflow ...` at
// a number too large for a double (1e999), or `path:line:column: a JSON object with more than
// 4096 members ...` at the comma that goes beyond kMaxJsonObjectMembers. Never throws.
Result<nlohmann::json> ParseJsonText(std::string_view text, const std::string& path);
Result<nlohmann::ordered_json> ParseOrderedJsonText(std::string_view text, const std::string& path);

// `j` as JSON text (`indent` < 0: one line). Strings that are not valid UTF-8 (a file name
// or a CSV header in Latin-1, a blob label) are written with U+FFFD in place of each bad
// byte instead of throwing nlohmann's type_error 316, which terminated `characterize` for a
// session named in Latin-1 (issue #20). Every JSON metro writes goes through here.
// 1-based line and column of byte `offset` of `text` (for file:line:column messages).
std::pair<int64_t, int64_t> TextLineColumn(std::string_view text, size_t offset);

// 1-based line and column of the '{' that opens element `index` of the array held by the
// top-level object's member `key` ({"key": [{...}, {...}]}), or {0, 0} when there is no such
// element. nlohmann_json keeps no positions; strings are skipped and depth is counted, so a
// member of that name nested deeper, or inside a string, is not taken for it.
std::pair<int64_t, int64_t> TopLevelArrayElementLineColumn(std::string_view text,
                                                           std::string_view key, size_t index);

std::string JsonText(const nlohmann::json& j, int indent = -1);
std::string JsonText(const nlohmann::ordered_json& j, int indent = -1);

}  // namespace metro
