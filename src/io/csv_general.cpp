// session.csv's general path: every dialect (ColumnPlan), strict and lenient, exact errors.
//
// Worker threads parse blocks into row-major buffers, then one sequential pass moves the
// rows, in file order, into the per-tag columns, checking time order per tag, so strict and
// lenient loads behave exactly as a one-thread reader would, whatever the thread count, and
// every error names its line and field.
//
// LoadGeneralCsv runs these stages, in this order:
//
//   parse    ParseBlocks                     blocks on all cores (ParseBlock, ParseRow)
//   columns  TimingOf, MakeBuilders,         how rows are timed; per-tag columns sized
//            NewSession                      exactly; the session's columns
//   rows     RowMover::MoveBlock, RowTime,   the sequential pass, block by block
//            Reject
//   tags     FinishTags, SecondsFromOrigin   times in seconds, scaled and text columns
//   warnings AddTimingWarnings               E-notation resolution, untimed rejections
#include <fast_float/fast_float.h>
#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <string>

#include "core/parallel.hpp"
#include "core/plain_decimal.hpp"
#include "io/csv_blocks.hpp"
#include "io/session_internal.hpp"

namespace metro::internal {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

inline void Trim(const char*& b, const char*& e) {
  while (b < e && (*b == ' ' || *b == '\t')) ++b;
  while (e > b && (e[-1] == ' ' || e[-1] == '\t')) --e;
}

inline void Unquote(const char*& b, const char*& e) {
  if (e - b >= 2 && *b == '"' && e[-1] == '"') {
    ++b;
    --e;
  }
}

std::string Printable(const char* b, const char* e) {
  std::string s(b, static_cast<size_t>(std::min<ptrdiff_t>(e - b, 40)));
  for (char& c : s) {
    if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) >= 0x7F) c = '?';
  }
  if (e - b > 40) s += "...";
  return s;
}

// Numbers as the dialect writes them.
class NumberSyntax {
 public:
  explicit NumberSyntax(const InputDialect& d)
      : delimiter_(d.delimiter),
        decimal_point_(d.decimal_point),
        options_(fast_float::chars_format::general, d.decimal_point) {}

  char delimiter() const { return delimiter_; }

  // The number at the start of [p, e): its end, or nullptr.
  const char* Prefix(const char* p, const char* e, double* out) const {
    if (decimal_point_ == '.') {
      if (const char* end = PlainDecimal(p, e, out)) return end;
    }
    const auto r = fast_float::from_chars_advanced(p, e, *out, options_);
    if (r.ec != std::errc() || r.ptr == p) return nullptr;
    return r.ptr;
  }

  // A whole field as a finite double. False (with a reason) otherwise.
  bool Field(const char* b, const char* e, double* out, const char** why) const {
    if (b == e) {
      *why = "empty";
      return false;
    }
    if (*b == '+') ++b;
    const char* end = Prefix(b, e, out);
    if (end != e) {
      *why = "not a number";
      return false;
    }
    if (!std::isfinite(*out)) {
      *why = "not finite";
      return false;
    }
    return true;
  }

  // An integer time field (ns_per_unit ns per unit) exactly in ns; decimal commas read.
  bool TimeNs(const char* b, const char* e, int64_t ns_per_unit, int64_t* ns,
              int64_t* resolution_ns, const char** why) const {
    if (b == e) {
      *why = "empty";
      return false;
    }
    if (decimal_point_ == '.') return ParseExactTimeNs(b, e, ns_per_unit, ns, resolution_ns, why);
    std::string copy(b, e);
    std::replace(copy.begin(), copy.end(), decimal_point_, '.');
    return ParseExactTimeNs(copy.data(), copy.data() + copy.size(), ns_per_unit, ns, resolution_ns,
                            why);
  }

 private:
  char delimiter_;
  char decimal_point_;
  fast_float::parse_options options_;
};

// Fast path for one numeric field: a number directly at `p` followed by the delimiter (or
// the end of the line for the last field), no spaces, finite. Returns the position after
// the delimiter, or nullptr if the field needs the careful path.
inline const char* FastNumber(const NumberSyntax& syntax, const char* p, const char* e, bool last,
                              double* out) {
  const char* end = syntax.Prefix(p, e, out);
  if (end == nullptr) return nullptr;
  if (last ? end != e : (end == e || *end != syntax.delimiter())) return nullptr;
  if (!std::isfinite(*out)) return nullptr;
  return end + 1;
}

// The end of the field starting at `p`: the delimiter after it (outside double quotes), or
// `e`.
const char* FieldEnd(const char* p, const char* e, char delimiter) {
  const char* q = p;
  while (q < e && (*q == ' ' || *q == '\t')) ++q;
  if (q < e && *q == '"') {
    for (++q; q < e; ++q) {
      if (*q == '"') {
        if (q + 1 < e && q[1] == '"') {
          ++q;
          continue;
        }
        break;
      }
    }
    const void* d = q < e ? std::memchr(q, delimiter, static_cast<size_t>(e - q)) : nullptr;
    return d != nullptr ? static_cast<const char*>(d) : e;
  }
  const void* d = p < e ? std::memchr(p, delimiter, static_cast<size_t>(e - p)) : nullptr;
  return d != nullptr ? static_cast<const char*>(d) : e;
}

// The time field [fb, fe) on the careful path, into *t (t_s) or *t_ns (an integer time
// column). Returns false if it is bad (recorded in block->bad).
bool CarefulTime(const ColumnPlan& plan, const NumberSyntax& syntax, const char* fb, const char* fe,
                 uint32_t local_line, Block* block, double* t, int64_t* t_ns) {
  const int f = plan.time_field;
  const std::string& name = plan.names[static_cast<size_t>(f)];
  const char* why = nullptr;
  if (plan.time_ns_per_unit != 0) {
    int64_t resolution_ns = 0;
    if (!syntax.TimeNs(fb, fe, plan.time_ns_per_unit, t_ns, &resolution_ns, &why)) {
      block->bad.push_back(
          {local_line, f + 1,
           fmt::format("{}: expected a time in whole {} (integer, or a decimal down to 1 "
                       "ns), found '{}' ({})",
                       name, name.substr(2), Printable(fb, fe), why)});
      return false;
    }
    // Only a resolution coarser than the column's unit is a loss worth a warning.
    if (resolution_ns > plan.time_ns_per_unit) {
      block->time_resolution_ns = std::max(block->time_resolution_ns, resolution_ns);
    }
  } else if (!syntax.Field(fb, fe, t, &why)) {
    block->bad.push_back({local_line, f + 1,
                          fmt::format("t_s: expected a finite time in seconds, found '{}' ({})",
                                      Printable(fb, fe), why)});
    return false;
  }
  return true;
}

// Parses one data line into the block. Returns false if the row is bad (recorded).
bool ParseRow(const ColumnPlan& plan, const NumberSyntax& syntax, const char* b, const char* e,
              uint32_t local_line, Block* block, std::vector<double>* numeric_row,
              std::vector<std::string>* text_row) {
  const int nf = static_cast<int>(plan.names.size());
  const char delimiter = syntax.delimiter();
  const bool integer_time = plan.time_ns_per_unit != 0;
  const char* p = b;
  double t = 0.0;
  int64_t t_ns = 0;
  int sensor = 1;
  for (int f = 0; f < nf; ++f) {
    const bool last = f == nf - 1;
    const size_t uf = static_cast<size_t>(f);
    const bool kept = !plan.names[uf].empty();
    // Fast path: most fields are plain numbers.
    if (kept && p < e && plan.info[uf].role != ColumnRole::kText &&
        plan.info[uf].role != ColumnRole::kUnknown && !(integer_time && f == plan.time_field)) {
      double v;
      const char* next = FastNumber(syntax, p, e, last, &v);
      if (next != nullptr) {
        if (f == plan.time_field) {
          t = v;
          p = next;
          continue;
        }
        if (f == plan.sensor_field) {
          if (v == std::floor(v) && v >= 1.0 && v <= 255.0) {
            sensor = static_cast<int>(v);
            p = next;
            continue;
          }
        } else {
          (*numeric_row)[static_cast<size_t>(plan.numeric_slot[uf])] = v;
          p = next;
          continue;
        }
      }
    }
    // Careful path: find the field, trim it, and say precisely what is wrong.
    const char* fb = p;
    const char* fe = FieldEnd(p, e, delimiter);
    const bool at_delimiter = fe < e;
    if (!at_delimiter && !last) {
      block->bad.push_back(
          {local_line, f + 2,
           fmt::format("missing field: expected {} fields ({}), found {}", nf,
                       fmt::join(plan.source_names, std::string(1, delimiter)), f + 1)});
      return false;
    }
    if (last && at_delimiter) {
      int found = nf + 1;
      for (const char* q = FieldEnd(fe + 1, e, delimiter); q < e;
           q = FieldEnd(q + 1, e, delimiter)) {
        ++found;
      }
      block->bad.push_back(
          {local_line, nf + 1, fmt::format("expected {} fields, found {}", nf, found)});
      return false;
    }
    p = fe + 1;
    if (!kept) continue;  // A column left out (--column 'SRC=').
    Trim(fb, fe);
    Unquote(fb, fe);
    const char* why = nullptr;
    if (f == plan.time_field) {
      if (!CarefulTime(plan, syntax, fb, fe, local_line, block, &t, &t_ns)) return false;
    } else if (f == plan.sensor_field) {
      double v = 0.0;
      if (!syntax.Field(fb, fe, &v, &why) || v != std::floor(v) || v < 1.0 || v > 255.0) {
        block->bad.push_back(
            {local_line, f + 1,
             fmt::format("sensor: expected a tag number 1..255, found '{}'", Printable(fb, fe))});
        return false;
      }
      sensor = static_cast<int>(v);
    } else if (plan.numeric_slot[uf] >= 0) {
      double v = kNaN;
      if (fb == fe && plan.info[uf].allow_empty) {
        v = kNaN;
      } else if (!syntax.Field(fb, fe, &v, &why)) {
        block->bad.push_back(
            {local_line, f + 1,
             fmt::format("{}: expected a finite number{}, found '{}' ({})", plan.names[uf],
                         plan.info[uf].allow_empty ? " or an empty field" : "", Printable(fb, fe),
                         why)});
        return false;
      }
      (*numeric_row)[static_cast<size_t>(plan.numeric_slot[uf])] = v;
    } else {
      (*text_row)[static_cast<size_t>(plan.text_slot[uf])].assign(fb, fe);
    }
  }
  block->sensor.push_back(static_cast<uint8_t>(sensor));
  if (integer_time) {
    block->t_ns.push_back(t_ns);
  } else {
    block->t_s.push_back(t);
  }
  block->local_line.push_back(local_line);
  block->numeric.insert(block->numeric.end(), numeric_row->begin(), numeric_row->end());
  for (auto& s : *text_row) block->text.push_back(std::move(s));
  return true;
}

void ParseBlock(const MappedFile& file, const ColumnPlan& plan, bool lenient, Block* block) {
  const char* data = file.data();
  const char* p = data + block->begin;
  const char* end = data + block->end;
  const NumberSyntax syntax(plan.dialect);
  const char line_end = plan.dialect.line_ends == "CR" ? '\r' : '\n';
  std::vector<double> numeric_row(plan.numeric_fields.size(), kNaN);
  std::vector<std::string> text_row(plan.text_fields.size());
  // Rough reserve: ~ one row per 40 bytes.
  const size_t guess = static_cast<size_t>(end - p) / 40 + 16;
  if (plan.time_ns_per_unit != 0) {
    block->t_ns.reserve(guess);
  } else {
    block->t_s.reserve(guess);
  }
  block->sensor.reserve(guess);
  block->local_line.reserve(guess);
  block->numeric.reserve(guess * plan.numeric_fields.size());
  uint32_t line = 0;
  while (p < end) {
    const char* nl =
        static_cast<const char*>(std::memchr(p, line_end, static_cast<size_t>(end - p)));
    const char* le = nl != nullptr ? nl : end;
    const char* lb = p;
    p = nl != nullptr ? nl + 1 : end;
    const uint32_t this_line = line++;
    const char* te = le;
    if (te > lb && te[-1] == '\r') --te;
    const char* first = lb;
    while (first < te && (*first == ' ' || *first == '\t')) ++first;
    if (first == te || *first == '#') continue;  // Blank or comment line.
    if (std::memchr(lb, '\0', static_cast<size_t>(te - lb)) != nullptr) {
      block->bad.push_back({this_line, 0, "binary data (NUL byte) in a text line"});
      if (!lenient) break;
      continue;
    }
    if (!ParseRow(plan, syntax, lb, te, this_line, block, &numeric_row, &text_row) && !lenient) {
      break;
    }
  }
  // Lines are counted to the end of the block even after a strict-mode stop, because the
  // next block's line numbers depend on it.
  while (p < end) {
    const char* nl =
        static_cast<const char*>(std::memchr(p, line_end, static_cast<size_t>(end - p)));
    ++line;
    p = nl != nullptr ? nl + 1 : end;
  }
  block->lines = line;
  block->parsed = true;
}

struct TagBuilder {
  Tag tag;
  double last_t = -std::numeric_limits<double>::infinity();
  int64_t last_ns = std::numeric_limits<int64_t>::min();
  uint32_t last_line = 0;
  std::vector<std::vector<std::string>> text;
};

// The columns of a raw count (plan.raw_scale) in physical units beside it, origin derived.
void AddScaledRawColumns(const ColumnPlan& plan, Tag* tag) {
  for (size_t q = 0; q < plan.raw_scale.size(); ++q) {
    if (plan.raw_scale[q] == 0.0) continue;
    const Quantity& counts = tag->quantities[q];
    const ColumnInfo info = ClassifyColumn(plan.raw_scaled_name[q]);
    Quantity scaled{plan.raw_scaled_name[q], info.UnitSymbol(), QuantityOrigin::kDerived,
                    std::vector<double>(counts.values.size())};
    for (size_t i = 0; i < counts.values.size(); ++i) {
      scaled.values[i] = counts.values[i] * plan.raw_scale[q];
    }
    tag->quantities.push_back(std::move(scaled));
  }
}

// ---- parse --------------------------------------------------------------------------------

// Parse blocks in parallel. In strict mode, blocks after the first one with an error
// are never reached by the sequential pass, so they need not be parsed.
void ParseBlocks(const MappedFile& file, const ColumnPlan& plan, const LoadOptions& options,
                 int threads, std::vector<Block>* cut, BlockProgress* progress,
                 ReleaseBehind* release) {
  std::vector<Block>& blocks = *cut;
  std::atomic<size_t> first_bad_block{blocks.size()};
  release->StartPass(BlockBegins(blocks), BlockEnds(blocks));
  ParallelFor(blocks.size(), threads, [&](size_t i) {
    if (!options.lenient && i > first_bad_block.load()) {
      release->BlockDone(i);  // Never read: the sequential pass stops before it.
      return;
    }
    ParseBlock(file, plan, options.lenient, &blocks[i]);
    release->BlockDone(i);
    progress->Parsed(i, blocks[i].begin, blocks[i].end);
    if (!options.lenient && !blocks[i].bad.empty()) {
      size_t cur = first_bad_block.load();
      while (i < cur && !first_bad_block.compare_exchange_weak(cur, i)) {
      }
    }
  });
}

// ---- columns ------------------------------------------------------------------------------

// How the rows are timed.
struct Timing {
  bool rate_time = false;  // No time column: sample k of a tag is at k / rate.
  // Rate-timed: integer time too when the period is a whole number of nanoseconds (100 Hz:
  // 10,000,000 ns), so tau0 is exactly 1 / rate, not a difference of doubles k / rate.
  double rate_period_ns = 0.0;
  bool rate_integer = false;
  bool integer_time = false;  // Times held in t_ns (integer time column or rate_integer).
  std::string time_name;      // The time column's name; empty when rate-timed.
};

Timing TimingOf(const ColumnPlan& plan) {
  Timing timing;
  timing.rate_time = plan.time_field < 0;
  timing.rate_period_ns = timing.rate_time ? 1e9 / plan.rate_hz : 0.0;
  timing.rate_integer = timing.rate_time &&
                        timing.rate_period_ns == std::round(timing.rate_period_ns) &&
                        timing.rate_period_ns < 9e15;
  timing.integer_time = plan.time_ns_per_unit != 0 || timing.rate_integer;
  timing.time_name =
      timing.rate_time ? std::string() : plan.names[static_cast<size_t>(plan.time_field)];
  return timing;
}

// One builder per sensor 1..255 that has rows (nullptr for the others).
using Builders = std::vector<std::unique_ptr<TagBuilder>>;

// The builders, their columns sized exactly from the rows counted per sensor.
Builders MakeBuilders(const std::vector<Block>& blocks, const ColumnPlan& plan,
                      const Timing& timing) {
  std::vector<int64_t> per_sensor(256, 0);
  for (const Block& b : blocks) {
    if (!b.parsed) break;
    for (uint8_t s : b.sensor) ++per_sensor[s];
  }
  Builders builders(256);
  const size_t nq = plan.numeric_fields.size();
  const size_t nt = plan.text_fields.size();
  for (int s = 1; s < 256; ++s) {
    if (per_sensor[s] == 0) continue;
    auto tb = std::make_unique<TagBuilder>();
    tb->tag.sensor = s;
    const size_t rows = static_cast<size_t>(per_sensor[s]);
    tb->tag.t_s.reserve(rows);
    if (timing.integer_time) tb->tag.t_ns.reserve(rows);
    tb->tag.line.reserve(rows);
    for (size_t q = 0; q < nq; ++q) {
      Quantity quantity;
      const size_t f = static_cast<size_t>(plan.numeric_fields[q]);
      quantity.name = plan.names[f];
      quantity.unit = plan.info[f].UnitSymbol();
      quantity.origin = QuantityOrigin::kFile;
      quantity.values.reserve(rows);
      tb->tag.quantities.push_back(std::move(quantity));
    }
    tb->text.resize(nt);
    builders[static_cast<size_t>(s)] = std::move(tb);
  }
  return builders;
}

// The session before its rows: path, format, dialect, columns.
Session NewSession(const std::string& path, const ColumnPlan& plan) {
  Session session;
  session.path = path;
  session.format = plan.format;
  session.input = plan.dialect;
  for (size_t f = 0; f < plan.names.size(); ++f) {
    if (plan.names[f].empty()) continue;
    session.columns.push_back(plan.names[f]);
    if (plan.info[f].role == ColumnRole::kUnknown) session.unknown_columns.push_back(plan.names[f]);
  }
  return session;
}

// ---- rows ---------------------------------------------------------------------------------

// The sequential pass: each block's rows, in file order, into the tags' columns, checking
// time order per tag; a bad row is an error (strict) or counted and kept aside (lenient).
class RowMover {
 public:
  RowMover(const std::string& path, const ColumnPlan& plan, const LoadOptions& options,
           const Timing& timing, Builders* builders, Session* session)
      : path_(path),
        plan_(plan),
        options_(options),
        timing_(timing),
        builders_(*builders),
        session_(*session) {}

  // The rows of block b, whose first line is first_line.
  Status MoveBlock(int64_t first_line, Block* block) {
    Block& b = *block;
    const size_t nq = plan_.numeric_fields.size();
    const size_t nt = plan_.text_fields.size();
    size_t bad_i = 0;
    const size_t rows = b.sensor.size();
    for (size_t r = 0; r <= rows; ++r) {
      const uint32_t row_line = r < rows ? b.local_line[r] : UINT32_MAX;
      while (bad_i < b.bad.size() && b.bad[bad_i].local_line < row_line) {
        const BadRow& bad = b.bad[bad_i++];
        if (Status s = Reject(first_line + bad.local_line, bad.field, bad.message); !s.ok()) {
          return s;
        }
        if (timing_.rate_time && plan_.sensor_field < 0) ++slots_[1];
      }
      if (r == rows) break;
      TagBuilder& tb = *builders_[b.sensor[r]];
      const int64_t line = first_line + b.local_line[r];
      double t = 0.0;
      int64_t t_ns = 0;
      Result<bool> timed = RowTime(b, r, line, &tb, &t, &t_ns);
      if (!timed.ok()) return timed.error();
      if (!timed.value()) continue;
      if (line > kMaxLineNumber) return TooManyLinesError(path_, line);
      ++session_.rows;
      tb.last_line = static_cast<uint32_t>(line);
      if (timing_.integer_time) {
        tb.tag.t_ns.push_back(t_ns);
      } else {
        tb.tag.t_s.push_back(t);
      }
      tb.tag.line.push_back(static_cast<uint32_t>(line));
      const double* row = b.numeric.data() + r * nq;
      for (size_t q = 0; q < nq; ++q) tb.tag.quantities[q].values.push_back(row[q]);
      for (size_t k = 0; k < nt; ++k) tb.text[k].push_back(std::move(b.text[r * nt + k]));
    }
    return Status::Ok();
  }

  // Rejected rows of a rate-timed file with a sensor column (their tags' clocks stood still).
  int64_t rejected_untimed() const { return rejected_untimed_; }

 private:
  // Rate-timed files: a rejected row of a file without a sensor column was still a sample
  // of tag 1, so its clock advances; with a sensor column the tag of a bad row is unknown.
  Status Reject(int64_t line, int field, const std::string& message) {
    if (!options_.lenient) return MakeError(path_, line, field, message);
    ++session_.rejected_rows;
    ++session_.rows;
    if (timing_.rate_time) ++rejected_untimed_;
    if (session_.rejected_lines.size() < options_.max_rejected_kept) {
      session_.rejected_lines.push_back(line);
      session_.rejected_reasons.push_back(message);
    }
    return Status::Ok();
  }

  // The time of row r of b (on `line`, of tag tb) in *t or *t_ns: true, or false when the
  // row was rejected as out of time order.
  Result<bool> RowTime(const Block& b, size_t r, int64_t line, TagBuilder* tb, double* t,
                       int64_t* t_ns) {
    const std::string& time_name = timing_.time_name;
    if (timing_.rate_integer) {
      if (__builtin_mul_overflow(slots_[b.sensor[r]]++,
                                 static_cast<int64_t>(timing_.rate_period_ns), t_ns)) {
        return MakeError(path_, line,
                         fmt::format("sample {} at {} Hz is beyond 2^63 ns (292 years) of "
                                     "time: check the rate",
                                     slots_[b.sensor[r]] - 1, plan_.rate_hz));
      }
    } else if (timing_.rate_time) {
      *t = static_cast<double>(slots_[b.sensor[r]]++) / plan_.rate_hz;
    } else if (timing_.integer_time) {
      const int64_t ns = b.t_ns[r];
      if (!(ns > tb->last_ns)) {
        const std::string message = fmt::format(
            "{} = {} is not after {} = {} of sensor {} on line {}: rows must be sorted by "
            "strictly increasing time per tag",
            time_name, ns / plan_.time_ns_per_unit, time_name, tb->last_ns / plan_.time_ns_per_unit,
            b.sensor[r], tb->last_line);
        if (Status s = Reject(line, plan_.time_field + 1, message); !s.ok()) return s.error();
        return false;
      }
      tb->last_ns = ns;
      *t_ns = ns;
    } else {
      *t = b.t_s[r];
      if (!(*t > tb->last_t)) {
        const std::string message = fmt::format(
            "t_s = {} is not after t_s = {} of sensor {} on line {}: rows must be sorted by "
            "strictly increasing time per tag",
            *t, tb->last_t, b.sensor[r], tb->last_line);
        if (Status s = Reject(line, plan_.time_field + 1, message); !s.ok()) return s.error();
        return false;
      }
      tb->last_t = *t;
    }
    return true;
  }

  const std::string& path_;
  const ColumnPlan& plan_;
  const LoadOptions& options_;
  const Timing& timing_;
  Builders& builders_;
  Session& session_;
  std::vector<int64_t> slots_ = std::vector<int64_t>(256, 0);  // Rate-timed: next sample.
  int64_t rejected_untimed_ = 0;
};

// The parsed blocks' rows into the tags, in file order (up to the first block not parsed);
// *first_line follows the blocks, *resolution_ns keeps the coarsest time resolution seen.
// Each block's buffers are freed as soon as it is moved.
Status MoveParsedBlocks(RowMover* mover, std::vector<Block>* blocks, int64_t* first_line,
                        int64_t* resolution_ns) {
  for (Block& b : *blocks) {
    if (!b.parsed) break;
    *resolution_ns = std::max(*resolution_ns, b.time_resolution_ns);
    if (Status s = mover->MoveBlock(*first_line, &b); !s.ok()) return s;
    *first_line += b.lines;
    b = Block();
  }
  return Status::Ok();
}

// ---- tags ---------------------------------------------------------------------------------

// Integer time: seconds of tag `sensor` from the session's first time, from exact differences.
Status SecondsFromOrigin(const std::string& path, const std::string& time_name, int sensor,
                         int64_t origin_ns, Tag* tag) {
  tag->t_s.resize(tag->t_ns.size());
  for (size_t i = 0; i < tag->t_ns.size(); ++i) {
    int64_t since_origin_ns = 0;
    if (__builtin_sub_overflow(tag->t_ns[i], origin_ns, &since_origin_ns)) {
      return MakeError(path, tag->line[i],
                       "the session's times span more than 2^63 ns (292 years): expected "
                       "one clock");
    }
    // Correctly rounded: one division of two exactly representable integers.
    tag->t_s[i] = static_cast<double>(since_origin_ns) / 1e9;
    // Far from the origin, times a few ns apart are one double of seconds: Tag::t_s
    // must still increase strictly.
    if (i > 0 && !(tag->t_s[i] > tag->t_s[i - 1])) {
      return MakeError(
          path, tag->line[i],
          fmt::format("{} = {} is {} ns after the previous time of sensor {} but {:g} s "
                      "from the session's first time: closer than seconds in a double "
                      "resolve there; expected one clock for the whole session",
                      time_name.empty() ? std::string("time") : time_name, tag->t_ns[i],
                      tag->t_ns[i] - tag->t_ns[i - 1], sensor, tag->t_s[i]));
    }
  }
  return Status::Ok();
}

// The built tags, in sensor order, into the session: times in seconds, scaled raw columns,
// text and unknown columns, counts.
Status FinishTags(const std::string& path, const ColumnPlan& plan, const Timing& timing,
                  Builders* builders, Session* session) {
  int64_t origin_ns = std::numeric_limits<int64_t>::max();
  if (timing.integer_time) {
    for (const auto& tb : *builders) {
      if (tb != nullptr && !tb->tag.t_ns.empty()) origin_ns = std::min(origin_ns, tb->tag.t_ns[0]);
    }
    session->input.time_origin_ns = origin_ns;
    session->input.time_integer = true;
  }
  for (int s = 1; s < 256; ++s) {
    TagBuilder* tb = (*builders)[static_cast<size_t>(s)].get();
    if (tb == nullptr || tb->tag.line.empty()) continue;
    if (timing.integer_time) {
      Status seconds = SecondsFromOrigin(path, timing.time_name, s, origin_ns, &tb->tag);
      if (!seconds.ok()) return seconds;
    }
    AddScaledRawColumns(plan, &tb->tag);
    for (size_t k = 0; k < plan.text_fields.size(); ++k) {
      const size_t f = static_cast<size_t>(plan.text_fields[k]);
      AddTextOrUnknownColumn(plan.names[f], plan.info[f].role == ColumnRole::kUnknown,
                             plan.info[f].UnitSymbol(), std::move(tb->text[k]), &tb->tag);
    }
    tb->tag.counts.frames = tb->tag.counts.fresh = static_cast<int64_t>(tb->tag.t_s.size());
    session->tags.push_back(std::move(tb->tag));
  }
  return Status::Ok();
}

// The warnings on the times: E-notation's resolution, rejected rows of a rate-timed file.
void AddTimingWarnings(const ColumnPlan& plan, const Timing& timing, int64_t resolution_ns,
                       int64_t rejected_untimed, Session* session) {
  if (resolution_ns > 0) {
    session->input.time_resolution_s = static_cast<double>(resolution_ns) / 1e9;
    session->input.warnings.push_back(fmt::format(
        "{} is written in E-notation (a spreadsheet round trip?): its last digits are gone, "
        "so times are resolved to {} ns ({:g} s) only; sample periods, gaps and Allan tau0 "
        "are good to that resolution",
        timing.time_name, resolution_ns, session->input.time_resolution_s));
  }
  if (timing.rate_time && rejected_untimed > 0 && plan.sensor_field >= 0) {
    session->input.warnings.push_back(fmt::format(
        "{} rows were rejected in a file timed by --rate-hz with a sensor column: the tag of a "
        "rejected row is unknown, so its clock did not advance and later times of that tag "
        "are early by one period per rejected row",
        rejected_untimed));
  }
}

}  // namespace

std::vector<Block> CutBlocks(const MappedFile& file, size_t data_begin, size_t data_end,
                             char line_end, int threads) {
  std::vector<Block> blocks;
  const size_t size = data_end;
  if (data_begin >= size) return blocks;
  const size_t span = size - data_begin;
  const size_t target = std::clamp<size_t>(span / (static_cast<size_t>(threads) * 16),
                                           size_t{1} << 20, size_t{8} << 20);
  size_t begin = data_begin;
  while (begin < size) {
    size_t end = std::min(size, begin + target);
    if (end < size) {
      const char* nl =
          static_cast<const char*>(std::memchr(file.data() + end, line_end, size - end));
      end = nl != nullptr ? static_cast<size_t>(nl - file.data()) + 1 : size;
    }
    Block block;
    block.begin = begin;
    block.end = end;
    blocks.push_back(std::move(block));
    begin = end;
  }
  return blocks;
}

Result<Session> LoadGeneralCsv(const std::string& path, const MappedFile& file,
                               const HeaderLine& header, const ColumnPlan& plan,
                               const LoadOptions& options, int threads, std::vector<Block>* cut,
                               BlockProgress* progress, ReleaseBehind* release) {
  std::vector<Block>& blocks = *cut;
  ParseBlocks(file, plan, options, threads, &blocks, progress, release);
  const Timing timing = TimingOf(plan);
  Builders builders = MakeBuilders(blocks, plan, timing);
  Session session = NewSession(path, plan);

  // Sequential pass in file order.
  RowMover mover(path, plan, options, timing, &builders, &session);
  int64_t first_line = header.line_number + 1;
  int64_t resolution_ns = 0;
  if (Status s = MoveParsedBlocks(&mover, &blocks, &first_line, &resolution_ns); !s.ok()) {
    return s.error();
  }

  if (Status s = FinishTags(path, plan, timing, &builders, &session); !s.ok()) return s.error();
  AddTimingWarnings(plan, timing, resolution_ns, mover.rejected_untimed(), &session);
  if (session.tags.empty()) {
    if (session.rejected_rows > 0) {
      return MakeError(path, 0,
                       fmt::format("no valid data rows: all {} rows were rejected (first: line "
                                   "{}: {})",
                                   session.rejected_rows, session.rejected_lines.front(),
                                   session.rejected_reasons.front()));
    }
    return MakeError(path, header.line_number,
                     "header only: no data rows after the header; expected one row per "
                     "observation");
  }
  return session;
}

namespace {

// The builders' rows so far as one group's tags (times in seconds from the session's
// origin, lines, numeric columns, scaled raw columns; no text), the builders emptied for the
// next group with their time-order state kept.
Status DrainGroup(const std::string& path, const ColumnPlan& plan, const Timing& timing,
                  int64_t origin_ns, Builders* builders, Session* group) {
  group->tags.clear();
  for (int s = 1; s < 256; ++s) {
    TagBuilder* tb = (*builders)[static_cast<size_t>(s)].get();
    if (tb == nullptr) continue;
    for (auto& text : tb->text) text.clear();
    if (tb->tag.line.empty()) continue;
    Tag tag;
    tag.sensor = s;
    // The builder's columns move to the group (no copy on the peak); the builder starts the
    // next group empty.
    tag.line = std::move(tb->tag.line);
    if (timing.integer_time) {
      tag.t_ns = std::move(tb->tag.t_ns);
      if (!tag.t_ns.empty() && tag.t_ns.front() < origin_ns) {
        return MakeError(path, tag.line.front(),
                         fmt::format("sensor {}'s first time is before the session's first row: "
                                     "the streaming mode needs rows in time order across tags; "
                                     "expected rows sorted by time (or run without --stream)",
                                     s));
      }
      if (Status sec = SecondsFromOrigin(path, timing.time_name, s, origin_ns, &tag); !sec.ok()) {
        return sec;
      }
    } else {
      tag.t_s = std::move(tb->tag.t_s);
    }
    tag.quantities.resize(tb->tag.quantities.size());
    for (size_t q = 0; q < tag.quantities.size(); ++q) {
      Quantity& from = tb->tag.quantities[q];
      tag.quantities[q].name = from.name;
      tag.quantities[q].unit = from.unit;
      tag.quantities[q].origin = from.origin;
      tag.quantities[q].values = std::move(from.values);
    }
    AddScaledRawColumns(plan, &tag);
    tag.counts.frames = tag.counts.fresh = static_cast<int64_t>(tag.line.size());
    group->tags.push_back(std::move(tag));
    tb->tag.t_s.clear();
    tb->tag.t_ns.clear();
    tb->tag.line.clear();
    for (Quantity& q : tb->tag.quantities) q.values.clear();
  }
  return Status::Ok();
}

// Builders for the sensors of `blocks` that have none yet.
void AddBuilders(const std::vector<Block>& blocks, const ColumnPlan& plan, const Timing& timing,
                 Builders* builders) {
  Builders fresh = MakeBuilders(blocks, plan, timing);
  for (size_t s = 0; s < fresh.size(); ++s) {
    if ((*builders)[s] == nullptr && fresh[s] != nullptr) (*builders)[s] = std::move(fresh[s]);
  }
}

}  // namespace

Result<Session> StreamGeneralCsv(const std::string& path, const MappedFile& file,
                                 const HeaderLine& header, const ColumnPlan& plan,
                                 const LoadOptions& options, size_t group_bytes,
                                 const std::function<Status(Session& group)>& on_group) {
  const int threads = ResolveThreads(options.threads);
  const char line_end = plan.dialect.line_ends == "CR" ? '\r' : '\n';
  const Timing timing = TimingOf(plan);
  Session session = NewSession(path, plan);
  Builders builders(256);
  RowMover mover(path, plan, options, timing, &builders, &session);
  ReleaseBehind release([&file](size_t begin, size_t end) { file.ReleaseBelow(begin, end); }, false,
                        0);
  int64_t first_line = header.line_number + 1;
  int64_t resolution_ns = 0;
  int64_t origin_ns = std::numeric_limits<int64_t>::max();
  Session group;
  group.path = path;
  size_t begin = header.data_begin;
  while (begin < plan.data_end) {
    // One group: about group_bytes, ending at a line end.
    size_t end = std::min(plan.data_end, begin + group_bytes);
    if (end < plan.data_end) {
      const char* nl =
          static_cast<const char*>(std::memchr(file.data() + end, line_end, plan.data_end - end));
      end = nl != nullptr ? static_cast<size_t>(nl - file.data()) + 1 : plan.data_end;
    }
    std::vector<Block> blocks = CutBlocks(file, begin, end, line_end, threads);
    BlockProgress progress(options.on_bytes_parsed, blocks.size());
    ParseBlocks(file, plan, options, threads, &blocks, &progress, &release);
    AddBuilders(blocks, plan, timing, &builders);
    if (Status s = MoveParsedBlocks(&mover, &blocks, &first_line, &resolution_ns); !s.ok()) {
      return s.error();
    }
    if (timing.integer_time && origin_ns == std::numeric_limits<int64_t>::max()) {
      for (const auto& tb : builders) {
        if (tb != nullptr && !tb->tag.t_ns.empty()) {
          origin_ns = std::min(origin_ns, tb->tag.t_ns[0]);
        }
      }
    }
    if (Status s = DrainGroup(path, plan, timing, origin_ns, &builders, &group); !s.ok()) {
      return s.error();
    }
    file.ReleaseBelow(begin, end);
    if (!group.tags.empty()) {
      if (Status s = on_group(group); !s.ok()) return s.error();
    }
    begin = end;
  }
  if (timing.integer_time) {
    session.input.time_origin_ns = origin_ns;
    session.input.time_integer = true;
  }
  AddTimingWarnings(plan, timing, resolution_ns, mover.rejected_untimed(), &session);
  if (session.rows == session.rejected_rows) {
    return MakeError(path, header.line_number,
                     session.rejected_rows > 0
                         ? "no valid data rows: all rows were rejected"
                         : "header only: no data rows after the header; expected one row per "
                           "observation");
  }
  return session;
}

}  // namespace metro::internal
