#include "core/yaml_document.hpp"

#include <fmt/format.h>
#include <yaml.h>

#include <cmath>
#include <cstdlib>
#include <memory>

namespace metro {
namespace {

// The parser and its current event, released on every path.
class EventReader {
 public:
  EventReader(std::string_view text) {
    yaml_parser_initialize(&parser_);
    yaml_parser_set_input_string(&parser_, reinterpret_cast<const unsigned char*>(text.data()),
                                 text.size());
  }
  ~EventReader() {
    if (has_event_) yaml_event_delete(&event_);
    yaml_parser_delete(&parser_);
  }
  EventReader(const EventReader&) = delete;
  EventReader& operator=(const EventReader&) = delete;

  // The next event, or an error at the parser's mark.
  Status Next(const std::string& file) {
    if (has_event_) yaml_event_delete(&event_);
    has_event_ = false;
    if (!yaml_parser_parse(&parser_, &event_)) {
      const yaml_mark_t& m = parser_.problem_mark;
      return MakeError(file, static_cast<int64_t>(m.line) + 1, static_cast<int64_t>(m.column) + 1,
                       fmt::format("invalid YAML: {}{}", parser_.problem ? parser_.problem : "",
                                   parser_.context ? fmt::format(" ({})", parser_.context) : ""));
    }
    has_event_ = true;
    return {};
  }
  const yaml_event_t& event() const { return event_; }

 private:
  yaml_parser_t parser_;
  yaml_event_t event_;
  bool has_event_ = false;
};

int64_t Line(const yaml_event_t& e) { return static_cast<int64_t>(e.start_mark.line) + 1; }
int64_t Column(const yaml_event_t& e) { return static_cast<int64_t>(e.start_mark.column) + 1; }

// The node whose first event `r` holds; reads through its end event.
Result<YamlNode> ReadNode(EventReader& r, const std::string& file, int depth) {
  const yaml_event_t& e = r.event();
  YamlNode node;
  node.line = Line(e);
  node.column = Column(e);
  if (depth > kMaxYamlDepth) {
    return MakeError(file, node.line, node.column,
                     fmt::format("YAML nested deeper than {} levels", kMaxYamlDepth));
  }
  const auto anchored = [&](const yaml_char_t* anchor) -> Status {
    if (anchor != nullptr) {
      return MakeError(file, node.line, node.column,
                       "a YAML anchor (&name): expected plain values (anchors and aliases are "
                       "not read)");
    }
    return {};
  };
  switch (e.type) {
    case YAML_SCALAR_EVENT: {
      if (Status s = anchored(e.data.scalar.anchor); !s.ok()) return s.error();
      node.kind = YamlNode::Kind::kScalar;
      node.scalar.assign(reinterpret_cast<const char*>(e.data.scalar.value), e.data.scalar.length);
      node.quoted = e.data.scalar.style == YAML_SINGLE_QUOTED_SCALAR_STYLE ||
                    e.data.scalar.style == YAML_DOUBLE_QUOTED_SCALAR_STYLE;
      return node;
    }
    case YAML_SEQUENCE_START_EVENT:
    case YAML_MAPPING_START_EVENT: {
      const bool mapping = e.type == YAML_MAPPING_START_EVENT;
      if (Status s = anchored(mapping ? e.data.mapping_start.anchor : e.data.sequence_start.anchor);
          !s.ok()) {
        return s.error();
      }
      node.kind = mapping ? YamlNode::Kind::kMapping : YamlNode::Kind::kSequence;
      const yaml_event_type_t end = mapping ? YAML_MAPPING_END_EVENT : YAML_SEQUENCE_END_EVENT;
      while (true) {
        if (Status s = r.Next(file); !s.ok()) return s.error();
        if (r.event().type == end) return node;
        Result<YamlNode> first = ReadNode(r, file, depth + 1);
        if (!first.ok()) return first.error();
        if (!mapping) {
          node.items.push_back(std::move(first.value()));
          continue;
        }
        if (Status s = r.Next(file); !s.ok()) return s.error();
        Result<YamlNode> value = ReadNode(r, file, depth + 1);
        if (!value.ok()) return value.error();
        node.members.emplace_back(std::move(first.value()), std::move(value.value()));
      }
    }
    case YAML_ALIAS_EVENT:
      return MakeError(file, node.line, node.column,
                       "a YAML alias (*name): expected plain values (aliases are not read)");
    default:
      return MakeError(file, node.line, node.column, "expected a YAML value");
  }
}

// OpenCV FileStorage writes `%YAML:1.0` on the first line, which libyaml refuses as a
// directive: blanked to a comment of the same length, so positions stay.
std::string WithoutOpenCvHeader(std::string_view text) {
  std::string out(text);
  if (out.rfind("%YAML:", 0) == 0) out[0] = '#';
  return out;
}

}  // namespace

const YamlNode* YamlNode::Find(std::string_view key) const {
  for (const auto& [k, v] : members) {
    if (k.IsScalar() && k.scalar == key) return &v;
  }
  return nullptr;
}

std::optional<double> YamlNode::Number() const {
  if (!IsScalar() || quoted || scalar.empty()) return std::nullopt;
  const char* begin = scalar.c_str();
  char* end = nullptr;
  const double v = std::strtod(begin, &end);
  if (end != begin + scalar.size() || !std::isfinite(v)) return std::nullopt;
  // strtod also reads hexadecimal and "infinity"; YAML numbers are decimal.
  for (char c : scalar) {
    if (c == 'x' || c == 'X' || c == 'n' || c == 'N') return std::nullopt;
  }
  return v;
}

std::string YamlNode::Describe() const {
  switch (kind) {
    case Kind::kMapping:
      return "a mapping";
    case Kind::kSequence:
      return fmt::format("a sequence of {}", items.size());
    case Kind::kScalar:
      break;
  }
  if (Number()) return fmt::format("the number {}", scalar);
  return fmt::format("the string \"{}\"", scalar);
}

Result<YamlNode> ParseYaml(std::string_view text, const std::string& file) {
  const std::string own = WithoutOpenCvHeader(text);
  EventReader r(own);
  YamlNode root;
  root.kind = YamlNode::Kind::kMapping;
  root.line = 1;
  root.column = 1;
  bool have_document = false;
  while (true) {
    if (Status s = r.Next(file); !s.ok()) return s.error();
    const yaml_event_t& e = r.event();
    if (e.type == YAML_STREAM_END_EVENT) return root;
    if (e.type == YAML_STREAM_START_EVENT || e.type == YAML_DOCUMENT_END_EVENT) continue;
    if (e.type == YAML_DOCUMENT_START_EVENT) {
      if (have_document) {
        return MakeError(file, Line(e), Column(e), "a second YAML document: expected one");
      }
      have_document = true;
      continue;
    }
    Result<YamlNode> node = ReadNode(r, file, 0);
    if (!node.ok()) return node.error();
    root = std::move(node.value());
  }
}

}  // namespace metro
