// session.csv loader.
//
// The file is memory-mapped and cut into line-aligned blocks. Clean files (the usual case:
// no malformed row, no text column, time increasing per tag) take one parallel pass: each
// block is parsed into a stage of per-tag columns in cache, runs of machine-written rows
// four fields per instruction (DecimalRows, AVX-512), and the stages are appended to the
// tag columns in file order as they complete.
// Anything irregular sends the file to the general loader: worker threads parse blocks
// into row-major buffers, then one sequential pass moves the rows, in file order, into the
// per-tag columns, checking time order per tag, so strict and lenient loads behave exactly
// as a one-thread reader would, whatever the thread count, and every error names its line.
// No buffer or column asks for transparent huge pages: on a VM whose host takes back free
// huge pages (virtio-balloon free page reporting), a cold huge page faults in at ~1 GB/s,
// and both loaders measured faster without them (docs/benchmarks.md, session 8).
// The mapping's pages are released behind the clean path (or the general loader) and the SHA-256
// hasher, whichever is slower (ReleaseBehind), so the file's pages give way to the parsed
// numbers and peak memory stays near the larger of the two (about 1.3 x the file for a
// clean session), not file + numbers, however fast the hasher runs.
#include <fast_float/fast_float.h>
#include <fcntl.h>
#include <fmt/format.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <condition_variable>
#include <cstring>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <new>
#include <optional>
#include <thread>

#include "core/parallel.hpp"
#include "core/plain_decimal.hpp"
#include "io/columns.hpp"
#include "io/decimal_rows.hpp"
#include "io/release_behind.hpp"
#include "io/session_internal.hpp"
#include "metro/core/check.hpp"
#include "metro/core/file.hpp"

namespace metro::internal {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// A read-only memory map of a whole file.
class MappedFile {
 public:
  MappedFile() = default;
  MappedFile(const MappedFile&) = delete;
  MappedFile& operator=(const MappedFile&) = delete;
  ~MappedFile() {
    if (data_ != nullptr) ::munmap(const_cast<char*>(data_), size_);
  }

  Status Open(const std::string& path) {
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) return MakeError(path, 0, std::string("cannot open: ") + std::strerror(errno));
    struct stat st {};
    if (::fstat(fd, &st) != 0 || S_ISDIR(st.st_mode)) {
      ::close(fd);
      return MakeError(path, 0, "is not a regular file");
    }
    size_ = static_cast<size_t>(st.st_size);
    if (size_ > 0) {
      void* p = ::mmap(nullptr, size_, PROT_READ, MAP_PRIVATE, fd, 0);
      if (p == MAP_FAILED) {
        ::close(fd);
        return MakeError(path, 0, std::string("cannot map: ") + std::strerror(errno));
      }
      data_ = static_cast<const char*>(p);
      ::madvise(p, size_, MADV_SEQUENTIAL);
    }
    ::close(fd);
    return Status::Ok();
  }

  // Drops the pages from the one holding `begin` to the last one wholly before `end`
  // (ReleaseBehind's ranges follow each other, so no page is left behind; a page dropped
  // early is mapped again from the page cache by whoever reads it).
  void ReleaseBelow(size_t begin, size_t end) const {
    const size_t page = static_cast<size_t>(::sysconf(_SC_PAGESIZE));
    const size_t first = begin / page * page;
    const size_t last = end / page * page;
    if (last > first) ::madvise(const_cast<char*>(data_) + first, last - first, MADV_DONTNEED);
  }

  const char* data() const { return data_; }
  size_t size() const { return size_; }

 private:
  const char* data_ = nullptr;
  size_t size_ = 0;
};

// Allocator for the parser's temporary row buffers: straight from mmap, so freeing a
// block's buffers returns the memory to the system at once (malloc would keep it in its
// arena and the peak would be file-sized buffers + tag columns).
template <typename T>
struct MmapAllocator {
  using value_type = T;
  MmapAllocator() = default;
  template <typename U>
  MmapAllocator(const MmapAllocator<U>&) {}  // NOLINT: allocator rebinding.
  T* allocate(size_t n) {
    const size_t bytes = std::max<size_t>(n * sizeof(T), 1);
    void* p = ::mmap(nullptr, bytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (p == MAP_FAILED) throw std::bad_alloc();
    return static_cast<T*>(p);
  }
  void deallocate(T* p, size_t n) { ::munmap(p, std::max<size_t>(n * sizeof(T), 1)); }
  template <typename U>
  bool operator==(const MmapAllocator<U>&) const {
    return true;
  }
  template <typename U>
  bool operator!=(const MmapAllocator<U>&) const {
    return false;
  }
};

template <typename T>
using MappedVector = std::vector<T, MmapAllocator<T>>;

inline void Trim(const char*& b, const char*& e) {
  while (b < e && (*b == ' ' || *b == '\t')) ++b;
  while (e > b && (e[-1] == ' ' || e[-1] == '\t')) --e;
}

// Parses a whole field as a finite double. Returns false (with a reason) otherwise.
inline bool ParseDouble(const char* b, const char* e, double* out, const char** why) {
  if (b == e) {
    *why = "empty";
    return false;
  }
  if (*b == '+') ++b;
  const auto result = fast_float::from_chars(b, e, *out);
  if (result.ec != std::errc() || result.ptr != e) {
    *why = "not a number";
    return false;
  }
  if (!std::isfinite(*out)) {
    *why = "not finite";
    return false;
  }
  return true;
}

struct ColumnPlan {
  std::vector<std::string> names;
  std::vector<ColumnInfo> info;
  int time_field = -1;
  int sensor_field = -1;
  // For each field: index into the numeric row (quantity), or into the text row, or -1.
  std::vector<int> numeric_slot;
  std::vector<int> text_slot;
  std::vector<int> numeric_fields;  // Field index of each numeric slot.
  std::vector<int> text_fields;     // Field index of each text slot.
};

struct BadRow {
  uint32_t local_line;
  int field;  // 1-based; 0 if not about one field
  std::string message;
};

struct Block {
  size_t begin = 0;
  size_t end = 0;
  uint32_t lines = 0;  // Lines in the block (the last may lack '\n').
  std::vector<uint8_t> sensor;
  std::vector<double> t_s;
  std::vector<uint32_t> local_line;
  std::vector<double> numeric;    // Row-major, plan.numeric_fields.size() per row.
  std::vector<std::string> text;  // Row-major, plan.text_fields.size() per row.
  std::vector<BadRow> bad;
  bool parsed = false;
};

// Reports each block's bytes to LoadOptions::on_bytes_parsed once: the clean path and the
// general loader parse the same blocks (one cut), so a block parsed by both (the clean path
// gave up on the file) is counted by whichever parses it first.
class BlockProgress {
 public:
  BlockProgress(const std::function<void(int64_t)>& callback, size_t blocks)
      : callback_(callback), reported_(callback ? blocks : 0) {}
  void Parsed(size_t block, size_t begin, size_t end) {
    if (!callback_ || reported_[block].exchange(true)) return;
    callback_(static_cast<int64_t>(end - begin));
  }

 private:
  const std::function<void(int64_t)>& callback_;
  std::vector<std::atomic<bool>> reported_;
};

std::string Printable(const char* b, const char* e) {
  std::string s(b, static_cast<size_t>(std::min<ptrdiff_t>(e - b, 40)));
  for (char& c : s) {
    if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) >= 0x7F) c = '?';
  }
  if (e - b > 40) s += "...";
  return s;
}

// Fast path for one numeric field: a number directly at `p` followed by ',' (or the end
// of the line for the last field), no spaces, finite. Returns the position after the
// separator, or nullptr if the field needs the general path.
inline const char* FastNumber(const char* p, const char* e, bool last, double* out) {
  const char* end = PlainDecimal(p, e, out);
  if (end == nullptr) {
    const auto r = fast_float::from_chars(p, e, *out);
    if (r.ec != std::errc() || r.ptr == p) return nullptr;
    end = r.ptr;
  }
  if (last ? end != e : (end == e || *end != ',')) return nullptr;
  if (!std::isfinite(*out)) return nullptr;
  return end + 1;
}

// Parses one data line into the block. Returns false if the row is bad (recorded).
bool ParseRow(const ColumnPlan& plan, const char* b, const char* e, uint32_t local_line,
              Block* block, std::vector<double>* numeric_row, std::vector<std::string>* text_row) {
  const int nf = static_cast<int>(plan.names.size());
  const char* p = b;
  double t = 0.0;
  int sensor = 1;
  for (int f = 0; f < nf; ++f) {
    const bool last = f == nf - 1;
    // Fast path: most fields are plain numbers.
    if (p < e && plan.info[f].role != ColumnRole::kText &&
        plan.info[f].role != ColumnRole::kUnknown) {
      double v;
      const char* next = FastNumber(p, e, last, &v);
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
          (*numeric_row)[plan.numeric_slot[f]] = v;
          p = next;
          continue;
        }
      }
    }
    // General path: find the field, trim it, and say precisely what is wrong.
    const char* fb = p;
    const char* comma =
        p <= e ? static_cast<const char*>(std::memchr(p, ',', static_cast<size_t>(e - p)))
               : nullptr;
    const char* fe = comma != nullptr ? comma : e;
    if (comma == nullptr && !last) {
      block->bad.push_back({local_line, f + 2,
                            fmt::format("missing field: expected {} fields ({}), found {}", nf,
                                        fmt::join(plan.names, ","), f + 1)});
      return false;
    }
    if (last && comma != nullptr) {
      const int found = nf + 1 + static_cast<int>(std::count(comma + 1, e, ','));
      block->bad.push_back(
          {local_line, nf + 1, fmt::format("expected {} fields, found {}", nf, found)});
      return false;
    }
    p = fe + 1;
    Trim(fb, fe);
    const char* why = nullptr;
    if (f == plan.time_field) {
      if (!ParseDouble(fb, fe, &t, &why)) {
        block->bad.push_back({local_line, f + 1,
                              fmt::format("t_s: expected a finite time in seconds, found '{}' ({})",
                                          Printable(fb, fe), why)});
        return false;
      }
    } else if (f == plan.sensor_field) {
      double v = 0.0;
      if (!ParseDouble(fb, fe, &v, &why) || v != std::floor(v) || v < 1.0 || v > 255.0) {
        block->bad.push_back(
            {local_line, f + 1,
             fmt::format("sensor: expected a tag number 1..255, found '{}'", Printable(fb, fe))});
        return false;
      }
      sensor = static_cast<int>(v);
    } else if (plan.numeric_slot[f] >= 0) {
      double v = kNaN;
      if (fb == fe && plan.info[f].allow_empty) {
        v = kNaN;
      } else if (!ParseDouble(fb, fe, &v, &why)) {
        block->bad.push_back(
            {local_line, f + 1,
             fmt::format("{}: expected a finite number{}, found '{}' ({})", plan.names[f],
                         plan.info[f].allow_empty ? " or an empty field" : "", Printable(fb, fe),
                         why)});
        return false;
      }
      (*numeric_row)[plan.numeric_slot[f]] = v;
    } else {
      (*text_row)[plan.text_slot[f]].assign(fb, fe);
    }
  }
  block->sensor.push_back(static_cast<uint8_t>(sensor));
  block->t_s.push_back(t);
  block->local_line.push_back(local_line);
  block->numeric.insert(block->numeric.end(), numeric_row->begin(), numeric_row->end());
  for (auto& s : *text_row) block->text.push_back(std::move(s));
  return true;
}

void ParseBlock(const MappedFile& file, const ColumnPlan& plan, bool lenient, Block* block) {
  const char* data = file.data();
  const char* p = data + block->begin;
  const char* end = data + block->end;
  std::vector<double> numeric_row(plan.numeric_fields.size(), kNaN);
  std::vector<std::string> text_row(plan.text_fields.size());
  // Rough reserve: ~ one row per 40 bytes.
  const size_t guess = static_cast<size_t>(end - p) / 40 + 16;
  block->t_s.reserve(guess);
  block->sensor.reserve(guess);
  block->local_line.reserve(guess);
  block->numeric.reserve(guess * plan.numeric_fields.size());
  uint32_t line = 0;
  while (p < end) {
    const char* nl = static_cast<const char*>(std::memchr(p, '\n', static_cast<size_t>(end - p)));
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
    if (!ParseRow(plan, lb, te, this_line, block, &numeric_row, &text_row) && !lenient) break;
  }
  // Lines are counted to the end of the block even after a strict-mode stop, because the
  // next block's line numbers depend on it.
  while (p < end) {
    const char* nl = static_cast<const char*>(std::memchr(p, '\n', static_cast<size_t>(end - p)));
    ++line;
    p = nl != nullptr ? nl + 1 : end;
  }
  block->lines = line;
  block->parsed = true;
}

template <typename B>
std::vector<size_t> BlockBegins(const std::vector<B>& blocks) {
  std::vector<size_t> begins;
  for (const B& b : blocks) begins.push_back(b.begin);
  return begins;
}

template <typename B>
std::vector<size_t> BlockEnds(const std::vector<B>& blocks) {
  std::vector<size_t> ends;
  for (const B& b : blocks) ends.push_back(b.end);
  return ends;
}

// The hasher reports its progress (and so lets pages go) this many bytes at a time.
constexpr size_t kHashChunkBytes = size_t{4} << 20;
// The file's pages kept mapped ahead of a hasher slower than the parser (ReleaseBehind): a
// quarter of the file, so the peak stays near 1.25 x the file for a session's columns
// however slow the hasher; at least 32 MB, so small files are read once.
constexpr size_t kMinReleaseGapBytes = size_t{32} << 20;

// Finds the header: the first line that is neither blank nor a comment.
struct HeaderLine {
  size_t line_begin = 0;
  size_t data_begin = 0;  // Offset just after the header line.
  int64_t line_number = 0;
  std::string text;
};

bool FindHeader(const MappedFile& file, HeaderLine* header) {
  const char* data = file.data();
  size_t pos = 0;
  int64_t line = 0;
  while (pos < file.size()) {
    const char* nl = static_cast<const char*>(std::memchr(data + pos, '\n', file.size() - pos));
    const size_t le = nl != nullptr ? static_cast<size_t>(nl - data) : file.size();
    ++line;
    size_t b = pos;
    size_t e = le;
    if (e > b && data[e - 1] == '\r') --e;
    while (b < e && (data[b] == ' ' || data[b] == '\t')) ++b;
    if (b < e && data[b] != '#') {
      header->line_begin = pos;
      header->data_begin = nl != nullptr ? le + 1 : file.size();
      header->line_number = line;
      header->text.assign(data + b, e - b);
      return true;
    }
    pos = nl != nullptr ? le + 1 : file.size();
  }
  return false;
}

Result<ColumnPlan> PlanColumns(const std::string& path, const HeaderLine& header) {
  ColumnPlan plan;
  const std::string& h = header.text;
  size_t start = 0;
  for (;;) {
    const size_t comma = h.find(',', start);
    std::string name =
        h.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    const char* b = name.data();
    const char* e = name.data() + name.size();
    Trim(b, e);
    plan.names.emplace_back(b, e);
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  std::map<std::string, int> seen;
  std::map<std::string, std::vector<std::string>> families;
  for (size_t f = 0; f < plan.names.size(); ++f) {
    const std::string& name = plan.names[f];
    const int column = static_cast<int>(f) + 1;
    if (!IsValidColumnName(name)) {
      return MakeError(path, header.line_number, column,
                       fmt::format("header: column {} is '{}': expected a lower-case name with "
                                   "its unit, e.g. pitch_deg ([a-z][a-z0-9_]*; see "
                                   "docs/formats.md)",
                                   column, Printable(name.data(), name.data() + name.size())));
    }
    if (!seen.emplace(name, column).second) {
      return MakeError(path, header.line_number, column,
                       fmt::format("header: column '{}' appears twice (columns {} and {})", name,
                                   seen[name], column));
    }
    ColumnInfo info = ClassifyColumn(name);
    if (!info.family.empty()) families[info.family].push_back(name);
    plan.info.push_back(info);
  }
  for (const auto& [family, members] : families) {
    const size_t need = family == "quat" ? 4 : 3;
    if (members.size() != need) {
      return MakeError(path, header.line_number,
                       fmt::format("header: '{}' needs its whole axis family ({} columns of "
                                   "family {}), found only {}",
                                   members.front(), need, family, fmt::join(members, ",")));
    }
  }
  const size_t nf = plan.names.size();
  plan.numeric_slot.assign(nf, -1);
  plan.text_slot.assign(nf, -1);
  for (size_t f = 0; f < nf; ++f) {
    switch (plan.info[f].role) {
      case ColumnRole::kTime:
        plan.time_field = static_cast<int>(f);
        break;
      case ColumnRole::kSensor:
        plan.sensor_field = static_cast<int>(f);
        break;
      case ColumnRole::kQuantity:
        plan.numeric_slot[f] = static_cast<int>(plan.numeric_fields.size());
        plan.numeric_fields.push_back(static_cast<int>(f));
        break;
      case ColumnRole::kText:
      case ColumnRole::kUnknown:
        plan.text_slot[f] = static_cast<int>(plan.text_fields.size());
        plan.text_fields.push_back(static_cast<int>(f));
        break;
    }
  }
  if (plan.time_field < 0) {
    return MakeError(path, header.line_number,
                     fmt::format("header: no t_s column; expected a session.csv header naming "
                                 "t_s (time in seconds) and quantities with units, e.g. "
                                 "t_s,sensor,qw,qx,qy,qz; found '{}'",
                                 Printable(h.data(), h.data() + h.size())));
  }
  return plan;
}

std::vector<Block> CutBlocks(const MappedFile& file, size_t data_begin, int threads) {
  std::vector<Block> blocks;
  const size_t size = file.size();
  if (data_begin >= size) return blocks;
  const size_t span = size - data_begin;
  const size_t target = std::clamp<size_t>(span / (static_cast<size_t>(threads) * 16),
                                           size_t{1} << 20, size_t{8} << 20);
  size_t begin = data_begin;
  while (begin < size) {
    size_t end = std::min(size, begin + target);
    if (end < size) {
      const char* nl = static_cast<const char*>(std::memchr(file.data() + end, '\n', size - end));
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

// ---- The clean-file path -------------------------------------------------------------
// Most session files have no malformed row, no text column and time increasing per tag.
// For those, one parallel pass parses each block (512 kB) into a stage, the block's rows
// tag by tag and column by column, and the stages are appended to the tag columns in
// block order, by whichever thread finds the next block parsed. No pass counts rows
// first, and no column is zero-filled before it is written: each number is written to its
// column once, in runs, from a stage still in cache, and the columns' pages are faulted
// in ahead of the appends by the parse threads (PageQueue). Anything unusual (a field the
// fast parser does not accept, a sensor that is not a plain 1..255 integer, time not
// increasing) abandons this path, and the general loader below, which explains every
// error exactly, reads the file instead.

inline bool SkipBlankOrComment(const char* lb, const char* te) {
  const char* first = lb;
  while (first < te && (*first == ' ' || *first == '\t')) ++first;
  return first == te || *first == '#';
}

struct CleanBlock {
  size_t begin = 0;
  size_t end = 0;
  size_t cut = 0;  // The file's block (CutBlocks) this one is part of.
};

// Bytes per clean-path block. Its stage holds about as many bytes of numbers, half a 1 MB
// L2; with the block's text and the columns it is appended to it does not stay there
// whole, but 128 kB to 8 MB blocks measured no faster (docs/benchmarks.md, session 8).
constexpr size_t kCleanBlockBytes = size_t{512} << 10;

// End of a line's last field at `q`: "\n", "\r\n" or the end of the block. Returns the
// start of the next line, or nullptr if `q` is not at the end of the line.
inline const char* EndOfLine(const char* q, const char* end) {
  if (q == end) return end;
  if (*q == '\n') return q + 1;
  if (*q == '\r' && (q + 1 == end || q[1] == '\n')) return q + 1 == end ? end : q + 2;
  return nullptr;
}

// One block's rows of one tag: column k of the stage (t_s, then the quantities) at
// values + k * room, and the block-relative line of each row. Its vectors keep their size
// from block to block, so a reused stage allocates nothing.
struct StagedTag {
  int sensor = 0;
  size_t rows = 0;
  size_t room = 0;
  std::vector<uint32_t> line;
  std::vector<double> values;  // Column-major, `room` rows per column.
};

// A block's rows staged for their tag columns; reused from block to block.
class BlockStage {
 public:
  // `fields`: the file field of each staged column (t_s, then the quantities).
  explicit BlockStage(std::vector<int> fields) : fields_(std::move(fields)) {
    slot_of_sensor_.fill(-1);
  }

  void Clear() {
    for (size_t i = 0; i < used_; ++i) {
      slot_of_sensor_[static_cast<size_t>(tags_[i].sensor)] = -1;
      tags_[i].rows = 0;
    }
    used_ = 0;
    lines = 0;
  }
  // Stages one row of `sensor` (its fields in file order) and its block-relative line.
  void Add(int sensor, const double* row, uint32_t line) {
    int& slot = slot_of_sensor_[static_cast<size_t>(sensor)];
    if (slot < 0) {
      if (used_ == tags_.size()) tags_.emplace_back();
      slot = static_cast<int>(used_++);
      tags_[static_cast<size_t>(slot)].sensor = sensor;
    }
    StagedTag& tag = tags_[static_cast<size_t>(slot)];
    if (tag.rows == tag.room) Grow(&tag);
    tag.line[tag.rows] = line;
    double* out = tag.values.data() + tag.rows;
    const size_t room = tag.room;
    for (size_t k = 0; k < fields_.size(); ++k) out[k * room] = row[fields_[k]];
    ++tag.rows;
  }
  const StagedTag* begin() const { return tags_.data(); }
  const StagedTag* end() const { return tags_.data() + used_; }

  uint32_t lines = 0;  // Lines in the block, blank and comment lines included.
  // DecimalRows's separators and values for one run: scratch space kept with the stage so
  // that it is allocated (and zero-filled) once per stage, not once per block.
  std::vector<uint32_t> run_separators;
  std::vector<double> run_values;

 private:
  void Grow(StagedTag* tag) const {
    // Columns 8 doubles longer than a power of two: the rows being written in the
    // columns then fall in different cache sets (at a power-of-two stride, the columns of
    // all tags competed for the same few sets; measured 5% slower).
    const size_t room = std::max<size_t>(1024, 2 * (tag->room & ~size_t{7})) + 8;
    std::vector<double> values(room * fields_.size());
    for (size_t k = 0; k < fields_.size(); ++k) {
      std::copy_n(tag->values.data() + k * tag->room, tag->rows, values.data() + k * room);
    }
    tag->values = std::move(values);
    tag->line.resize(room);
    tag->room = room;
  }

  std::vector<int> fields_;
  std::array<int, 256> slot_of_sensor_;
  std::vector<StagedTag> tags_;  // The first used_ are this block's.
  size_t used_ = 0;
};

// Bytes per DecimalRows run: its separators and values stay in the core's cache.
constexpr size_t kVectorRunBytes = size_t{64} << 10;

// Parses one block into `stage`. Runs of machine-written rows go through DecimalRows (four
// fields per instruction); any run it refuses, and every block on a CPU without AVX-512,
// is read by the scalar parser below, which parses numbers straight from the block (no
// separate search for the end of each line). Returns false at the first line neither
// accepts.
bool ParseCleanBlock(const MappedFile& file, const ColumnPlan& plan, const CleanBlock& block,
                     BlockStage* stage) {
  const char* p = file.data() + block.begin;
  const char* end = file.data() + block.end;
  const int nf = static_cast<int>(plan.names.size());
  uint32_t line = 0;
  // One parsed row (its fields in file order) into its tag's stage. False if the sensor
  // is not a plain integer 1..255.
  auto put = [&](const double* fields, uint32_t this_line) {
    int sensor = 1;
    if (plan.sensor_field >= 0) {
      const double v = fields[plan.sensor_field];
      if (!(v >= 1.0 && v <= 255.0 && v == std::floor(v))) return false;
      sensor = static_cast<int>(v);
    }
    stage->Add(sensor, fields, this_line);
    return true;
  };
  std::vector<double> fields(static_cast<size_t>(nf));
  // The scalar parser, for the lines in [p, run_end).
  auto scalar_lines = [&](const char* run_end) {
    while (p < run_end) {
      const uint32_t this_line = line++;
      if (*p == '#' || *p == ' ' || *p == '\t' || *p == '\r' || *p == '\n') {
        // Possibly a blank or comment line; a data line starting with a blank is left to
        // the general loader.
        const char* nl =
            static_cast<const char*>(std::memchr(p, '\n', static_cast<size_t>(run_end - p)));
        const char* lb = p;
        const char* te = nl != nullptr ? nl : run_end;
        p = nl != nullptr ? nl + 1 : run_end;
        if (te > lb && te[-1] == '\r') --te;
        if (SkipBlankOrComment(lb, te)) continue;
        return false;
      }
      const char* q = p;
      for (int f = 0; f < nf; ++f) {
        const bool last = f == nf - 1;
        double v;
        const char* number_end;
        if (plan.info[f].allow_empty && (q == run_end || *q == ',' || *q == '\n' || *q == '\r')) {
          v = kNaN;  // An empty field where the format allows one ("unknown").
          number_end = q;
        } else {
          number_end = PlainDecimal(q, run_end, &v);
          if (number_end == nullptr) {
            const auto r = fast_float::from_chars(q, run_end, v);
            number_end = r.ec == std::errc() && r.ptr != q && std::isfinite(v) ? r.ptr : nullptr;
          }
        }
        const char* next = nullptr;
        if (number_end != nullptr) {
          if (last) {
            next = EndOfLine(number_end, run_end);
          } else if (number_end < run_end && *number_end == ',') {
            next = number_end + 1;
          }
        }
        if (next == nullptr) return false;
        q = next;
        fields[static_cast<size_t>(f)] = v;
      }
      p = q;
      if (!put(fields.data(), this_line)) return false;
    }
    return true;
  };
  // DecimalRows loads the 16 bytes before each field's end: the run must not start at the
  // very beginning of the mapping (a block never does unless the header is tiny).
  const bool vector = DecimalRowsAvailable() && block.begin >= 16;
  std::vector<uint32_t>& separators = stage->run_separators;
  std::vector<double>& values = stage->run_values;
  bool ok = true;
  while (p < end && ok) {
    const char* run_end = end;
    if (vector && static_cast<size_t>(end - p) > kVectorRunBytes) {
      const char* from = p + kVectorRunBytes;
      const char* nl =
          static_cast<const char*>(std::memchr(from, '\n', static_cast<size_t>(end - from)));
      run_end = nl != nullptr ? nl + 1 : end;
    }
    const int64_t rows = vector ? DecimalRows(p, run_end, nf, &separators, &values) : -1;
    if (rows < 0) {
      ok = scalar_lines(run_end);
      continue;
    }
    for (int64_t r = 0; r < rows && ok; ++r) {
      ok = put(values.data() + r * nf, line++);
    }
    p = run_end;
  }
  stage->lines = line;
  return ok;
}

// Stages for the parse threads. A thread takes a stage before it takes a block, so the
// lowest block not yet appended always has one and the appending never waits for itself;
// `threads` + 2 stages let threads go on parsing while a stage waits its turn.
class StagePool {
 public:
  StagePool(size_t count, const std::vector<int>& fields) {
    for (size_t i = 0; i < count; ++i) free_.push_back(std::make_unique<BlockStage>(fields));
  }
  // A cleared stage, or nullptr once the parse has failed.
  std::unique_ptr<BlockStage> Take() {
    std::unique_lock<std::mutex> lock(mutex_);
    ready_.wait(lock, [this] { return failed_ || !free_.empty(); });
    if (failed_) return nullptr;
    std::unique_ptr<BlockStage> stage = std::move(free_.back());
    free_.pop_back();
    stage->Clear();
    return stage;
  }
  void Give(std::unique_ptr<BlockStage> stage) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      free_.push_back(std::move(stage));
    }
    ready_.notify_one();
  }
  void Fail() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      failed_ = true;
    }
    ready_.notify_all();
  }

 private:
  std::mutex mutex_;
  std::condition_variable ready_;
  std::vector<std::unique_ptr<BlockStage>> free_;
  bool failed_ = false;
};

// Pages of the tag columns to fault in ahead of the appends, by the parse threads between
// blocks (MADV_POPULATE_WRITE, 256 kB to 2 MB per call): the appends, one thread at a time,
// then only copy, and the page faults (the larger part of the load's kernel time) are
// taken by both threads. Advice only. A queued range whose column has been reallocated
// meanwhile (a tag that outgrew its reservation) is freed memory or someone else's:
// faulting it in writes no byte, so it costs time at worst.
class PageQueue {
 public:
  // Queues [begin, end), whole pages only.
  void Add(uintptr_t begin, uintptr_t end) {
    constexpr uintptr_t kPage = 4096;
    constexpr uintptr_t kChunk = uintptr_t{2} << 20;
    begin = (begin + kPage - 1) & ~(kPage - 1);
    end &= ~(kPage - 1);
    std::lock_guard<std::mutex> lock(mutex_);
    for (; begin < end; begin += kChunk) ranges_.emplace_back(begin, std::min(end, begin + kChunk));
  }
  // Faults in one queued range; false if none is left.
  bool FaultOne() {
    std::pair<uintptr_t, uintptr_t> r;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (next_ == ranges_.size()) return false;
      r = ranges_[next_++];
    }
#ifdef MADV_POPULATE_WRITE
    ::madvise(reinterpret_cast<void*>(r.first), r.second - r.first, MADV_POPULATE_WRITE);
#endif
    return true;
  }

 private:
  std::mutex mutex_;
  std::vector<std::pair<uintptr_t, uintptr_t>> ranges_;
  size_t next_ = 0;
};

// Rows of each column queued for faulting ahead of its end: enough for the parse threads
// to fault them in well before the appends arrive, few enough that a tag which stops early
// leaves little faulted in for nothing.
constexpr size_t kRowsAhead = size_t{1} << 17;

// Queues the pages of `column` from *queued (the end of what was queued for it before, or
// 0) to kRowsAhead rows past its end, within its capacity, once that is 256 kB or more.
template <typename T>
void QueueColumnPages(const std::vector<T>& column, uintptr_t* queued, PageQueue* pages) {
  const uintptr_t begin = reinterpret_cast<uintptr_t>(column.data());
  const uintptr_t capacity_end = begin + column.capacity() * sizeof(T);
  if (*queued < begin || *queued > capacity_end) *queued = begin;  // A new allocation.
  const uintptr_t want =
      begin + std::min(column.capacity(), column.size() + kRowsAhead) * sizeof(T);
  if (want >= *queued + (uintptr_t{256} << 10) || (want == capacity_end && want > *queued)) {
    pages->Add(*queued, want);
    *queued = want;
  }
}

std::atomic<int64_t> clean_path_loads{0};

// The clean-file path. Returns no value when the file needs the general loader.
// `cut` is the file's blocks (CutBlocks), the same the general loader parses.
std::optional<Session> LoadCleanCsv(const std::string& path, const MappedFile& file,
                                    const HeaderLine& header, const ColumnPlan& plan, int threads,
                                    const std::vector<Block>& cut, BlockProgress* progress,
                                    ReleaseBehind* release) {
  if (!plan.text_fields.empty() || cut.empty()) return std::nullopt;
  // The file's blocks cut again into clean-path blocks; a file block counts as parsed
  // (progress) once all of its pieces are.
  std::vector<CleanBlock> blocks;
  std::vector<std::atomic<uint32_t>> pieces_left(cut.size());
  for (size_t c = 0; c < cut.size(); ++c) {
    uint32_t pieces = 0;
    for (size_t begin = cut[c].begin; begin < cut[c].end; ++pieces) {
      size_t end = cut[c].end;
      if (end - begin > 2 * kCleanBlockBytes) {
        const char* from = file.data() + begin + kCleanBlockBytes;
        const char* nl = static_cast<const char*>(
            std::memchr(from, '\n', static_cast<size_t>(file.data() + end - from)));
        if (nl != nullptr) end = static_cast<size_t>(nl - file.data()) + 1;
      }
      blocks.push_back(CleanBlock{begin, end, c});
      begin = end;
    }
    pieces_left[c].store(pieces);
  }
  const size_t nq = plan.numeric_fields.size();
  const size_t workers = std::min(static_cast<size_t>(ResolveThreads(threads)), blocks.size());
  std::vector<int> staged_fields{plan.time_field};
  staged_fields.insert(staged_fields.end(), plan.numeric_fields.begin(), plan.numeric_fields.end());
  StagePool pool(workers + 2, staged_fields);

  PageQueue pages;
  // The tag columns, by sensor, appended to in block order by one thread at a time, and
  // how far each column's pages are queued (t_s, line, then the quantities).
  std::array<std::unique_ptr<Tag>, 256> tags;
  std::array<std::vector<uintptr_t>, 256> queued_pages;
  int64_t next_line = header.line_number + 1;  // First line of the next block to append.
  // False once a block's rows do not fit the clean path (a line neither parser accepts,
  // or a time that does not increase strictly within its tag).
  std::atomic<bool> clean{true};
  // Appends block i's stage. A tag's columns are reserved, when the tag first appears,
  // for the rows it would have if the rest of the file held them at this block's rate,
  // 5% over (only the pages written are ever faulted in); a tag that outgrows that is
  // reallocated (correct, only slower).
  auto append = [&](size_t i, const BlockStage& stage) {
    const CleanBlock& block = blocks[i];
    if (next_line + stage.lines - 1 > kMaxLineNumber) {
      clean.store(false);  // The general loader reports the line beyond 32 bits.
      return;
    }
    for (const StagedTag& st : stage) {
      std::unique_ptr<Tag>& slot = tags[static_cast<size_t>(st.sensor)];
      if (slot == nullptr) {
        slot = std::make_unique<Tag>();
        Tag& tag = *slot;
        tag.sensor = st.sensor;
        const double rate =
            static_cast<double>(st.rows) / static_cast<double>(block.end - block.begin);
        const size_t expected =
            static_cast<size_t>(rate * static_cast<double>(file.size() - block.begin));
        for (size_t q = 0; q < nq; ++q) {
          Quantity quantity;
          const int f = plan.numeric_fields[q];
          quantity.name = plan.names[static_cast<size_t>(f)];
          quantity.unit = plan.info[static_cast<size_t>(f)].unit;
          quantity.origin = QuantityOrigin::kFile;
          tag.quantities.push_back(std::move(quantity));
        }
        auto reserve = [&tag](size_t rows) {
          tag.t_s.reserve(rows);
          tag.line.reserve(rows);
          for (Quantity& quantity : tag.quantities) quantity.values.reserve(rows);
        };
        try {
          reserve(expected + expected / 20 + 64);
        } catch (const std::bad_alloc&) {
          // The guess can exceed what the system lets one allocation have (a tag dense in
          // its first block, rare after it, on a file of tens of GB); the columns then grow
          // as they fill. If they cannot, the load fails with a clear error.
          reserve(2 * st.rows);
        }
      }
      Tag& tag = *slot;
      std::vector<uintptr_t>& queued = queued_pages[static_cast<size_t>(st.sensor)];
      queued.resize(nq + 2);
      QueueColumnPages(tag.t_s, &queued[0], &pages);
      QueueColumnPages(tag.line, &queued[1], &pages);
      for (size_t q = 0; q < nq; ++q) {
        QueueColumnPages(tag.quantities[q].values, &queued[q + 2], &pages);
      }
      const size_t n = st.rows;
      const double* t = st.values.data();
      // Time must increase strictly per tag; if it does not, the general loader reports
      // (or, with --lenient, rejects) the rows in file order. Checked here, while the
      // stage is in cache, rather than in another pass over the columns.
      double last_t = tag.t_s.empty() ? -std::numeric_limits<double>::infinity() : tag.t_s.back();
      bool increasing = true;
      for (size_t r = 0; r < n; ++r) {
        increasing &= t[r] > last_t;
        last_t = t[r];
      }
      if (!increasing) {
        clean.store(false);
        return;
      }
      tag.t_s.insert(tag.t_s.end(), t, t + n);
      for (size_t q = 0; q < nq; ++q) {
        const double* v = st.values.data() + (q + 1) * st.room;
        tag.quantities[q].values.insert(tag.quantities[q].values.end(), v, v + n);
      }
      const uint32_t first = static_cast<uint32_t>(next_line);
      // Block-relative lines copied, then made absolute where they now lie (in cache; a
      // loop of push_backs checks the capacity per row).
      const size_t at = tag.line.size();
      tag.line.insert(tag.line.end(), st.line.data(), st.line.data() + n);
      uint32_t* lines = tag.line.data() + at;
      for (size_t r = 0; r < n; ++r) lines[r] += first;
    }
    next_line += stage.lines;
  };

  // Blocks parsed and waiting for their turn; the thread that finds block `next_append`
  // parsed appends it and every parsed block after it, outside the lock.
  std::mutex order_mutex;
  std::vector<std::unique_ptr<BlockStage>> parsed(blocks.size());
  size_t next_append = 0;
  bool appending = false;
  auto parsed_block = [&](size_t i, std::unique_ptr<BlockStage> stage) {
    std::unique_lock<std::mutex> lock(order_mutex);
    parsed[i] = std::move(stage);
    if (appending) return;
    appending = true;
    while (next_append < blocks.size() && parsed[next_append] != nullptr) {
      std::unique_ptr<BlockStage> next = std::move(parsed[next_append]);
      lock.unlock();
      append(next_append, *next);
      if (!clean.load()) {
        pool.Fail();
        return;  // `appending` stays set: nothing more is appended.
      }
      pool.Give(std::move(next));
      lock.lock();
      ++next_append;
    }
    appending = false;
  };

  std::atomic<size_t> next_block{0};
  // The mapping's pages are released file block by file block (8 MB), not piece by
  // piece: each release is a TLB shootdown on every core.
  release->StartPass(BlockBegins(cut), BlockEnds(cut));
  auto worker = [&] {
    for (;;) {
      while (pages.FaultOne()) {
      }
      std::unique_ptr<BlockStage> stage = pool.Take();
      if (stage == nullptr) return;
      const size_t i = next_block.fetch_add(1);
      if (i >= blocks.size()) {
        pool.Give(std::move(stage));
        return;
      }
      if (!ParseCleanBlock(file, plan, blocks[i], stage.get())) {
        clean.store(false);
        pool.Fail();
        return;
      }
      const size_t c = blocks[i].cut;
      if (pieces_left[c].fetch_sub(1) == 1) {
        progress->Parsed(c, cut[c].begin, cut[c].end);
        release->BlockDone(c);
      }
      parsed_block(i, std::move(stage));
    }
  };
  // An exception in a worker (std::bad_alloc: the session does not fit in memory) stops
  // the others and is rethrown here once they have finished.
  RunOnThreads(workers, worker, [&] {
    clean.store(false);
    pool.Fail();
  });
  if (!clean.load()) return std::nullopt;
  METRO_CHECK(next_append == blocks.size());

  Session session;
  session.path = path;
  session.format = SessionFormat::kCsv;
  session.columns = plan.names;
  for (std::unique_ptr<Tag>& tag : tags) {
    if (tag == nullptr) continue;
    if (tag->t_s.size() > UINT32_MAX) return std::nullopt;
    tag->counts.frames = tag->counts.fresh = static_cast<int64_t>(tag->t_s.size());
    session.rows += tag->counts.fresh;
    session.tags.push_back(std::move(*tag));
  }
  if (session.tags.empty()) return std::nullopt;  // Header only: the general loader words it.
  clean_path_loads.fetch_add(1);
  return session;
}

struct TagBuilder {
  Tag tag;
  double last_t = -std::numeric_limits<double>::infinity();
  uint32_t last_line = 0;
  std::vector<std::vector<std::string>> text;
};

}  // namespace

int64_t CleanPathLoads() { return clean_path_loads.load(); }

namespace {

Result<Session> LoadMappedCsv(const std::string& path, const MappedFile& file,
                              const LoadOptions& options, bool allow_clean_path,
                              ReleaseBehind* release) {
  if (file.size() == 0) {
    return MakeError(path, 0,
                     "empty file: expected a session.csv header line (t_s,...) "
                     "followed by data rows");
  }
  HeaderLine header;
  if (!FindHeader(file, &header)) {
    return MakeError(path, 0,
                     "no header: the file holds only blank or comment lines; "
                     "expected a session.csv header line (t_s,...)");
  }
  auto plan_or = PlanColumns(path, header);
  if (!plan_or.ok()) return plan_or.error();
  const ColumnPlan& plan = plan_or.value();

  int threads =
      options.threads > 0 ? options.threads : static_cast<int>(std::thread::hardware_concurrency());
  threads = std::max(1, threads);
  // One cut of the file, shared by the clean path and the general loader (so a block is
  // the same block for both, which BlockProgress relies on).
  std::vector<Block> blocks = CutBlocks(file, header.data_begin, threads);
  BlockProgress progress(options.on_bytes_parsed, blocks.size());
  // The comments and the header line before the first block.
  if (options.on_bytes_parsed) options.on_bytes_parsed(static_cast<int64_t>(header.data_begin));
  if (allow_clean_path) {
    if (auto session =
            LoadCleanCsv(path, file, header, plan, threads, blocks, &progress, release)) {
      return *std::move(session);
    }
  }

  // Parse blocks in parallel. In strict mode, blocks after the first one with an error
  // are never reached by the sequential pass, so they need not be parsed.
  std::atomic<size_t> first_bad_block{blocks.size()};
  release->StartPass(BlockBegins(blocks), BlockEnds(blocks));
  ParallelFor(blocks.size(), threads, [&](size_t i) {
    if (!options.lenient && i > first_bad_block.load()) {
      release->BlockDone(i);  // Never read: the sequential pass stops before it.
      return;
    }
    ParseBlock(file, plan, options.lenient, &blocks[i]);
    release->BlockDone(i);
    progress.Parsed(i, blocks[i].begin, blocks[i].end);
    if (!options.lenient && !blocks[i].bad.empty()) {
      size_t cur = first_bad_block.load();
      while (i < cur && !first_bad_block.compare_exchange_weak(cur, i)) {
      }
    }
  });

  // Count rows per sensor to size the tag columns exactly.
  std::vector<int64_t> per_sensor(256, 0);
  for (const Block& b : blocks) {
    if (!b.parsed) break;
    for (uint8_t s : b.sensor) ++per_sensor[s];
  }
  std::vector<std::unique_ptr<TagBuilder>> builders(256);
  const size_t nq = plan.numeric_fields.size();
  const size_t nt = plan.text_fields.size();
  for (int s = 1; s < 256; ++s) {
    if (per_sensor[s] == 0) continue;
    auto tb = std::make_unique<TagBuilder>();
    tb->tag.sensor = s;
    const size_t rows = static_cast<size_t>(per_sensor[s]);
    tb->tag.t_s.reserve(rows);
    tb->tag.line.reserve(rows);
    for (size_t q = 0; q < nq; ++q) {
      Quantity quantity;
      const int f = plan.numeric_fields[q];
      quantity.name = plan.names[f];
      quantity.unit = plan.info[f].unit;
      quantity.origin = QuantityOrigin::kFile;
      quantity.values.reserve(rows);
      tb->tag.quantities.push_back(std::move(quantity));
    }
    tb->text.resize(nt);
    builders[s] = std::move(tb);
  }

  Session session;
  session.path = path;
  session.format = SessionFormat::kCsv;
  session.columns = plan.names;
  for (size_t f = 0; f < plan.names.size(); ++f) {
    if (plan.info[f].role == ColumnRole::kUnknown) session.unknown_columns.push_back(plan.names[f]);
  }

  auto reject = [&](int64_t line, int field, const std::string& message) -> Status {
    if (!options.lenient) return MakeError(path, line, field, message);
    ++session.rejected_rows;
    ++session.rows;
    if (session.rejected_lines.size() < options.max_rejected_kept) {
      session.rejected_lines.push_back(line);
      session.rejected_reasons.push_back(message);
    }
    return Status::Ok();
  };

  // Sequential pass in file order.
  int64_t first_line = header.line_number + 1;
  for (Block& b : blocks) {
    if (!b.parsed) break;
    size_t bad_i = 0;
    const size_t rows = b.t_s.size();
    for (size_t r = 0; r <= rows; ++r) {
      const uint32_t row_line = r < rows ? b.local_line[r] : UINT32_MAX;
      while (bad_i < b.bad.size() && b.bad[bad_i].local_line < row_line) {
        const BadRow& bad = b.bad[bad_i++];
        if (Status s = reject(first_line + bad.local_line, bad.field, bad.message); !s.ok()) {
          return s.error();
        }
      }
      if (r == rows) break;
      TagBuilder& tb = *builders[b.sensor[r]];
      const int64_t line = first_line + b.local_line[r];
      const double t = b.t_s[r];
      if (!(t > tb.last_t)) {
        const std::string message = fmt::format(
            "t_s = {} is not after t_s = {} of sensor {} on line {}: rows must be sorted by "
            "strictly increasing time per tag",
            t, tb.last_t, b.sensor[r], tb.last_line);
        if (Status s = reject(line, plan.time_field + 1, message); !s.ok()) return s.error();
        continue;
      }
      if (line > kMaxLineNumber) return TooManyLinesError(path, line);
      ++session.rows;
      tb.last_t = t;
      tb.last_line = static_cast<uint32_t>(line);
      tb.tag.t_s.push_back(t);
      tb.tag.line.push_back(static_cast<uint32_t>(line));
      const double* row = b.numeric.data() + r * nq;
      for (size_t q = 0; q < nq; ++q) tb.tag.quantities[q].values.push_back(row[q]);
      for (size_t k = 0; k < nt; ++k) tb.text[k].push_back(std::move(b.text[r * nt + k]));
    }
    first_line += b.lines;
    // Free the block's buffers as soon as they are moved.
    b = Block();
  }

  for (int s = 1; s < 256; ++s) {
    if (!builders[s] || builders[s]->tag.t_s.empty()) continue;
    TagBuilder& tb = *builders[s];
    for (size_t k = 0; k < nt; ++k) {
      const int f = plan.text_fields[k];
      AddTextOrUnknownColumn(plan.names[f], plan.info[f].role == ColumnRole::kUnknown,
                             plan.info[f].unit, std::move(tb.text[k]), &tb.tag);
    }
    tb.tag.counts.frames = tb.tag.counts.fresh = static_cast<int64_t>(tb.tag.t_s.size());
    session.tags.push_back(std::move(tb.tag));
  }
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

}  // namespace

Result<Session> LoadSessionCsv(const std::string& path, const LoadOptions& options,
                               bool allow_clean_path, bool hash) {
  MappedFile file;
  if (Status s = file.Open(path); !s.ok()) return s.error();
  // The SHA-256 of the bytes, on a second thread while the parser works, from the parser's
  // own mapping: the file's pages are mapped once for both and released once both are past
  // them; a hasher slower than the parser (a CPU without SHA extensions) keeps at most a
  // quarter of the file mapped behind the parser (ReleaseBehind).
  ReleaseBehind release([&file](size_t begin, size_t end) { file.ReleaseBelow(begin, end); }, hash,
                        std::max(file.size() / 4, kMinReleaseGapBytes));
  std::string digest;
  std::optional<Result<Session>> session;
  RunBeside(
      [&] {
        if (!hash) return;
        digest = Sha256Hex(std::string_view(file.data(), file.size()), kHashChunkBytes,
                           [&release](size_t hashed) { release.Hashed(hashed); });
      },
      [&] { session = LoadMappedCsv(path, file, options, allow_clean_path, &release); });
  if (session->ok() && hash) session->value().sha256 = std::move(digest);
  return *std::move(session);
}

}  // namespace metro::internal
