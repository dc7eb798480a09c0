// YAML text from other tools' files (Kalibr's imu.yaml / imu-chain yaml, OpenVINS's
// kalibr_imu_chain.yaml), parsed with libyaml (Debian libyaml-dev) into a tree that keeps the
// 1-based line and column of every node, so a reader can say `imu.yaml:12:7: ...` about any
// value. Private to the library and its tests: public headers carry typed models.
//
// Accepted: YAML 1.1 block and flow mappings and sequences of scalars, `# comments`, one
// document; OpenCV FileStorage's first line `%YAML:1.0` (which is not a YAML directive) is read
// as a comment. Refused with file:line:column: syntax errors, anchors and aliases, tags other
// than the core ones, more than one document, nesting deeper than kMaxYamlDepth.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "metro/core/status.hpp"

namespace metro {

inline constexpr int kMaxYamlDepth = 32;

struct YamlNode {
  enum class Kind { kScalar, kSequence, kMapping };
  Kind kind = Kind::kScalar;
  std::string scalar;  // kScalar: the text as written (quotes removed).
  bool quoted = false;
  std::vector<YamlNode> items;                         // kSequence
  std::vector<std::pair<YamlNode, YamlNode>> members;  // kMapping: key node, value node
  int64_t line = 0, column = 0;                        // 1-based start of the node

  bool IsScalar() const { return kind == Kind::kScalar; }
  bool IsSequence() const { return kind == Kind::kSequence; }
  bool IsMapping() const { return kind == Kind::kMapping; }
  // The value of member `key` of a mapping, or nullptr.
  const YamlNode* Find(std::string_view key) const;
  // The scalar as a finite double (YAML 1.1 numbers: 1, -2.5, 1e-3, .5); nullopt otherwise.
  std::optional<double> Number() const;
  // "a mapping", "a sequence", "the string \"x\"", "the number 3": for messages.
  std::string Describe() const;
};

// Parses `text` (named `file` in errors). An empty document is an empty mapping.
Result<YamlNode> ParseYaml(std::string_view text, const std::string& file);

}  // namespace metro
