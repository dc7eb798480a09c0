// Reading a JSON document metro wrote (a report, a calibration) back into its typed model,
// with errors that point into the file: `r.json:41:17: sensors[0].type_a.mean: expected a
// number, found a string`. nlohmann_json keeps no positions, so the document keeps its text
// and the position of a value is found by walking the text along the value's path, only
// when an error is reported.
//
// Private to the library (and its tests): the public headers carry typed models, not JSON.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "metro/core/status.hpp"

namespace metro {

// One step of a path into a document: a member name or an array index.
using JsonPathStep = std::variant<std::string, size_t>;

// A parsed JSON file, kept with its text for positions.
class JsonDocument {
 public:
  // Parsed with ParseOrderedJsonText's limits (nesting depth, number range); syntax errors
  // at file:line:column.
  static Result<JsonDocument> Parse(std::string text, std::string file);

  const nlohmann::ordered_json& root() const { return root_; }
  const std::string& file() const { return file_; }
  const std::string& text() const { return text_; }

  // 1-based line and column of the value at `path`, or of its nearest ancestor present in the
  // text (the object a missing member belongs to).
  std::pair<int64_t, int64_t> LineColumnOf(const std::vector<JsonPathStep>& path) const;

 private:
  std::string text_;
  std::string file_;
  nlohmann::ordered_json root_;
};

// The byte offset in JSON `text` of the value at `path`, or of its nearest ancestor present
// (what JsonDocument::LineColumnOf reports as a line and column), found by walking the text:
// strings are skipped and brackets counted, so the text need not be parsed again.
size_t JsonValueOffset(std::string_view text, const std::vector<JsonPathStep>& path);

// `literal` a JSON string as written, from its opening quote: the offset in `literal` of
// byte `index` of the decoded string, an escape counting as the UTF-8 bytes it stands for
// (\n one, \u00e9 two, a surrogate pair four); past the end, the closing quote's offset.
size_t JsonStringByteOffset(std::string_view literal, size_t index);

// A cursor on one value of a JsonDocument. Reads never throw: a missing value or one of the
// wrong type records the FIRST error of the whole reading (shared by every cursor made from
// one root cursor) at the value's file:line:column with its path, and gives a default (0,
// false, "", empty), so a FromJson reads straight through and checks ok() once at the end.
// The document must outlive its cursors.
class JsonCursor {
 public:
  explicit JsonCursor(const JsonDocument& document);  // The root.

  // A member (absent: reading it fails as missing) and an array element.
  JsonCursor operator[](std::string_view key) const;
  JsonCursor operator[](size_t index) const;

  bool Has(std::string_view key) const;  // The member is present (even if null).
  bool Present() const { return value_ != nullptr; }
  bool IsNull() const;  // Present and null.
  bool IsObject() const;
  bool IsArray() const;
  bool IsNumber() const;
  bool IsString() const;
  size_t Size() const;                    // Elements or members; 0 for anything else.
  std::vector<std::string> Keys() const;  // Member names in order; fails unless an object.
  std::string Path() const;

  // Required values.
  double Number() const;
  int64_t Integer() const;  // A JSON integer, or a number with an integral value.
  bool Bool() const;
  std::string String() const;
  // null gives NaN (metro writes NaN as null).
  double NumberOrNaN() const;
  // null gives +infinity (metro writes infinite degrees of freedom as null).
  double NumberOrInfinity() const;
  // null or absent gives nullopt.
  std::optional<double> OptionalNumber() const;
  std::optional<int64_t> OptionalInteger() const;
  std::optional<std::string> OptionalString() const;
  // Arrays of a kind; each element is checked at its own position.
  std::vector<double> Numbers() const;
  std::vector<double> NumbersOrNaN() const;
  std::vector<int64_t> Integers() const;
  std::vector<std::string> Strings() const;

  // The value itself (a null value when absent), for a free-form echo.
  const nlohmann::ordered_json& Raw() const;

  // Records an error at this value: "<path>: expected <expected>, found <what is there>".
  void Fail(const std::string& expected) const;

  bool ok() const;
  // The first error of the reading. Requires !ok().
  Error error() const;

 private:
  struct State {
    const JsonDocument* document = nullptr;
    std::optional<Error> first;
  };
  JsonCursor(std::shared_ptr<State> state, const nlohmann::ordered_json* value,
             std::vector<JsonPathStep> path);
  // Checks the value is present and passes `is`; otherwise records "expected `what`".
  bool Expect(bool (*is)(const nlohmann::ordered_json&), const char* what) const;

  std::shared_ptr<State> state_;
  const nlohmann::ordered_json* value_ = nullptr;  // nullptr: absent.
  std::vector<JsonPathStep> path_;
};

// Reads JSON `text` (from `file`) into a typed model with `read` (its FromJsonValue): the
// model, or the first error of the reading (syntax, type, missing member) at its position.
template <typename T>
Result<T> ReadJsonText(std::string_view text, const std::string& file,
                       T (*read)(const JsonCursor&)) {
  Result<JsonDocument> document = JsonDocument::Parse(std::string(text), file);
  if (!document.ok()) return document.error();
  const JsonCursor root(document.value());
  T value = read(root);
  if (!root.ok()) return root.error();
  return value;
}

}  // namespace metro
