// PlanCsv runs these stages, in this order (the dialects: docs/formats.md):
//
//   1 framing   DetectFraming                   byte-order mark, line ends, delimiter
//   2 header    ReadHeader, ApplyRateMetadata   header line, named format, metadata rate
//   3 columns   NameColumns, ColumnName,        canonical names, roles and slots, how rows
//               AssignRoles, CheckTiming,       are timed, raw-count scales, the time
//               PlanRawScales,                  column's written resolution
//               CheckTimeResolution
//   4 footer    FindDataEnd                     a spreadsheet footer
#include "io/csv_plan.hpp"

#include <fast_float/fast_float.h>
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>

namespace metro::internal {
namespace {

// Bytes of the file looked at to decide its dialect and header.
constexpr size_t kHeadBytes = size_t{64} << 10;
// Lines looked at (at most) to decide the delimiter and find the header.
constexpr size_t kHeadLines = 40;

std::string Lower(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

std::string_view TrimView(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return s;
}

std::string Printable(std::string_view s) {
  std::string out(s.substr(0, 60));
  for (char& c : out) {
    if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) == 0x7F) c = '?';
  }
  if (s.size() > 60) out += "...";
  return out;
}

// One line of the file's head.
struct HeadLine {
  size_t begin = 0;  // Offset in the file.
  size_t next = 0;   // Offset of the next line.
  int64_t number = 0;
  std::string_view text;  // Without its line end.
};

// The first lines of the file from `from`, split on `line_end`.
std::vector<HeadLine> HeadLines(const MappedFile& file, size_t from, char line_end,
                                size_t max_lines) {
  std::vector<HeadLine> lines;
  const size_t limit = std::min(file.size(), from + kHeadBytes);
  size_t pos = from;
  int64_t number = 0;
  while (pos < file.size() && lines.size() < max_lines) {
    const char* nl =
        static_cast<const char*>(std::memchr(file.data() + pos, line_end, file.size() - pos));
    const size_t le = nl != nullptr ? static_cast<size_t>(nl - file.data()) : file.size();
    HeadLine line;
    line.begin = pos;
    line.next = nl != nullptr ? le + 1 : file.size();
    line.number = ++number;
    size_t e = le;
    if (line_end == '\n' && e > pos && file.data()[e - 1] == '\r') --e;
    line.text = std::string_view(file.data() + pos, e - pos);
    lines.push_back(line);
    pos = line.next;
    if (pos > limit) break;
  }
  return lines;
}

bool IsBlank(std::string_view s) { return TrimView(s).empty(); }
bool IsComment(std::string_view s) {
  s = TrimView(s);
  return !s.empty() && s.front() == '#';
}

// A field that parses as a finite number with `decimal_point` (E-notation included).
bool IsNumber(std::string_view field, char decimal_point) {
  field = TrimView(field);
  if (!field.empty() && field.front() == '"' && field.size() >= 2 && field.back() == '"') {
    field = field.substr(1, field.size() - 2);
  }
  if (!field.empty() && field.front() == '+') field.remove_prefix(1);
  if (field.empty()) return false;
  double v;
  const fast_float::parse_options options(fast_float::chars_format::general, decimal_point);
  const auto r =
      fast_float::from_chars_advanced(field.data(), field.data() + field.size(), v, options);
  return r.ec == std::errc() && r.ptr == field.data() + field.size() && std::isfinite(v);
}

// True if every field of the line is a number: a data row, not a header.
bool IsDataLine(std::string_view line, char delimiter, char decimal_point) {
  const std::vector<std::string> fields = SplitFields(line, delimiter);
  if (fields.empty()) return false;
  return std::all_of(fields.begin(), fields.end(),
                     [&](const std::string& f) { return IsNumber(f, decimal_point); });
}

size_t CountOutsideQuotes(std::string_view line, char c) {
  size_t n = 0;
  bool quoted = false;
  for (char x : line) {
    if (x == '"') quoted = !quoted;
    if (!quoted && x == c) ++n;
  }
  return n;
}

// Stage 1: delimiter and decimal point, from the lines that are not blank or comments.
void DetectDelimiter(const std::vector<HeadLine>& lines, InputDialect* dialect) {
  std::vector<std::string_view> texts;
  for (const HeadLine& l : lines) {
    if (!IsBlank(l.text) && !IsComment(l.text)) texts.push_back(l.text);
  }
  // Score: how many lines share the commonest non-zero count of the delimiter. A ';' file
  // with decimal commas has as many ';' on every line, its commas vary or miss the header.
  size_t best_score = 0;
  char best = ',';
  for (char d : {',', ';', '\t'}) {
    std::map<size_t, size_t> counts;
    for (std::string_view t : texts) ++counts[CountOutsideQuotes(t, d)];
    size_t score = 0;
    for (const auto& [count, lines_with] : counts) {
      if (count > 0) score = std::max(score, lines_with);
    }
    if (score > best_score) {
      best_score = score;
      best = d;
    }
  }
  // A one-column file: a header without any delimiter. Commas in its rows are then decimal
  // commas, not a second column.
  if (!texts.empty() && !IsDataLine(texts.front(), ',', '.') &&
      CountOutsideQuotes(texts.front(), ',') == 0 && CountOutsideQuotes(texts.front(), ';') == 0 &&
      CountOutsideQuotes(texts.front(), '\t') == 0) {
    best = ';';
  }
  dialect->delimiter = best;
  dialect->decimal_point = '.';
  if (best != ',') {
    // Decimal comma: a comma between digits in a data line.
    for (std::string_view t : texts) {
      for (size_t i = 1; i + 1 < t.size(); ++i) {
        if (t[i] == ',' && std::isdigit(static_cast<unsigned char>(t[i - 1])) &&
            std::isdigit(static_cast<unsigned char>(t[i + 1]))) {
          dialect->decimal_point = ',';
          return;
        }
      }
    }
  }
}

// Normalises a unit written in a header ("rad s^-1", "deg/s", "m/s²") to a metro unit.
const Unit* UnitFromText(std::string unit) {
  std::string u;
  for (char c : Lower(unit)) {
    if (c != ' ') u += c;
  }
  // UTF-8 degree sign and superscript two.
  auto replace = [&u](std::string_view from, std::string_view to) {
    for (size_t at = u.find(from); at != std::string::npos; at = u.find(from, at + to.size())) {
      u.replace(at, from.size(), to);
    }
  };
  replace("\xc2\xb0", "deg");
  replace("\xc2\xb2", "^2");
  replace("\xc2\xb5", "u");
  replace("\xce\xbc", "u");
  static const std::array<std::pair<std::string_view, std::string_view>, 24> kAliases = {{
      {"s", "s"},         {"sec", "s"},         {"ms", "ms"},        {"us", "us"},
      {"ns", "ns"},       {"deg/s", "deg/s"},   {"dps", "deg/s"},    {"degs^-1", "deg/s"},
      {"rad/s", "rad/s"}, {"rads^-1", "rad/s"}, {"rads-1", "rad/s"}, {"m/s^2", "m/s^2"},
      {"m/s2", "m/s^2"},  {"ms^-2", "m/s^2"},   {"ms-2", "m/s^2"},   {"g", "g"},
      {"deg", "deg"},     {"rad", "rad"},       {"degc", "degC"},    {"c", "degC"},
      {"lsb", "LSB"},     {"hz", "Hz"},         {"m", "m"},          {"v", "V"},
  }};
  for (const auto& [alias, symbol] : kAliases) {
    if (u == alias) return UnitBySymbol(symbol);
  }
  return nullptr;
}

std::vector<std::string> Words(std::string_view s) {
  std::vector<std::string> words;
  std::string w;
  char previous = 0;
  for (char c : s) {
    const unsigned char u = static_cast<unsigned char>(c);
    // A camel-case word boundary ("accX", "gyroZ", "AccelX"): lower case or digit, then
    // upper case.
    if (std::isupper(u) && !w.empty() &&
        (std::islower(static_cast<unsigned char>(previous)) ||
         std::isdigit(static_cast<unsigned char>(previous)))) {
      words.push_back(w);
      w.clear();
    }
    previous = c;
    if (std::isalnum(u)) {
      w += static_cast<char>(std::tolower(u));
    } else if (!w.empty()) {
      words.push_back(w);
      w.clear();
    }
  }
  if (!w.empty()) words.push_back(w);
  return words;
}

bool Has(const std::vector<std::string>& words, std::string_view w) {
  return std::find(words.begin(), words.end(), w) != words.end();
}

bool HasPrefix(const std::vector<std::string>& words, std::string_view prefix) {
  return std::any_of(words.begin(), words.end(),
                     [&](const std::string& w) { return w.rfind(prefix, 0) == 0; });
}

// The axis letter among a header name's words, 0 if none.
char AxisOfWords(const std::vector<std::string>& words) {
  char axis = 0;
  for (const std::string& w : words) {
    if (w == "x" || w == "y" || w == "z") axis = w[0];
  }
  return axis;
}

// The sensor a header name's words spell: "gyro", "gyroscope", "w", "omega", "angular",
// "rate"; "acc", "accel", "accelerometer", "acceleration", "a".
SensorKind SensorOfWords(const std::vector<std::string>& words) {
  if (HasPrefix(words, "gyr") || Has(words, "w") || Has(words, "omega") || Has(words, "angular") ||
      Has(words, "rate")) {
    return SensorKind::kGyroscope;
  }
  if (HasPrefix(words, "acc") || Has(words, "a")) return SensorKind::kAccelerometer;
  return SensorKind::kNone;
}

bool NamesTime(const std::vector<std::string>& words) {
  return Has(words, "time") || Has(words, "timestamp") || Has(words, "t");
}

// Sensor Logger's per-sensor files say which sensor only in their file name.
SensorKind SensorLoggerSensor(const std::string& path) {
  const std::string base = Lower(path.substr(path.find_last_of('/') + 1));
  if (base.find("gyro") != std::string::npos) return SensorKind::kGyroscope;
  if (base.find("accel") != std::string::npos || base.find("gravity") != std::string::npos) {
    return SensorKind::kAccelerometer;
  }
  return SensorKind::kNone;
}

// The canonical name a named format gives one of its header names; `ok` false when the
// format has none for it (then the ordinary rules apply). "" = the column is left out.
std::string NamedFormatColumn(SessionFormat format, const std::string& path,
                              std::string_view source, bool* ok) {
  *ok = true;
  const std::string lower = Lower(TrimView(source));
  switch (format) {
    case SessionFormat::kRaw:
      if (lower.size() == 2 && (lower[0] == 'a' || lower[0] == 'g') &&
          (lower[1] == 'x' || lower[1] == 'y' || lower[1] == 'z')) {
        return lower + "_lsb";
      }
      break;
    case SessionFormat::kSensorLogger: {
      if (lower == "time") return "t_ns";
      if (lower == "seconds_elapsed") return "";  // The same clock as `time`, as a double.
      const SensorKind sensor = SensorLoggerSensor(path);
      if (lower.size() == 1 && (lower[0] == 'x' || lower[0] == 'y' || lower[0] == 'z') &&
          sensor != SensorKind::kNone) {
        const Unit* unit = UnitBySymbol(sensor == SensorKind::kGyroscope ? "rad/s" : "m/s^2");
        return AxisColumn(sensor, lower[0], *unit);
      }
      break;
    }
    case SessionFormat::kEuroc:
    case SessionFormat::kPhyphox:
    case SessionFormat::kPhone: {
      const std::string inferred = InferCanonicalName(source);
      if (!inferred.empty()) return inferred;
      if (format != SessionFormat::kEuroc) {
        // phyphox's other columns ("Absolute (rad/s)"): carried as unknown columns named
        // by their words and unit suffix ("absolute_rads").
        const size_t open = source.find_last_of("([");
        const std::vector<std::string> words = Words(source.substr(0, open));
        const Unit* unit = nullptr;
        if (open != std::string_view::npos) {
          const size_t close = source.find_first_of(")]", open);
          unit = UnitFromText(std::string(source.substr(open + 1, close - open - 1)));
        }
        if (!words.empty() && unit != nullptr && !unit->suffix.empty() &&
            std::isalpha(static_cast<unsigned char>(words[0][0]))) {
          return fmt::format("{}_{}", fmt::join(words, "_"), unit->suffix);
        }
      }
      break;
    }
    default:
      break;
  }
  *ok = false;
  return "";
}

// Stage 4: a spreadsheet's footer after the last data row: rows of empty fields (",,,,")
// and one or more text lines whose other fields are empty ("Step: 0.005 = 1/200,,,,").
size_t FindDataEnd(const MappedFile& file, size_t data_begin, char line_end, char delimiter,
                   std::vector<std::string>* notes, int64_t* footer_lines) {
  size_t end = file.size();
  *footer_lines = 0;
  std::vector<std::string> dropped;
  for (int k = 0; k < 20 && end > data_begin; ++k) {
    size_t e = end;
    while (e > data_begin && (file.data()[e - 1] == '\n' || file.data()[e - 1] == '\r')) --e;
    if (e == data_begin) break;
    const char* nl =
        static_cast<const char*>(memrchr(file.data() + data_begin, line_end, e - data_begin));
    const size_t b = nl != nullptr ? static_cast<size_t>(nl - file.data()) + 1 : data_begin;
    const std::string_view line(file.data() + b, e - b);
    const std::vector<std::string> fields = SplitFields(line, delimiter);
    if (fields.size() < 2) break;
    const bool rest_empty = std::all_of(fields.begin() + 1, fields.end(),
                                        [](const std::string& f) { return f.empty(); });
    if (!rest_empty) break;
    const bool first_empty = fields.front().empty();
    const bool first_text =
        !first_empty && !IsNumber(fields.front(), '.') && fields.front().front() != '#';
    if (!first_empty && !first_text) break;
    dropped.push_back(Printable(line));
    ++*footer_lines;
    end = b;
  }
  if (*footer_lines > 0) {
    std::reverse(dropped.begin(), dropped.end());
    notes->push_back(
        fmt::format("{} line(s) after the last data row left out as a spreadsheet footer: {}",
                    *footer_lines, fmt::join(dropped, " | ")));
  }
  return end;
}

// A "key,value" line before a raw logger's header.
struct MetadataLine {
  std::string key;
  std::string value;
  int64_t line = 0;
  int64_t value_column = 0;  // 1-based column where the value starts.
};

struct Found {
  HeaderLine header;
  std::vector<MetadataLine> metadata;
};

// Stage 2: the header line.
Result<Found> FindHeaderLine(const std::string& path, const std::vector<HeadLine>& lines,
                             const InputDialect& dialect) {
  Found found;
  size_t first = lines.size();  // First line that is neither blank nor a comment.
  for (size_t i = 0; i < lines.size(); ++i) {
    if (!IsBlank(lines[i].text) && !IsComment(lines[i].text)) {
      first = i;
      break;
    }
  }
  if (first == lines.size()) {
    return MakeError(path, 0,
                     "no header: the file holds only blank or comment lines; expected a "
                     "session.csv header line (t_s,...)");
  }
  auto set = [&found](const HeadLine& l, std::string_view text) {
    found.header.line_begin = l.begin;
    found.header.data_begin = l.next;
    found.header.line_number = l.number;
    found.header.text = std::string(TrimView(text));
  };
  const char d = dialect.delimiter;
  const char dp = dialect.decimal_point;
  if (IsDataLine(lines[first].text, d, dp)) {
    // A data row first: the header may be the comment right before it (EuRoC's
    // "#timestamp [ns],w_RS_S_x [rad s^-1],...").
    const size_t fields = SplitFields(lines[first].text, d).size();
    for (size_t i = first; i-- > 0;) {
      if (IsBlank(lines[i].text)) continue;
      std::string_view c = TrimView(lines[i].text);
      c.remove_prefix(1);  // '#'
      if (SplitFields(c, d).size() == fields && !IsDataLine(c, d, dp)) {
        set(lines[i], c);
        return found;
      }
      break;
    }
    return MakeError(path, lines[first].number, 1,
                     fmt::format("no header: line {} is a data row ('{}'); expected a header "
                                 "line naming the columns with their units before it, e.g. "
                                 "t_s,gx_dps,gy_dps,gz_dps (docs/formats.md)",
                                 lines[first].number, Printable(lines[first].text)));
  }
  // Metadata lines ("Fs,100" of a raw logger) before the header: "key,value" lines, then
  // the header, then a data row with another number of fields.
  size_t data = lines.size();
  for (size_t i = first; i < lines.size(); ++i) {
    if (IsDataLine(lines[i].text, d, dp)) {
      data = i;
      break;
    }
  }
  if (data < lines.size() && data > first + 1) {
    std::vector<size_t> meta;
    size_t header = data;
    for (size_t i = data; i-- > first;) {
      if (IsBlank(lines[i].text) || IsComment(lines[i].text)) continue;
      if (header == data) {
        header = i;
        continue;
      }
      meta.push_back(i);
    }
    // Only before a raw logger's header of bare axis names (ax,ay,az,gx,gy,gz): elsewhere
    // a "key,value" line is a header or a row, and its errors say so.
    const std::vector<std::string> names = SplitFields(lines[header].text, d);
    const bool raw_header = std::all_of(names.begin(), names.end(), [](const std::string& n) {
      const std::string l = Lower(n);
      return l.size() == 2 && (l[0] == 'a' || l[0] == 'g') &&
             (l[1] == 'x' || l[1] == 'y' || l[1] == 'z');
    });
    const bool all_key_value =
        raw_header && !meta.empty() && std::all_of(meta.begin(), meta.end(), [&](size_t i) {
          const std::vector<std::string> f = SplitFields(lines[i].text, d);
          return f.size() == 2 && !IsNumber(f[0], dp);
        });
    if (all_key_value) {
      for (auto it = meta.rbegin(); it != meta.rend(); ++it) {
        const std::vector<std::string> f = SplitFields(lines[*it].text, d);
        const size_t value_at = lines[*it].text.find(d) + 1;
        found.metadata.push_back(
            {f[0], f[1], lines[*it].number, static_cast<int64_t>(value_at) + 1});
      }
      set(lines[header], lines[header].text);
      found.header.metadata_lines = static_cast<int64_t>(meta.size());
      return found;
    }
  }
  set(lines[first], lines[first].text);
  return found;
}

std::string ProposeMapping(std::string_view source) {
  const std::string inferred = InferCanonicalName(source);
  if (!inferred.empty()) {
    return fmt::format("map it: --column '{}={}'", source, inferred);
  }
  // An axis spelled without its unit ("accX", "accelerometer_x"): the unit is the user's.
  const std::vector<std::string> words = Words(source);
  const char axis = AxisOfWords(words);
  const SensorKind sensor = SensorOfWords(words);
  if (axis != 0 && sensor == SensorKind::kAccelerometer) {
    return fmt::format(
        "it names the accelerometer's {} axis but not its unit: map it with yours, --column "
        "'{}=a{}_mps2' (m/s^2) or --column '{}=a{}_g' (g)",
        axis, source, axis, source, axis);
  }
  if (axis != 0 && sensor == SensorKind::kGyroscope) {
    return fmt::format(
        "it names the gyroscope's {} axis but not its unit: map it with yours, --column "
        "'{}=g{}_rads' (rad/s) or --column '{}=g{}_dps' (deg/s)",
        axis, source, axis, source, axis);
  }
  return fmt::format(
      "map it to a canonical name with its unit: --column '{}=NAME' (e.g. gx_dps, ax_g, "
      "t_s; docs/formats.md), or leave it out with --column '{}='",
      source, source);
}

// Nearest supported shape for a header metro cannot read as session.csv.
std::string FormatHint(SessionFormat detected) {
  switch (detected) {
    case SessionFormat::kEuroc:
      return "; this looks like a EuRoC file: pass --format euroc";
    case SessionFormat::kPhyphox:
      return "; this looks like a phyphox export: pass --format phyphox";
    case SessionFormat::kSensorLogger:
      return "; this looks like a Sensor Logger file: pass --format sensorlogger";
    case SessionFormat::kPhone:
      return "; this looks like a phone or logger app's export whose columns spell their "
             "sensor, axis and unit: pass --format phone";
    case SessionFormat::kRaw:
      return "; this looks like a raw-count logger print: pass --format raw";
    default:
      return "";
  }
}

}  // namespace

std::vector<std::string> SplitFields(std::string_view line, char delimiter) {
  std::vector<std::string> fields;
  std::string field;
  bool quoted = false;
  bool was_quoted = false;
  for (size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted) {
      if (c == '"') {
        if (i + 1 < line.size() && line[i + 1] == '"') {
          field += '"';
          ++i;
        } else {
          quoted = false;
        }
      } else {
        field += c;
      }
    } else if (c == '"' && TrimView(field).empty()) {
      quoted = true;
      was_quoted = true;
      field.clear();
    } else if (c == delimiter) {
      fields.emplace_back(was_quoted ? field : std::string(TrimView(field)));
      field.clear();
      was_quoted = false;
    } else if (!(was_quoted && (c == ' ' || c == '\t'))) {
      field += c;
    }
  }
  fields.emplace_back(was_quoted ? field : std::string(TrimView(field)));
  return fields;
}

std::string InferCanonicalName(std::string_view source) {
  std::string_view s = TrimView(source);
  // The unit: the last "(...)" or "[...]" group.
  const Unit* unit = nullptr;
  std::string_view name = s;
  const size_t open = s.find_last_of("([");
  if (open != std::string_view::npos) {
    const char close = s[open] == '(' ? ')' : ']';
    const size_t end = s.find(close, open);
    if (end != std::string_view::npos) {
      unit = UnitFromText(std::string(s.substr(open + 1, end - open - 1)));
      name = s.substr(0, open);
    }
  }
  const std::vector<std::string> words = Words(name);
  if (words.empty()) return "";
  if (unit == nullptr) {
    // "gyro_x_dps"-like: the last word may be the unit.
    if (const Unit* u = UnitBySuffix(words.back()); u != nullptr && words.size() > 1) {
      unit = u;
    } else {
      return "";
    }
  }
  const char axis = AxisOfWords(words);
  if (unit->dimension == Dimension::kTime && NamesTime(words)) {
    return "t_" + std::string(unit->suffix);
  }
  const SensorKind sensor = SensorOfWords(words);
  if (sensor != SensorKind::kNone && axis != 0) {
    for (const Unit* allowed : AxisUnits(sensor)) {
      if (allowed == unit) return AxisColumn(sensor, axis, *unit);
    }
    return "";
  }
  if (unit->dimension == Dimension::kAngle && unit->symbol == "deg") {
    for (const char* angle : {"yaw", "pitch", "roll"}) {
      if (Has(words, angle)) return std::string(angle) + "_deg";
    }
  }
  if (unit->dimension == Dimension::kTemperature && HasPrefix(words, "temp")) return "temp_c";
  return "";
}

namespace {

// A header that spells at least one sensor axis with its unit in an app's words ("Accel_X
// (m/s^2)", "accX [g]", "Acc X (m/s^2)", "gyroscope_x_rads") and names no canonical
// quantity (a session.csv's ax_g): the kPhone format. `fields` in the header's own case
// (camel-case words).
bool SpellsSensorAxes(const std::vector<std::string>& fields) {
  int axes = 0;
  for (const std::string& f : fields) {
    const std::string lower = Lower(f);
    if (IsValidColumnName(lower) && ClassifyColumn(lower).role == ColumnRole::kQuantity) {
      return false;
    }
    const std::string inferred = InferCanonicalName(f);
    if (inferred.empty() || inferred.rfind("t_", 0) == 0) continue;
    const ColumnInfo info = ClassifyColumn(inferred);
    if (info.sensor == SensorKind::kAccelerometer || info.sensor == SensorKind::kGyroscope) {
      ++axes;
    }
  }
  return axes > 0;
}

}  // namespace

SessionFormat DetectNamedFormat(const std::string& path, std::string_view head) {
  // The header, whichever line it is: look at the first lines' names.
  const std::string lower = Lower(head.substr(0, std::min<size_t>(head.size(), 4096)));
  if (lower.find("w_rs_s_x") != std::string::npos ||
      lower.find("#timestamp [ns]") != std::string::npos) {
    return SessionFormat::kEuroc;
  }
  size_t pos = 0;
  int lines = 0;
  while (pos < lower.size() && lines++ < 8) {
    size_t nl = lower.find('\n', pos);
    if (nl == std::string::npos) nl = lower.size();
    std::string_view line(lower.data() + pos, nl - pos);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    const std::string_view spelled(head.data() + pos, line.size());  // Its own case.
    pos = nl + 1;
    if (IsBlank(line) || IsComment(line)) continue;
    for (char d : {',', ';', '\t'}) {
      const std::vector<std::string> f = SplitFields(line, d);
      if (f.size() < 2) continue;
      if (f[0] == "time (s)" && std::any_of(f.begin() + 1, f.end(), [](const std::string& n) {
            return n.rfind("gyroscope ", 0) == 0 || n.rfind("acceleration ", 0) == 0 ||
                   n.rfind("linear acceleration ", 0) == 0;
          })) {
        return SessionFormat::kPhyphox;
      }
      if (SpellsSensorAxes(SplitFields(spelled, d))) return SessionFormat::kPhone;
      std::vector<std::string> sorted = f;
      std::sort(sorted.begin(), sorted.end());
      if (sorted == std::vector<std::string>{"seconds_elapsed", "time", "x", "y", "z"}) {
        return SessionFormat::kSensorLogger;
      }
      const bool raw = std::all_of(f.begin(), f.end(), [](const std::string& n) {
        return n.size() == 2 && (n[0] == 'a' || n[0] == 'g') &&
               (n[1] == 'x' || n[1] == 'y' || n[1] == 'z');
      });
      if (raw) return SessionFormat::kRaw;
    }
  }
  (void)path;
  return SessionFormat::kCsv;
}

bool ParseExactTimeNs(const char* b, const char* e, int64_t ns_per_unit, int64_t* ns,
                      int64_t* resolution_ns, const char** why) {
  *resolution_ns = 0;
  const char* p = b;
  bool negative = false;
  if (p < e && (*p == '-' || *p == '+')) negative = *p++ == '-';
  // Mantissa digits as an integer (at most 19 significant), then the exponent.
  uint64_t mantissa = 0;
  int digits = 0;
  int fraction = 0;
  bool any = false;
  bool dot = false;
  for (; p < e; ++p) {
    if (*p >= '0' && *p <= '9') {
      any = true;
      if (mantissa == 0 && *p == '0') {
        if (dot) ++fraction;
        continue;
      }
      if (++digits > 19) {
        *why = "too many digits for an integer time";
        return false;
      }
      mantissa = mantissa * 10 + static_cast<unsigned>(*p - '0');
      if (dot) ++fraction;
    } else if (*p == '.' && !dot) {
      dot = true;
    } else {
      break;
    }
  }
  if (!any) {
    *why = p == e && b == e ? "empty" : "not a number";
    return false;
  }
  int exponent = 0;
  bool has_exponent = false;
  if (p < e && (*p == 'e' || *p == 'E')) {
    has_exponent = true;
    ++p;
    bool exp_negative = false;
    if (p < e && (*p == '-' || *p == '+')) exp_negative = *p++ == '-';
    if (p == e || *p < '0' || *p > '9') {
      *why = "not a number";
      return false;
    }
    for (; p < e && *p >= '0' && *p <= '9'; ++p) {
      exponent = exponent * 10 + (*p - '0');
      if (exponent > 400) break;
    }
    if (exp_negative) exponent = -exponent;
  }
  if (p != e) {
    *why = "not a number";
    return false;
  }
  // value [ns] = mantissa * 10^(exponent - fraction) * ns_per_unit, ns_per_unit = 10^k.
  int k = 0;
  for (int64_t u = ns_per_unit; u > 1; u /= 10) ++k;
  const int place = exponent - fraction + k;  // Power of ten (ns) of the last digit written.
  uint64_t value = mantissa;
  constexpr uint64_t kMax = static_cast<uint64_t>(std::numeric_limits<int64_t>::max());
  if (place >= 0) {
    for (int i = 0; i < place && value != 0; ++i) {
      if (value > kMax / 10) {
        *why = "out of range for nanoseconds in 64 bits";
        return false;
      }
      value *= 10;
    }
    if (has_exponent && place > 0 && mantissa != 0) {
      int64_t r = 1;
      for (int i = 0; i < place; ++i) r *= 10;
      *resolution_ns = r;
    }
  } else {
    for (int i = 0; i < -place; ++i) {
      if (value % 10 != 0) {
        *why = "finer than 1 ns";
        return false;
      }
      value /= 10;
    }
  }
  if (value > kMax) {
    *why = "out of range for nanoseconds in 64 bits";
    return false;
  }
  *ns = negative ? -static_cast<int64_t>(value) : static_cast<int64_t>(value);
  return true;
}

bool ColumnPlan::CleanPathCan() const {
  if (dialect.delimiter != ',' || dialect.decimal_point != '.' || dialect.line_ends == "CR") {
    return false;
  }
  if (time_field < 0 || time_ns_per_unit != 0 || !text_fields.empty()) return false;
  if (!raw_scale.empty()) return false;
  return std::none_of(names.begin(), names.end(), [](const std::string& n) { return n.empty(); });
}

namespace {

// ---- stage 1: framing ---------------------------------------------------------------------

// Where the text starts, its head, line end and first lines.
struct Framing {
  std::string_view head;  // The first kHeadBytes after the byte-order mark.
  char line_end = '\n';
  std::vector<HeadLine> lines;
};

// Byte-order mark, line ends, delimiter (into *dialect).
Framing DetectFraming(const MappedFile& file, InputDialect* dialect) {
  size_t start = 0;
  if (file.size() >= 3 && std::memcmp(file.data(), "\xEF\xBB\xBF", 3) == 0) {
    dialect->bom = true;
    start = 3;
  }
  Framing framing;
  framing.head = std::string_view(file.data() + start, std::min(file.size() - start, kHeadBytes));
  const std::string_view head = framing.head;
  const size_t lf = static_cast<size_t>(std::count(head.begin(), head.end(), '\n'));
  const size_t cr = static_cast<size_t>(std::count(head.begin(), head.end(), '\r'));
  const char line_end = lf == 0 && cr > 0 ? '\r' : '\n';
  framing.line_end = line_end;
  dialect->line_ends = line_end == '\r' ? "CR" : (cr > 0 ? "CRLF" : "LF");
  framing.lines = HeadLines(file, start, line_end, kHeadLines);
  DetectDelimiter(framing.lines, dialect);
  return framing;
}

// ---- stage 2: the header ------------------------------------------------------------------

// A sample rate given in the metadata lines before the header (plan->rate_hz unless
// --rate-hz is given); a rate line that says no rate is refused.
Status ApplyRateMetadata(const std::string& path, const std::vector<MetadataLine>& metadata,
                         const LoadOptions& options, ColumnPlan* plan) {
  InputDialect& dialect = plan->dialect;
  for (const MetadataLine& m : metadata) {
    const std::string k = Lower(std::string(TrimView(m.key)));
    if (k != "fs" && k != "rate_hz" && k != "sample rate" && k != "sampling rate") continue;
    const std::string_view value = TrimView(m.value);
    double rate_hz = 0.0;
    const auto parsed = fast_float::from_chars(value.data(), value.data() + value.size(), rate_hz);
    const bool positive = parsed.ec == std::errc() && parsed.ptr == value.data() + value.size() &&
                          std::isfinite(rate_hz) && rate_hz > 0.0;
    // A sample-rate line that says no rate is refused, not skipped: the times of every row
    // would come from it.
    if (!positive) {
      return MakeError(path, m.line, m.value_column,
                       fmt::format("metadata '{}' gives the sample rate as '{}'; expected a "
                                   "positive number of hertz, e.g. '{},100' (or drop the line "
                                   "and pass --rate-hz R)",
                                   Printable(m.key), Printable(m.value), Printable(m.key)));
    }
    if (options.rate_hz == 0.0) {
      plan->rate_hz = rate_hz;
      dialect.notes.push_back(fmt::format("metadata '{},{}' sets the sample rate to {} Hz", m.key,
                                          m.value, plan->rate_hz));
    } else if (rate_hz != options.rate_hz) {
      dialect.notes.push_back(fmt::format("--rate-hz {} overrides the metadata '{},{}' (line {})",
                                          options.rate_hz, m.key, m.value, m.line));
    }
  }
  return Status::Ok();
}

// The header line (*header), the format (plan->format) and the metadata before the header.
Status ReadHeader(const std::string& path, const MappedFile& file, const Framing& framing,
                  const LoadOptions& options, SessionFormat format, ColumnPlan* plan,
                  HeaderLine* header) {
  InputDialect& dialect = plan->dialect;
  auto found_or = FindHeaderLine(path, framing.lines, dialect);
  if (!found_or.ok()) return found_or.error();
  const Found& found = found_or.value();
  *header = found.header;
  dialect.header_in_comment = IsComment(std::string_view(
      file.data() + header->line_begin, std::min<size_t>(file.size() - header->line_begin, 256)));
  if (format == SessionFormat::kAuto || format == SessionFormat::kCsv) {
    const SessionFormat named = DetectNamedFormat(path, framing.head);
    if (format == SessionFormat::kAuto) format = named;
  }
  plan->format = format;
  plan->rate_hz = options.rate_hz;
  if (Status s = ApplyRateMetadata(path, found.metadata, options, plan); !s.ok()) return s;
  if (header->metadata_lines > 0) {
    dialect.notes.push_back(fmt::format("{} metadata line(s) before the header on line {}",
                                        header->metadata_lines, header->line_number));
  }
  return Status::Ok();
}

// ---- stage 3: the columns -----------------------------------------------------------------

// The canonical name of header field `source` (column 1-based): --column, the named
// format's, or the header's own if canonical; empty: left out.
Result<std::string> ColumnName(const std::string& path, std::string_view head,
                               const HeaderLine& header, const LoadOptions& options,
                               SessionFormat format, const std::string& source, int column) {
  std::string name;
  bool mapped = false;
  for (const ColumnMapping& m : options.column_map) {
    if (Lower(m.source) == Lower(source)) {
      name = m.canonical;
      mapped = true;
    }
  }
  if (!mapped) name = NamedFormatColumn(format, path, source, &mapped);
  if (!mapped && format == SessionFormat::kSensorLogger) {
    const std::string lower = Lower(source);
    if (lower == "x" || lower == "y" || lower == "z") {
      return MakeError(
          path, header.line_number, column,
          fmt::format("Sensor Logger names the sensor of its x, y, z columns only in the file "
                      "name (Gyroscope.csv, Accelerometer.csv), and '{}' does not say it: map "
                      "the axes, e.g. --column x=gx_rads --column y=gy_rads --column z=gz_rads "
                      "(gyroscope, rad/s) or ax_mps2.. (accelerometer, m/s^2)",
                      path));
    }
  }
  if (!mapped) {
    const std::string lower = Lower(source);
    if (!IsValidColumnName(lower)) {
      const SessionFormat detected = DetectNamedFormat(path, head);
      const std::string hint = format == SessionFormat::kCsv ? FormatHint(detected) : "";
      return MakeError(path, header.line_number, column,
                       fmt::format("header: column {} is '{}', not a canonical column name "
                                   "([a-z][a-z0-9_]* with its unit, e.g. gx_dps); {}{}",
                                   column, Printable(source), ProposeMapping(source), hint));
    }
    name = lower;
  }
  if (!name.empty() && !IsValidColumnName(name)) {
    return MakeError(path, header.line_number, column,
                     fmt::format("--column maps '{}' to '{}', which is not a canonical column "
                                 "name ([a-z][a-z0-9_]*, e.g. gx_dps; docs/formats.md)",
                                 Printable(source), Printable(name)));
  }
  return name;
}

// The header's fields (sources) named and classified: plan->source_names, names, info.
Status NameColumns(const std::string& path, std::string_view head, const HeaderLine& header,
                   const LoadOptions& options, const std::vector<std::string>& sources,
                   ColumnPlan* plan) {
  InputDialect& dialect = plan->dialect;
  if (sources.size() > kMaxSessionColumns) {
    return MakeError(path, header.line_number,
                     fmt::format("{} columns; metro reads at most {} (docs/formats.md, "
                                 "\"Limits\"): write the columns you need to a new file, or "
                                 "split it",
                                 sources.size(), kMaxSessionColumns));
  }
  dialect.quoted = header.text.find('"') != std::string::npos;
  std::map<std::string, int> seen;
  for (size_t f = 0; f < sources.size(); ++f) {
    const std::string& source = sources[f];
    const int column = static_cast<int>(f) + 1;
    Result<std::string> named =
        ColumnName(path, head, header, options, plan->format, source, column);
    if (!named.ok()) return named.error();
    const std::string& name = named.value();
    if (name != source) dialect.mapping.push_back(ColumnMapping{source, name});
    if (!name.empty() && !seen.emplace(name, column).second) {
      return MakeError(path, header.line_number, column,
                       fmt::format("header: column '{}' appears twice (columns {} and {})", name,
                                   seen[name], column));
    }
    plan->source_names.push_back(source);
    plan->names.push_back(name);
    plan->info.push_back(name.empty() ? ColumnInfo{} : ClassifyColumn(name));
    const std::vector<std::string> words = Words(source);
    if (!name.empty() && plan->info.back().role == ColumnRole::kUnknown &&
        plan->info.back().unit == nullptr && AxisOfWords(words) != 0 &&
        SensorOfWords(words) != SensorKind::kNone) {
      // "accX": carried as a unit-less unknown column, which its reader may not expect.
      dialect.warnings.push_back(
          fmt::format("{}:{}:{}: column '{}' is carried as an unknown column without a unit "
                      "(unit 1): {}",
                      path, header.line_number, column, Printable(source), ProposeMapping(source)));
    }
  }
  dialect.header_line = header.line_number;
  dialect.header_names = plan->names;
  return Status::Ok();
}

// Each named column's role: the time, the sensor, numeric and text slots.
Status AssignRoles(const std::string& path, const HeaderLine& header, ColumnPlan* plan) {
  ColumnPlan& p = *plan;
  const size_t nf = p.names.size();
  p.numeric_slot.assign(nf, -1);
  p.text_slot.assign(nf, -1);
  for (size_t f = 0; f < nf; ++f) {
    if (p.names[f].empty()) continue;  // Left out.
    switch (p.info[f].role) {
      case ColumnRole::kTime:
        if (p.time_field >= 0) {
          return MakeError(path, header.line_number, static_cast<int>(f) + 1,
                           fmt::format("header: two time columns, '{}' and '{}'; leave one "
                                       "out with --column '{}='",
                                       p.names[static_cast<size_t>(p.time_field)], p.names[f],
                                       p.source_names[f]));
        }
        p.time_field = static_cast<int>(f);
        p.time_ns_per_unit = p.names[f] == "t_s"    ? 0
                             : p.names[f] == "t_ms" ? 1000000
                             : p.names[f] == "t_us" ? 1000
                                                    : 1;
        break;
      case ColumnRole::kSensor:
        p.sensor_field = static_cast<int>(f);
        break;
      case ColumnRole::kQuantity:
        p.numeric_slot[f] = static_cast<int>(p.numeric_fields.size());
        p.numeric_fields.push_back(static_cast<int>(f));
        break;
      case ColumnRole::kText:
      case ColumnRole::kUnknown:
        p.text_slot[f] = static_cast<int>(p.text_fields.size());
        p.text_fields.push_back(static_cast<int>(f));
        break;
    }
  }
  return Status::Ok();
}

// How the rows are timed: the time column, or --rate-hz / the metadata's rate; neither is
// an error that proposes a mapping.
Status CheckTiming(const std::string& path, std::string_view head, const HeaderLine& header,
                   const LoadOptions& options, const std::vector<std::string>& sources,
                   ColumnPlan* plan) {
  InputDialect& dialect = plan->dialect;
  if (plan->time_field >= 0) {
    const std::string& name = plan->names[static_cast<size_t>(plan->time_field)];
    dialect.time_source = plan->source_names[static_cast<size_t>(plan->time_field)];
    dialect.time_unit = name.substr(2);
    dialect.time_integer = plan->time_ns_per_unit != 0;
    if (options.rate_hz > 0.0) {
      return MakeError(path, header.line_number, plan->time_field + 1,
                       fmt::format("--rate-hz is for a file without a time column, but this "
                                   "one has '{}'; leave it out with --column '{}=' to time the "
                                   "rows by --rate-hz instead",
                                   dialect.time_source, dialect.time_source));
    }
    return Status::Ok();
  }
  if (plan->rate_hz > 0.0) {
    dialect.time_unit = "rate";
    dialect.rate_hz = plan->rate_hz;
    return Status::Ok();
  }
  std::string proposal;
  for (const std::string& s : sources) {
    const std::string inferred = InferCanonicalName(s);
    if (inferred.rfind("t_", 0) == 0 && ClassifyColumn(inferred).role == ColumnRole::kTime) {
      proposal = fmt::format("; map yours: --column '{}={}'", s, inferred);
      break;
    }
    if (inferred.empty() && NamesTime(Words(s))) {
      proposal = fmt::format(
          "; '{}' names a time without its unit: map it with your clock's, --column '{}=t_s' "
          "(or t_ms, t_us, t_ns)",
          s, s);
      break;
    }
  }
  return MakeError(
      path, header.line_number,
      fmt::format(
          "header: no time column; expected t_s, t_ms, t_us or t_ns (or --rate-hz R "
          "for a file without one){}; found '{}'{}",
          proposal, Printable(header.text),
          plan->format == SessionFormat::kCsv ? FormatHint(DetectNamedFormat(path, head)) : ""));
}

// Raw counts with full-scale settings: the physical columns beside the counts.
void PlanRawScales(const LoadOptions& options, ColumnPlan* plan) {
  for (size_t q = 0; q < plan->numeric_fields.size(); ++q) {
    const ColumnInfo& info = plan->info[static_cast<size_t>(plan->numeric_fields[q])];
    double scale = 0.0;
    std::string scaled;
    if (info.unit != nullptr && info.unit->symbol == "LSB") {
      if (info.sensor == SensorKind::kAccelerometer && options.accel_fs_g > 0.0) {
        scale = options.accel_fs_g / 32768.0;  // MPU6050: 16384 LSB/g at +-2 g.
        scaled = AxisColumn(info.sensor, info.axis, *UnitBySymbol("g"));
      } else if (info.sensor == SensorKind::kGyroscope && options.gyro_fs_dps > 0.0) {
        scale = options.gyro_fs_dps / 32768.0;
        scaled = AxisColumn(info.sensor, info.axis, *UnitBySymbol("deg/s"));
      }
    }
    plan->raw_scale.push_back(scale);
    plan->raw_scaled_name.push_back(scaled);
  }
  if (std::all_of(plan->raw_scale.begin(), plan->raw_scale.end(),
                  [](double s) { return s == 0.0; })) {
    plan->raw_scale.clear();
    plan->raw_scaled_name.clear();
  } else {
    plan->dialect.accel_fs_g = options.accel_fs_g;
    plan->dialect.gyro_fs_dps = options.gyro_fs_dps;
  }
}

// Time in seconds written in E-notation (a spreadsheet round trip: 1.40363657975856E+09)
// keeps only the digits written: say which resolution is left, from the first data row
// (the clean path parses such a column as any number; integer time units are checked row
// by row in the general path).
void CheckTimeResolution(const std::vector<HeadLine>& lines, const HeaderLine& header,
                         ColumnPlan* plan) {
  InputDialect& dialect = plan->dialect;
  if (plan->time_field >= 0 && plan->time_ns_per_unit == 0) {
    for (const HeadLine& l : lines) {
      if (l.begin < header.data_begin || IsBlank(l.text) || IsComment(l.text)) continue;
      const std::vector<std::string> fields = SplitFields(l.text, dialect.delimiter);
      if (static_cast<size_t>(plan->time_field) >= fields.size()) break;
      std::string t = fields[static_cast<size_t>(plan->time_field)];
      std::replace(t.begin(), t.end(), dialect.decimal_point, '.');
      int64_t ns = 0;
      int64_t resolution_ns = 0;
      const char* why = nullptr;
      if (t.find_first_of("eE") != std::string::npos &&
          ParseExactTimeNs(t.data(), t.data() + t.size(), 1000000000, &ns, &resolution_ns, &why) &&
          resolution_ns >= 1000) {
        dialect.time_resolution_s = static_cast<double>(resolution_ns) / 1e9;
        dialect.warnings.push_back(fmt::format(
            "t_s is written in E-notation (a spreadsheet round trip?), '{}' on line {}: its "
            "last digits are gone, so times are resolved to {:g} s only; sample periods, gaps "
            "and Allan tau0 are good to that resolution",
            Printable(l.text.substr(0, 60)), l.number, dialect.time_resolution_s));
      }
      break;
    }
  }
}

}  // namespace

Result<ColumnPlan> PlanCsv(const std::string& path, const MappedFile& file,
                           const LoadOptions& options, SessionFormat format, HeaderLine* header) {
  ColumnPlan plan;
  // Stage 1: byte-order mark, line ends, delimiter.
  const Framing framing = DetectFraming(file, &plan.dialect);
  // Stage 2: the header.
  if (Status s = ReadHeader(path, file, framing, options, format, &plan, header); !s.ok()) {
    return s.error();
  }
  // Stage 3: the columns.
  const std::vector<std::string> sources = SplitFields(header->text, plan.dialect.delimiter);
  if (Status s = NameColumns(path, framing.head, *header, options, sources, &plan); !s.ok()) {
    return s.error();
  }
  if (Status s = AssignRoles(path, *header, &plan); !s.ok()) return s.error();
  if (Status s = CheckTiming(path, framing.head, *header, options, sources, &plan); !s.ok()) {
    return s.error();
  }
  PlanRawScales(options, &plan);
  CheckTimeResolution(framing.lines, *header, &plan);
  // Stage 4: a spreadsheet footer.
  int64_t footer = 0;
  plan.data_end = FindDataEnd(file, header->data_begin, framing.line_end, plan.dialect.delimiter,
                              &plan.dialect.notes, &footer);
  return plan;
}

}  // namespace metro::internal
