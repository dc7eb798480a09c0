#include "core/json_reader.hpp"

#include <fmt/format.h>

#include <cctype>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <utility>

#include "core/json_text.hpp"

namespace metro {
namespace {

using ordered_json = nlohmann::ordered_json;
constexpr size_t kNpos = std::string_view::npos;

// --- Positions: the text walked along a path (only when an error is reported).

size_t SkipSpace(std::string_view text, size_t i) {
  while (i < text.size() && std::isspace(static_cast<unsigned char>(text[i]))) ++i;
  return i;
}

// `i` at the opening quote; the offset after the closing one (or the end of the text).
size_t SkipString(std::string_view text, size_t i) {
  for (++i; i < text.size(); ++i) {
    if (text[i] == '\\') {
      ++i;
    } else if (text[i] == '"') {
      return i + 1;
    }
  }
  return text.size();
}

// `i` at the first character of a value; the offset just after it. Nested values are
// skipped by counting brackets outside strings, without recursion.
size_t SkipValue(std::string_view text, size_t i) {
  if (i >= text.size()) return text.size();
  if (text[i] == '"') return SkipString(text, i);
  if (text[i] != '{' && text[i] != '[') {
    while (i < text.size() && std::string_view(",]} \t\r\n").find(text[i]) == kNpos) ++i;
    return i;
  }
  int depth = 0;
  while (i < text.size()) {
    const char c = text[i];
    if (c == '"') {
      i = SkipString(text, i);
      continue;
    }
    if (c == '{' || c == '[') ++depth;
    if ((c == '}' || c == ']') && --depth == 0) return i + 1;
    ++i;
  }
  return text.size();
}

// The decoded JSON string token that starts at `i` ("" when it does not parse).
std::string DecodeString(std::string_view text, size_t i, size_t end) {
  try {
    return ordered_json::parse(text.substr(i, end - i)).get<std::string>();
  } catch (const nlohmann::json::exception&) {
    return {};
  }
}

// `i` at '{': the offset of the value of member `key`, or npos.
size_t FindMember(std::string_view text, size_t i, const std::string& key) {
  i = SkipSpace(text, i + 1);
  while (i < text.size() && text[i] == '"') {
    const size_t key_end = SkipString(text, i);
    const bool match = DecodeString(text, i, key_end) == key;
    i = SkipSpace(text, key_end);
    if (i >= text.size() || text[i] != ':') return kNpos;
    const size_t value = SkipSpace(text, i + 1);
    if (match) return value;
    i = SkipSpace(text, SkipValue(text, value));
    if (i >= text.size() || text[i] != ',') return kNpos;
    i = SkipSpace(text, i + 1);
  }
  return kNpos;
}

// `i` at '[': the offset of element `index`, or npos.
size_t FindElement(std::string_view text, size_t i, size_t index) {
  i = SkipSpace(text, i + 1);
  if (i >= text.size() || text[i] == ']') return kNpos;
  for (size_t k = 0;; ++k) {
    if (k == index) return i;
    i = SkipSpace(text, SkipValue(text, i));
    if (i >= text.size() || text[i] != ',') return kNpos;
    i = SkipSpace(text, i + 1);
  }
}

// What a value is, for "found ..." in messages.
std::string Describe(const ordered_json* value) {
  if (value == nullptr) return "nothing (the member is missing)";
  switch (value->type()) {
    case ordered_json::value_t::null:
      return "null";
    case ordered_json::value_t::boolean:
      return value->get<bool>() ? "true" : "false";
    case ordered_json::value_t::string: {
      std::string s = value->get<std::string>();
      if (s.size() > 40) s = s.substr(0, 37) + "...";
      return fmt::format("the string \"{}\"", s);
    }
    case ordered_json::value_t::number_integer:
    case ordered_json::value_t::number_unsigned:
    case ordered_json::value_t::number_float:
      return "the number " + JsonText(*value);
    case ordered_json::value_t::object:
      return "an object";
    case ordered_json::value_t::array:
      return "an array";
    default:
      return "an unsupported value";
  }
}

bool IsNumberValue(const ordered_json& v) { return v.is_number(); }
bool IsBoolValue(const ordered_json& v) { return v.is_boolean(); }
bool IsStringValue(const ordered_json& v) { return v.is_string(); }
bool IsArrayValue(const ordered_json& v) { return v.is_array(); }
bool IsObjectValue(const ordered_json& v) { return v.is_object(); }
bool IsIntegerValue(const ordered_json& v) {
  if (v.is_number_integer() || v.is_number_unsigned()) {
    return !v.is_number_unsigned() ||
           v.get<uint64_t>() <= static_cast<uint64_t>(std::numeric_limits<int64_t>::max());
  }
  if (!v.is_number_float()) return false;
  const double d = v.get<double>();
  return std::isfinite(d) && std::floor(d) == d && std::fabs(d) < 9.0e15;
}

// "sensors[0].quantities.gx_dps" ("(top level)" for the root).
std::string JsonPathText(const std::vector<JsonPathStep>& path) {
  if (path.empty()) return "(top level)";
  std::string out;
  for (const JsonPathStep& step : path) {
    if (const std::string* key = std::get_if<std::string>(&step)) {
      out += (out.empty() ? "" : ".") + *key;
    } else {
      out += fmt::format("[{}]", std::get<size_t>(step));
    }
  }
  return out;
}

const ordered_json& NullJson() {
  static const ordered_json null_value;
  return null_value;
}

}  // namespace

Result<JsonDocument> JsonDocument::Parse(std::string text, std::string file) {
  Result<ordered_json> root = ParseOrderedJsonText(text, file);
  if (!root.ok()) return root.error();
  JsonDocument document;
  document.text_ = std::move(text);
  document.file_ = std::move(file);
  document.root_ = std::move(root).value();
  return document;
}

std::pair<int64_t, int64_t> JsonDocument::LineColumnOf(
    const std::vector<JsonPathStep>& path) const {
  return TextLineColumn(text_, JsonValueOffset(text_, path));
}

size_t JsonValueOffset(std::string_view text, const std::vector<JsonPathStep>& path) {
  size_t at = SkipSpace(text, 0);
  for (const JsonPathStep& step : path) {
    if (at >= text.size()) break;
    size_t next = kNpos;
    if (const std::string* key = std::get_if<std::string>(&step)) {
      if (text[at] == '{') next = FindMember(text, at, *key);
    } else if (text[at] == '[') {
      next = FindElement(text, at, std::get<size_t>(step));
    }
    if (next == kNpos) break;
    at = next;
  }
  return at;
}

size_t JsonStringByteOffset(std::string_view literal, size_t index) {
  const auto hex4 = [&literal](size_t i) -> long {
    if (i + 4 > literal.size()) return -1;
    const std::string digits(literal.substr(i, 4));
    char* end = nullptr;
    const long v = std::strtol(digits.c_str(), &end, 16);
    return end == digits.c_str() + 4 ? v : -1;
  };
  size_t i = literal.empty() || literal[0] != '"' ? 0 : 1;
  size_t decoded = 0;
  while (i < literal.size() && literal[i] != '"' && decoded < index) {
    if (literal[i] != '\\' || i + 1 >= literal.size()) {
      ++i;
      ++decoded;
      continue;
    }
    if (literal[i + 1] != 'u') {
      i += 2;
      ++decoded;
      continue;
    }
    const long cp = hex4(i + 2);
    const long low = cp >= 0xD800 && cp < 0xDC00 && i + 7 < literal.size() &&
                             literal[i + 6] == '\\' && literal[i + 7] == 'u'
                         ? hex4(i + 8)
                         : -1;
    if (low >= 0xDC00 && low < 0xE000) {
      i += 12;  // A surrogate pair: one code point above U+FFFF, 4 bytes.
      decoded += 4;
    } else {
      i += 6;
      decoded += cp < 0x80 ? 1 : cp < 0x800 ? 2 : 3;
    }
  }
  return i;
}

JsonCursor::JsonCursor(const JsonDocument& document)
    : state_(std::make_shared<State>()), value_(&document.root()) {
  state_->document = &document;
}

JsonCursor::JsonCursor(std::shared_ptr<State> state, const ordered_json* value,
                       std::vector<JsonPathStep> path)
    : state_(std::move(state)), value_(value), path_(std::move(path)) {}

JsonCursor JsonCursor::operator[](std::string_view key) const {
  std::vector<JsonPathStep> path = path_;
  path.emplace_back(std::string(key));
  const ordered_json* child = nullptr;
  if (value_ != nullptr && value_->is_object()) {
    auto it = value_->find(std::string(key));
    if (it != value_->end()) child = &*it;
  }
  return JsonCursor(state_, child, std::move(path));
}

JsonCursor JsonCursor::operator[](size_t index) const {
  std::vector<JsonPathStep> path = path_;
  path.emplace_back(index);
  const ordered_json* child = nullptr;
  if (value_ != nullptr && value_->is_array() && index < value_->size()) {
    child = &(*value_)[index];
  }
  return JsonCursor(state_, child, std::move(path));
}

bool JsonCursor::Has(std::string_view key) const {
  return value_ != nullptr && value_->is_object() && value_->contains(std::string(key));
}

bool JsonCursor::IsNull() const { return value_ != nullptr && value_->is_null(); }
bool JsonCursor::IsObject() const { return value_ != nullptr && value_->is_object(); }
bool JsonCursor::IsArray() const { return value_ != nullptr && value_->is_array(); }
bool JsonCursor::IsNumber() const { return value_ != nullptr && value_->is_number(); }
bool JsonCursor::IsString() const { return value_ != nullptr && value_->is_string(); }

size_t JsonCursor::Size() const {
  return value_ != nullptr && (value_->is_array() || value_->is_object()) ? value_->size() : 0;
}

std::vector<std::string> JsonCursor::Keys() const {
  std::vector<std::string> keys;
  if (!Expect(IsObjectValue, "an object")) return keys;
  for (auto it = value_->begin(); it != value_->end(); ++it) keys.push_back(it.key());
  return keys;
}

std::string JsonCursor::Path() const { return JsonPathText(path_); }

void JsonCursor::Fail(const std::string& expected) const {
  if (state_->first) return;
  const auto [line, column] = state_->document->LineColumnOf(path_);
  state_->first = MakeError(
      state_->document->file(), line, column,
      fmt::format("{}: expected {}, found {}", JsonPathText(path_), expected, Describe(value_)));
}

bool JsonCursor::Expect(bool (*is)(const ordered_json&), const char* what) const {
  if (value_ != nullptr && is(*value_)) return true;
  Fail(what);
  return false;
}

double JsonCursor::Number() const {
  return Expect(IsNumberValue, "a number") ? value_->get<double>() : 0.0;
}

int64_t JsonCursor::Integer() const {
  if (!Expect(IsIntegerValue, "an integer")) return 0;
  return value_->is_number_float() ? static_cast<int64_t>(value_->get<double>())
                                   : value_->get<int64_t>();
}

bool JsonCursor::Bool() const {
  return Expect(IsBoolValue, "true or false") && value_->get<bool>();
}

std::string JsonCursor::String() const {
  return Expect(IsStringValue, "a string") ? value_->get<std::string>() : std::string();
}

double JsonCursor::NumberOrNaN() const {
  if (IsNull()) return std::numeric_limits<double>::quiet_NaN();
  return Expect(IsNumberValue, "a number or null") ? value_->get<double>() : 0.0;
}

double JsonCursor::NumberOrInfinity() const {
  if (IsNull()) return std::numeric_limits<double>::infinity();
  return Expect(IsNumberValue, "a number or null (infinite degrees of freedom)")
             ? value_->get<double>()
             : std::numeric_limits<double>::infinity();
}

std::optional<double> JsonCursor::OptionalNumber() const {
  if (value_ == nullptr || value_->is_null()) return std::nullopt;
  if (!Expect(IsNumberValue, "a number or null")) return std::nullopt;
  return value_->get<double>();
}

std::optional<int64_t> JsonCursor::OptionalInteger() const {
  if (value_ == nullptr || value_->is_null()) return std::nullopt;
  if (!Expect(IsIntegerValue, "an integer or null")) return std::nullopt;
  return Integer();
}

std::optional<std::string> JsonCursor::OptionalString() const {
  if (value_ == nullptr || value_->is_null()) return std::nullopt;
  if (!Expect(IsStringValue, "a string or null")) return std::nullopt;
  return value_->get<std::string>();
}

std::vector<double> JsonCursor::Numbers() const {
  std::vector<double> out;
  if (!Expect(IsArrayValue, "an array of numbers")) return out;
  out.reserve(value_->size());
  for (size_t i = 0; i < value_->size(); ++i) out.push_back((*this)[i].Number());
  return out;
}

std::vector<double> JsonCursor::NumbersOrNaN() const {
  std::vector<double> out;
  if (!Expect(IsArrayValue, "an array of numbers or nulls")) return out;
  out.reserve(value_->size());
  for (size_t i = 0; i < value_->size(); ++i) out.push_back((*this)[i].NumberOrNaN());
  return out;
}

std::vector<int64_t> JsonCursor::Integers() const {
  std::vector<int64_t> out;
  if (!Expect(IsArrayValue, "an array of integers")) return out;
  out.reserve(value_->size());
  for (size_t i = 0; i < value_->size(); ++i) out.push_back((*this)[i].Integer());
  return out;
}

std::vector<std::string> JsonCursor::Strings() const {
  std::vector<std::string> out;
  if (!Expect(IsArrayValue, "an array of strings")) return out;
  out.reserve(value_->size());
  for (size_t i = 0; i < value_->size(); ++i) out.push_back((*this)[i].String());
  return out;
}

const ordered_json& JsonCursor::Raw() const { return value_ != nullptr ? *value_ : NullJson(); }

bool JsonCursor::ok() const { return !state_->first.has_value(); }

Error JsonCursor::error() const {
  METRO_CHECK(state_->first.has_value());
  return *state_->first;
}

}  // namespace metro
