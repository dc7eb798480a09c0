#include "metro/calibration/segment_file.hpp"

#include <fast_float/fast_float.h>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <sstream>

#include "metro/core/check.hpp"
#include "metro/core/file.hpp"

namespace metro {
namespace {

constexpr const char* kExample =
    "expected a header such as 'kind,start_s,end_s,table_rate_dps,input' and lines such as "
    "'static,0.0,4.5' or 'table,7.0,17.0,30'";

std::vector<std::string> SplitComma(const std::string& line) {
  std::vector<std::string> out;
  std::string field;
  std::istringstream in(line);
  while (std::getline(in, field, ',')) {
    const size_t b = field.find_first_not_of(" \t\r");
    const size_t e = field.find_last_not_of(" \t\r");
    out.push_back(b == std::string::npos ? "" : field.substr(b, e - b + 1));
  }
  if (!line.empty() && line.back() == ',') out.push_back("");
  return out;
}

bool ParseNumber(const std::string& s, double* out) {
  const char* end = s.data() + s.size();
  const auto r = fast_float::from_chars(s.data(), end, *out);
  return r.ec == std::errc() && r.ptr == end && std::isfinite(*out);
}

}  // namespace

Result<std::vector<AnnotatedSegment>> ReadSegmentsFile(const std::string& path) {
  Result<std::string> text = ReadFile(path);
  if (!text.ok()) return text.error();
  std::istringstream in(text.value());
  std::string line;
  int line_no = 0;
  int col_kind = -1, col_start = -1, col_end = -1, col_rate = -1, col_input = -1;
  size_t columns = 0;
  std::vector<AnnotatedSegment> out;
  while (std::getline(in, line)) {
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line_no == 1 && line.rfind("\xEF\xBB\xBF", 0) == 0) line.erase(0, 3);
    const size_t first = line.find_first_not_of(" \t");
    if (first == std::string::npos || line[first] == '#') continue;
    const std::vector<std::string> f = SplitComma(line);
    if (col_kind < 0) {
      for (size_t i = 0; i < f.size(); ++i) {
        std::string name = f[i];
        std::transform(name.begin(), name.end(), name.begin(),
                       [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
        const int c = static_cast<int>(i);
        if (name == "kind")
          col_kind = c;
        else if (name == "start_s")
          col_start = c;
        else if (name == "end_s")
          col_end = c;
        else if (name == "table_rate_dps")
          col_rate = c;
        else if (name == "input")
          col_input = c;
        else {
          return MakeError(path, line_no, c + 1,
                           fmt::format("unknown column '{}'; {}", f[i], kExample));
        }
      }
      if (col_kind < 0 || col_start < 0 || col_end < 0) {
        return MakeError(path, line_no, 1,
                         fmt::format("the header needs kind, start_s and end_s; {}", kExample));
      }
      columns = f.size();
      continue;
    }
    if (f.size() != columns) {
      return MakeError(
          path, line_no, static_cast<int64_t>(std::min(f.size(), columns)) + 1,
          fmt::format("{} fields where the header has {}; {}", f.size(), columns, kExample));
    }
    AnnotatedSegment a;
    a.line = line_no;
    const std::string& kind = f[static_cast<size_t>(col_kind)];
    if (kind == "static") {
      a.kind = SegmentKind::kStatic;
    } else if (kind == "rotation") {
      a.kind = SegmentKind::kRotation;
    } else if (kind == "table") {
      a.kind = SegmentKind::kTable;
    } else {
      return MakeError(path, line_no, col_kind + 1,
                       fmt::format("kind '{}'; expected static, rotation or table", kind));
    }
    if (!ParseNumber(f[static_cast<size_t>(col_start)], &a.start_s)) {
      return MakeError(
          path, line_no, col_start + 1,
          fmt::format("start_s '{}' is not a number [s]", f[static_cast<size_t>(col_start)]));
    }
    if (!ParseNumber(f[static_cast<size_t>(col_end)], &a.end_s)) {
      return MakeError(
          path, line_no, col_end + 1,
          fmt::format("end_s '{}' is not a number [s]", f[static_cast<size_t>(col_end)]));
    }
    if (!(a.end_s > a.start_s)) {
      return MakeError(path, line_no, col_end + 1,
                       fmt::format("end_s {} is not after start_s {}", a.end_s, a.start_s));
    }
    if (a.kind == SegmentKind::kTable) {
      double rate = 0;
      if (col_rate < 0 || !ParseNumber(f[static_cast<size_t>(col_rate)], &rate) || rate == 0.0) {
        return MakeError(path, line_no, col_rate < 0 ? 1 : col_rate + 1,
                         "a table segment needs a non-zero table_rate_dps [deg/s] (the table's "
                         "signed rate), e.g. 'table,7.0,17.0,30'");
      }
      a.table_rate_dps = rate;
    }
    if (col_input >= 0 && !f[static_cast<size_t>(col_input)].empty()) {
      double input = 0;
      if (!ParseNumber(f[static_cast<size_t>(col_input)], &input) || input < 1 ||
          input != std::floor(input) || input > 1e6) {
        return MakeError(path, line_no, col_input + 1,
                         fmt::format("input '{}'; expected the 1-based index of a SESSION argument",
                                     f[static_cast<size_t>(col_input)]));
      }
      a.input = static_cast<int>(input) - 1;
    }
    out.push_back(a);
  }
  if (col_kind < 0) return MakeError(path, 1, 1, fmt::format("no header; {}", kExample));
  if (std::none_of(out.begin(), out.end(),
                   [](const AnnotatedSegment& a) { return a.kind == SegmentKind::kStatic; })) {
    return MakeError(path, line_no, 0, "no static segment; a calibration needs static poses");
  }
  return out;
}

Result<SegmentationSummary> SegmentsFromAnnotations(const SegmentationInput& input,
                                                    const std::vector<AnnotatedSegment>& all,
                                                    const std::string& path) {
  METRO_CHECK(input.t_s != nullptr && !input.t_s->empty());
  const std::vector<double>& t = *input.t_s;
  SegmentationSummary summary;
  std::vector<Segment> segments;
  for (const AnnotatedSegment& a : all) {
    if (a.input != input.piece) continue;
    const size_t b =
        static_cast<size_t>(std::lower_bound(t.begin(), t.end(), a.start_s) - t.begin());
    const size_t e = static_cast<size_t>(std::upper_bound(t.begin(), t.end(), a.end_s) - t.begin());
    if (e < b + 2) {
      return MakeError(path, a.line, 0,
                       fmt::format("{} segment {} .. {} s holds {} samples of input {} (t_s {} .. "
                                   "{} s); expected at least 2",
                                   SegmentKindName(a.kind), a.start_s, a.end_s, e > b ? e - b : 0,
                                   input.piece + 1, t.front(), t.back()));
    }
    Segment s;
    s.kind = a.kind;
    s.piece = input.piece;
    s.begin = b;
    s.end = e;
    s.start_s = t[b];
    s.end_s = t[e - 1];
    s.table_rate_dps = a.table_rate_dps;
    s.note = fmt::format("annotated ({} line {})", path, a.line);
    segments.push_back(s);
  }
  std::sort(segments.begin(), segments.end(),
            [](const Segment& x, const Segment& y) { return x.begin < y.begin; });
  // No overlap between two segments of one kind (a table run may lie inside a rotation).
  for (SegmentKind kind : {SegmentKind::kStatic, SegmentKind::kRotation, SegmentKind::kTable}) {
    const Segment* prev = nullptr;
    for (const Segment& s : segments) {
      if (s.kind != kind) continue;
      if (prev != nullptr && s.begin < prev->end) {
        return MakeError(path, 0, 0,
                         fmt::format("{} segments {} .. {} s and {} .. {} s of input {} overlap",
                                     SegmentKindName(kind), prev->start_s, prev->end_s, s.start_s,
                                     s.end_s, input.piece + 1));
      }
      prev = &s;
    }
  }
  // Rotations between consecutive static segments where none is annotated there.
  std::vector<Segment> statics;
  for (const Segment& s : segments) {
    if (s.kind == SegmentKind::kStatic) statics.push_back(s);
  }
  for (size_t i = 0; i + 1 < statics.size(); ++i) {
    const size_t b = statics[i].end, e = statics[i + 1].begin;
    if (e <= b) continue;
    const bool annotated = std::any_of(segments.begin(), segments.end(), [&](const Segment& s) {
      return s.kind == SegmentKind::kRotation && s.begin < e && s.end > b;
    });
    if (annotated) continue;
    Segment r;
    r.kind = SegmentKind::kRotation;
    r.piece = input.piece;
    r.begin = b;
    r.end = e;
    r.start_s = t[b];
    r.end_s = t[e - 1];
    segments.push_back(r);
  }
  std::sort(segments.begin(), segments.end(),
            [](const Segment& x, const Segment& y) { return x.begin < y.begin; });
  int pose = 0;
  for (Segment& s : segments) {
    if (s.kind == SegmentKind::kStatic) {
      s.pose = pose++;
      ++summary.static_count;
    }
    if (s.kind == SegmentKind::kTable) ++summary.table_count;
    if (s.kind == SegmentKind::kRotation) ++summary.rotation_count;
  }
  summary.pose_count = pose;
  summary.segments = std::move(segments);
  return summary;
}

}  // namespace metro
