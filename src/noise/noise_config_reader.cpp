#include "metro/noise/noise_config_reader.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <map>

#include "core/json_reader.hpp"
#include "core/nearest_name.hpp"
#include "noise/noise_export_formats.hpp"

namespace metro {
namespace {

bool IsKeyChar(char c) {
  return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '_' || c == '.' || c == '-';
}

// A finite number filling all of `s`.
std::optional<double> ParseNumber(std::string_view s) {
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  double v = 0.0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (ec != std::errc() || end != s.data() + s.size() || !std::isfinite(v)) return std::nullopt;
  return v;
}

std::string_view Trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return s;
}

// The text before a comment: a '#' at the start or after a blank, outside quotes.
std::string_view StripComment(std::string_view s) {
  char quote = 0;
  for (size_t i = 0; i < s.size(); ++i) {
    const char c = s[i];
    if (quote != 0) {
      if (c == quote) quote = 0;
    } else if (c == '"' || c == '\'') {
      quote = c;
    } else if (c == '#' && (i == 0 || s[i - 1] == ' ' || s[i - 1] == '\t')) {
      return s.substr(0, i);
    }
  }
  return s;
}

NoiseConfigEntry Entry(std::string key, std::string_view value, int64_t key_line,
                       int64_t key_column, int64_t column) {
  NoiseConfigEntry e;
  e.key = std::move(key);
  e.text = std::string(value);
  if (e.text.size() >= 2 && (e.text.front() == '"' || e.text.front() == '\'') &&
      e.text.back() == e.text.front()) {
    e.text = e.text.substr(1, e.text.size() - 2);
  } else {
    e.number = ParseNumber(value);
  }
  e.key_line = e.line = key_line;
  e.key_column = key_column;
  e.column = column;
  return e;
}

// `[a, b, c]` starting at `col0` (1-based column of '['): entries key[i].
Status FlowList(const std::string& file, const std::string& key, std::string_view v, int64_t line,
                int64_t key_column, int64_t col0, std::vector<NoiseConfigEntry>* out) {
  if (v.back() != ']') {
    return MakeError(file, line, col0 + static_cast<int64_t>(v.size()) - 1,
                     "expected ']' closing the list");
  }
  size_t start = 1;
  for (size_t i = 0; start < v.size(); ++i) {
    size_t end = v.find(',', start);
    if (end == std::string_view::npos) end = v.size() - 1;
    std::string_view item = v.substr(start, end - start);
    const size_t lead = item.find_first_not_of(" \t");
    item = Trim(item);
    if (item.empty()) {
      return MakeError(file, line, col0 + static_cast<int64_t>(start),
                       "expected a number between the commas of the list");
    }
    out->push_back(Entry(fmt::format("{}[{}]", key, i), item, line, key_column,
                         col0 + static_cast<int64_t>(start + lead)));
    start = end + 1;
  }
  return {};
}

// One `key: value` or `param set NAME VALUE` line; `parents` are the open mappings (indent,
// flattened key).
Status ReadLine(const std::string& file, std::string_view raw, int64_t line,
                std::vector<std::pair<size_t, std::string>>* parents,
                std::vector<NoiseConfigEntry>* out) {
  const std::string_view body = StripComment(raw);
  const size_t indent = body.find_first_not_of(" \t");
  if (indent == std::string_view::npos) return {};
  std::string_view s = Trim(body);
  if (s.rfind("%YAML", 0) == 0 || s == "---") return {};
  const int64_t key_col = static_cast<int64_t>(indent) + 1;
  if (s.rfind("param set ", 0) == 0) {
    const std::string_view rest = s.substr(10);
    const size_t sp = rest.find_first_of(" \t");
    if (sp == std::string_view::npos) {
      return MakeError(file, line, key_col, "expected `param set NAME VALUE`");
    }
    const std::string_view value = Trim(rest.substr(sp));
    out->push_back(Entry(std::string(rest.substr(0, sp)), value, line, key_col + 10,
                         static_cast<int64_t>(value.data() - raw.data()) + 1));
    return {};
  }
  const size_t colon = s.find(':');
  if (colon == 0 || colon == std::string_view::npos ||
      !std::all_of(s.begin(), s.begin() + static_cast<std::ptrdiff_t>(colon), IsKeyChar)) {
    return MakeError(file, line, key_col,
                     "expected `key: value` (YAML), `param set NAME VALUE` (PX4) or a # comment");
  }
  while (!parents->empty() && parents->back().first >= indent) parents->pop_back();
  std::string key(s.substr(0, colon));
  const std::string prefix = parents->empty() ? "" : parents->back().second + ".";
  const std::string_view value = Trim(s.substr(colon + 1));
  if (value.empty()) {  // A mapping: its members follow, indented.
    parents->push_back({indent, prefix + key});
    return {};
  }
  const int64_t value_col = static_cast<int64_t>(value.data() - raw.data()) + 1;
  if (value.front() == '[') {
    return FlowList(file, prefix + key, value, line, key_col, value_col, out);
  }
  out->push_back(Entry(prefix + key, value, line, key_col, value_col));
  return {};
}

Result<NoiseConfigFile> ReadText(std::string_view text, const std::string& file) {
  NoiseConfigFile config;
  config.file = file;
  std::vector<std::pair<size_t, std::string>> parents;
  int64_t line = 0;
  size_t pos = 0;
  while (pos <= text.size()) {
    size_t end = text.find('\n', pos);
    if (end == std::string_view::npos) end = text.size();
    std::string_view raw = text.substr(pos, end - pos);
    if (!raw.empty() && raw.back() == '\r') raw.remove_suffix(1);
    ++line;
    if (Status s = ReadLine(file, raw, line, &parents, &config.entries); !s.ok()) return s.error();
    pos = end + 1;
  }
  return config;
}

void Flatten(const JsonDocument& doc, const nlohmann::ordered_json& v, const std::string& key,
             std::vector<JsonPathStep>* path, std::vector<NoiseConfigEntry>* out) {
  if (v.is_object()) {
    for (auto it = v.begin(); it != v.end(); ++it) {
      if (path->empty() && it.key() == "metro_convention") continue;
      path->push_back(it.key());
      Flatten(doc, it.value(), key.empty() ? it.key() : key + "." + it.key(), path, out);
      path->pop_back();
    }
    return;
  }
  if (v.is_array()) {
    for (size_t i = 0; i < v.size(); ++i) {
      path->push_back(i);
      Flatten(doc, v[i], fmt::format("{}[{}]", key, i), path, out);
      path->pop_back();
    }
    return;
  }
  NoiseConfigEntry e;
  e.key = key;
  if (v.is_number()) e.number = v.get<double>();
  e.text = v.is_string() ? v.get<std::string>() : v.dump();
  const auto [line, column] = doc.LineColumnOf(*path);
  e.key_line = e.line = line;
  e.key_column = e.column = column;
  out->push_back(std::move(e));
}

std::vector<std::string> KnownKeys(NoiseExportFormat format) {
  std::vector<std::string> keys;
  for (const ExportMetaKey& m : ExportMetaKeys(format)) keys.push_back(m.key);
  for (const ExportKeyGroup& g : ExportKeyGroups(format)) {
    for (const ExportKeySpec& k : g.keys) keys.push_back(k.key);
  }
  return keys;
}

Error At(const NoiseConfigFile& c, const NoiseConfigEntry& e, bool key, std::string message) {
  return MakeError(c.file, key ? e.key_line : e.line, key ? e.key_column : e.column,
                   std::move(message));
}

// Every entry known, once, of the right kind; every key present. The entries by key.
Result<std::map<std::string, const NoiseConfigEntry*>> CheckKeys(const NoiseConfigFile& c,
                                                                 NoiseExportFormat format) {
  const std::vector<std::string> known = KnownKeys(format);
  std::map<std::string, const NoiseConfigEntry*> by_key;
  std::map<std::string, ExportMetaKind> meta;
  for (const ExportMetaKey& m : ExportMetaKeys(format)) meta[m.key] = m.kind;
  const char* name = NoiseExportFormatName(format);
  for (const NoiseConfigEntry& e : c.entries) {
    if (std::find(known.begin(), known.end(), e.key) == known.end()) {
      return At(c, e, true,
                fmt::format("unknown key '{}' in a {} noise file; expected one of {} "
                            "(nearest: {})",
                            e.key, name, fmt::join(known, ", "), Nearest(e.key, known)));
    }
    if (!by_key.emplace(e.key, &e).second) {
      return At(c, e, true, fmt::format("'{}' is given twice; expected each key once", e.key));
    }
    const auto m = meta.find(e.key);
    if (m != meta.end() && m->second == ExportMetaKind::kTopic) continue;
    if (!e.number) {
      return At(c, e, false, fmt::format("{}: expected a number, found '{}'", e.key, e.text));
    }
    const double v = *e.number;
    if (m != meta.end() && m->second == ExportMetaKind::kZero && v != 0.0) {
      return At(c, e, false,
                fmt::format("{}: expected 0 (an off-diagonal covariance; metro "
                            "compares diagonal covariances), found {}",
                            e.key, e.text));
    }
    if (m != meta.end() && m->second == ExportMetaKind::kRate && !(v > 0.0)) {
      return At(c, e, false,
                fmt::format("{}: expected a positive rate in Hz, found {}", e.key, e.text));
    }
    if (v < 0.0) {
      return At(c, e, false,
                fmt::format("{}: expected a non-negative noise value (a standard "
                            "deviation or variance), found {}",
                            e.key, e.text));
    }
  }
  for (const std::string& k : known) {
    if (by_key.count(k) != 0) continue;
    const size_t dot = k.find('.');
    int64_t line = 1, column = 1;  // The parent mapping's key when it is there.
    for (const NoiseConfigEntry& e : c.entries) {
      if (dot != std::string::npos && e.key.rfind(k.substr(0, dot + 1), 0) == 0) {
        line = e.key_line;
        column = e.key_column;
        break;
      }
    }
    return MakeError(
        c.file, line, column,
        fmt::format("missing key '{}'; a {} noise file holds {}", k, name, fmt::join(known, ", ")));
  }
  return by_key;
}

}  // namespace

Result<NoiseConfigFile> ReadNoiseConfig(std::string_view text, const std::string& file) {
  const size_t first = text.find_first_not_of(" \t\r\n");
  if (first == std::string_view::npos || text[first] != '{') return ReadText(text, file);
  Result<JsonDocument> doc = JsonDocument::Parse(std::string(text), file);
  if (!doc.ok()) return doc.error();
  NoiseConfigFile config;
  config.file = file;
  std::vector<JsonPathStep> path;
  Flatten(doc.value(), doc.value().root(), "", &path, &config.entries);
  return config;
}

Result<NoiseExportFormat> DetectNoiseConfigFormat(const NoiseConfigFile& config) {
  for (const NoiseConfigEntry& e : config.entries) {
    for (NoiseExportFormat f : kAllNoiseExportFormats) {
      const std::vector<std::string> keys = KnownKeys(f);
      if (std::find(keys.begin(), keys.end(), e.key) != keys.end()) return f;
    }
  }
  std::string examples;
  for (NoiseExportFormat f : kAllNoiseExportFormats) {
    examples += fmt::format("{}{} ({})", examples.empty() ? "" : ", ", NoiseExportFormatName(f),
                            ExportKeyGroups(f).front().keys.front().key);
  }
  return MakeError(config.file, 1, 1,
                   "no key of a known noise file; expected the keys of one of: " + examples);
}

Result<NoiseComparison> CompareNoiseConfig(const NoiseConfigFile& config,
                                           const NoiseExportInput& input,
                                           const NoiseExportOptions& options) {
  Result<std::map<std::string, const NoiseConfigEntry*>> by_key = CheckKeys(config, options.format);
  if (!by_key.ok()) return by_key.error();
  Result<NoiseExport> expected = ExportedNoiseValues(input, options);
  if (!expected.ok()) return expected.error();
  NoiseComparison out;
  out.format = options.format;
  for (const ExportedNoiseValue& v : expected.value().values) {
    NoiseComparisonRow r;
    r.key = v.key;
    r.unit = v.unit;
    r.file_value = *by_key.value().at(v.key)->number;
    r.measured = v.value;
    r.u_measured = v.u;
    r.ratio = r.file_value / r.measured;
    r.e_n = (r.file_value - r.measured) / (out.k * v.u);  // U_x = 0, U_X = k u(X).
    out.rows.push_back(r);
  }
  return out;
}

std::string NoiseComparisonTable(const NoiseComparison& c) {
  std::string s = fmt::format("{:<36} {:>14} {:>14} {:>10} {:>10} {:>8}  unit\n", "key", "file",
                              "measured", "u", "ratio", "E_n");
  for (const NoiseComparisonRow& r : c.rows) {
    s += fmt::format("{:<36} {:>14.6g} {:>14.6g} {:>10.2g} {:>10.4g} {:>8.3g}  {}\n", r.key,
                     r.file_value, r.measured, r.u_measured, r.ratio, r.e_n, r.unit);
  }
  s += fmt::format(
      "E_n = (file - measured) / sqrt(U_file^2 + U_measured^2), U_measured = {:g} u, U_file = 0 "
      "(ISO 13528:2015 9.7); |E_n| <= 1: the file agrees with the measurement\n",
      c.k);
  return s;
}

}  // namespace metro
