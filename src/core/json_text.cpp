#include "core/json_text.hpp"

#include <fmt/format.h>

#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <string>

namespace metro {
std::pair<int64_t, int64_t> TextLineColumn(std::string_view text, size_t offset) {
  int64_t line = 1;
  int64_t column = 1;
  for (size_t i = 0; i < offset && i < text.size(); ++i) {
    if (text[i] == '\n') {
      ++line;
      column = 1;
    } else {
      ++column;
    }
  }
  return {line, column};
}

namespace {

// Calls visit(i) for each byte of `text` outside JSON strings, in order, until it returns
// true; returns that offset, or npos. visit may move i forward past a token it has read.
template <typename Visit>
size_t FirstOutsideStrings(std::string_view text, Visit visit) {
  bool in_string = false;
  for (size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (in_string) {
      if (c == '\\') {
        ++i;
      } else if (c == '"') {
        in_string = false;
      }
    } else if (c == '"') {
      in_string = true;
    } else if (visit(i)) {
      return i;
    }
  }
  return std::string_view::npos;
}

// The offset of the first '[' or '{' that opens level kMaxJsonDepth + 1, or npos. One pass,
// no recursion.
size_t TooDeepAt(std::string_view text) {
  int depth = 0;
  return FirstOutsideStrings(text, [&](size_t& i) {
    const char c = text[i];
    if (c == '[' || c == '{') return ++depth > kMaxJsonDepth;
    if ((c == ']' || c == '}') && depth > 0) --depth;
    return false;
  });
}

// The offset of the comma that gives an object its (kMaxJsonObjectMembers + 1)-th member, or
// npos. nlohmann::ordered_json keeps an object's members in a vector and looks each new key
// up in it, so reading an object costs the square of its members: bounded here, the parse
// stays linear in the text. One pass, no recursion (depth is at most kMaxJsonDepth).
size_t TooManyMembersAt(std::string_view text) {
  int depth = 0;
  bool object[kMaxJsonDepth + 2] = {};
  size_t members[kMaxJsonDepth + 2] = {};
  return FirstOutsideStrings(text, [&](size_t& i) {
    const char c = text[i];
    if (c == '[' || c == '{') {
      if (depth + 1 < kMaxJsonDepth + 2) {
        ++depth;
        object[depth] = c == '{';
        members[depth] = 1;
      }
    } else if ((c == ']' || c == '}') && depth > 0) {
      --depth;
    } else if (c == ',' && depth > 0 && object[depth]) {
      return ++members[depth] > kMaxJsonObjectMembers;
    }
    return false;
  });
}

// The offset of the first number too large for a double, which nlohmann::json refuses with
// out_of_range 406 and no position; npos when there is none.
size_t OverflowingNumberAt(std::string_view text) {
  return FirstOutsideStrings(text, [&](size_t& i) {
    const char c = text[i];
    if (c != '-' && (c < '0' || c > '9')) return false;
    size_t end = i;
    while (end < text.size() &&
           std::string_view("+-.0123456789eE").find(text[end]) != std::string_view::npos) {
      ++end;
    }
    const std::string token(text.substr(i, end - i));
    errno = 0;
    const double value = std::strtod(token.c_str(), nullptr);
    if (errno == ERANGE && (value == HUGE_VAL || value == -HUGE_VAL)) return true;
    i = end - 1;
    return false;
  });
}

template <class Json>
Result<Json> Parse(std::string_view text, const std::string& path) {
  if (const size_t at = TooDeepAt(text); at != std::string_view::npos) {
    const auto [line, column] = TextLineColumn(text, at);
    return MakeError(path, line, column,
                     fmt::format("JSON nested deeper than {} levels; metro's files nest a few "
                                 "levels (docs/report-schema.md, docs/budget-format.md)",
                                 kMaxJsonDepth));
  }
  if (const size_t at = TooManyMembersAt(text); at != std::string_view::npos) {
    const auto [line, column] = TextLineColumn(text, at);
    return MakeError(path, line, column,
                     fmt::format("a JSON object with more than {} members; metro's files hold "
                                 "at most a few hundred keys in an object, and many items in "
                                 "arrays (docs/report-schema.md, docs/budget-format.md)",
                                 kMaxJsonObjectMembers));
  }
  try {
    return Json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    // e.byte is the 1-based position of the byte the parser stopped at.
    const auto [line, column] = TextLineColumn(text, e.byte > 0 ? e.byte - 1 : 0);
    return MakeError(path, line, column, std::string("invalid JSON: ") + e.what());
  } catch (const nlohmann::json::exception& e) {
    // out_of_range 406: a number beyond a double's range (1e999); it carries no position.
    const size_t at = OverflowingNumberAt(text);
    if (at == std::string_view::npos) return MakeError(path + ": invalid JSON: " + e.what());
    const auto [line, column] = TextLineColumn(text, at);
    return MakeError(path, line, column,
                     std::string("invalid JSON: ") + e.what() +
                         "; numbers must be finite doubles (at most about 1.8e308)");
  }
}

// The key of the member whose ':' is at `colon`: the JSON string just before it, or "" when
// there is none (only the text is read; escapes inside keys are not decoded).
std::string_view KeyBefore(std::string_view text, size_t colon) {
  size_t end = colon;
  while (end > 0 && std::isspace(static_cast<unsigned char>(text[end - 1]))) --end;
  if (end == 0 || text[end - 1] != '"') return {};
  const size_t close = end - 1;
  size_t open = close;
  while (open > 0) {
    --open;
    if (text[open] == '"' && (open == 0 || text[open - 1] != '\\')) {
      return text.substr(open + 1, close - open - 1);
    }
  }
  return {};
}

}  // namespace

Result<nlohmann::json> ParseJsonText(std::string_view text, const std::string& path) {
  return Parse<nlohmann::json>(text, path);
}

Result<nlohmann::ordered_json> ParseOrderedJsonText(std::string_view text,
                                                    const std::string& path) {
  return Parse<nlohmann::ordered_json>(text, path);
}

std::pair<int64_t, int64_t> TopLevelArrayElementLineColumn(std::string_view text,
                                                           std::string_view key, size_t index) {
  int depth = 0;
  bool key_seen = false;  // The last member key at depth 1 was `key`; its value comes next.
  bool in_array = false;  // Inside `key`'s array (depth 2).
  bool found = false;
  size_t seen = 0;
  const size_t at = FirstOutsideStrings(text, [&](size_t& i) {
    const char c = text[i];
    if (std::isspace(static_cast<unsigned char>(c))) return false;
    if (c == ':' && depth == 1 && !in_array) {
      key_seen = KeyBefore(text, i) == key;
      return false;
    }
    const bool opens_array = key_seen && depth == 1 && c == '[';
    key_seen = false;
    if (c == '[' || c == '{') {
      if (in_array && depth == 2 && c == '{' && seen++ == index) {
        found = true;
        return true;
      }
      ++depth;
      in_array = in_array || opens_array;
    } else if (c == ']' || c == '}') {
      if (in_array && depth == 2) return true;  // The array ended before element `index`.
      --depth;
    }
    return false;
  });
  if (!found || at == std::string_view::npos) return {0, 0};
  return TextLineColumn(text, at);
}

std::string JsonText(const nlohmann::json& j, int indent) {
  return j.dump(indent, ' ', false, nlohmann::json::error_handler_t::replace);
}

std::string JsonText(const nlohmann::ordered_json& j, int indent) {
  return j.dump(indent, ' ', false, nlohmann::ordered_json::error_handler_t::replace);
}

}  // namespace metro
