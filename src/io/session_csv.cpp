// session.csv loader.
//
// The file is memory-mapped and cut into line-aligned blocks that worker threads parse
// independently into row-major buffers (numbers with fast_float). A single sequential pass
// then moves the rows, in file order, into per-tag columns, checking time order per tag.
// Because errors and rejections are resolved in that sequential pass, strict and lenient
// loads behave exactly as a one-thread reader would, whatever the thread count. Pages of
// the mapping are released behind the parser, so peak memory is about the size of the
// parsed numbers, not file + numbers.
#include <fast_float/fast_float.h>
#include <fcntl.h>
#include <fmt/format.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <new>
#include <thread>

#include "io/columns.hpp"
#include "io/session_internal.hpp"
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

  // Tells the kernel the bytes [begin, end) will not be read again.
  void Release(size_t begin, size_t end) const {
    const size_t page = static_cast<size_t>(::sysconf(_SC_PAGESIZE));
    const size_t first = (begin + page - 1) / page * page;
    const size_t last = end / page * page;
    if (last > first) ::madvise(const_cast<char*>(data_) + first, last - first, MADV_DONTNEED);
  }

  const char* data() const { return data_; }
  size_t size() const { return size_; }

 private:
  const char* data_ = nullptr;
  size_t size_ = 0;
};

// Asks for transparent huge pages on the page-aligned interior of [p, p + bytes): large
// buffers that are written once then fault in 2 MiB at a time instead of 4 KiB.
void AdviseHugePages(void* p, size_t bytes) {
  constexpr uintptr_t kHuge = uintptr_t{2} << 20;
  const uintptr_t begin = (reinterpret_cast<uintptr_t>(p) + kHuge - 1) & ~(kHuge - 1);
  const uintptr_t end = (reinterpret_cast<uintptr_t>(p) + bytes) & ~(kHuge - 1);
  if (end > begin) ::madvise(reinterpret_cast<void*>(begin), end - begin, MADV_HUGEPAGE);
}

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
    AdviseHugePages(p, bytes);
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
  const auto r = fast_float::from_chars(p, e, *out);
  if (r.ec != std::errc() || r.ptr == p) return nullptr;
  if (last ? r.ptr != e : (r.ptr == e || *r.ptr != ',')) return nullptr;
  if (!std::isfinite(*out)) return nullptr;
  return r.ptr + 1;
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
  file.Release(block->begin, block->end);
}

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

struct TagBuilder {
  Tag tag;
  double last_t = -std::numeric_limits<double>::infinity();
  uint32_t last_line = 0;
  std::vector<std::vector<std::string>> text;
};

}  // namespace

Result<Session> LoadSessionCsv(const std::string& path, const LoadOptions& options) {
  MappedFile file;
  if (Status s = file.Open(path); !s.ok()) return s.error();
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
  std::vector<Block> blocks = CutBlocks(file, header.data_begin, threads);

  // Parse blocks in parallel. In strict mode, blocks after the first one with an error
  // are not needed.
  std::atomic<size_t> next{0};
  std::atomic<size_t> first_bad_block{blocks.size()};
  auto worker = [&] {
    for (;;) {
      const size_t i = next.fetch_add(1);
      if (i >= blocks.size()) return;
      // Strict mode: blocks after the first one with an error are never reached by the
      // sequential pass, so they need not be parsed.
      if (!options.lenient && i > first_bad_block.load()) continue;
      ParseBlock(file, plan, options.lenient, &blocks[i]);
      if (!options.lenient && !blocks[i].bad.empty()) {
        size_t cur = first_bad_block.load();
        while (i < cur && !first_bad_block.compare_exchange_weak(cur, i)) {
        }
      }
    }
  };
  std::vector<std::thread> pool;
  const int workers = std::min<int>(threads, static_cast<int>(blocks.size()));
  for (int k = 1; k < workers; ++k) pool.emplace_back(worker);
  worker();
  for (auto& th : pool) th.join();

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
    AdviseHugePages(tb->tag.t_s.data(), rows * sizeof(double));
    AdviseHugePages(tb->tag.line.data(), rows * sizeof(uint32_t));
    for (size_t q = 0; q < nq; ++q) {
      Quantity quantity;
      const int f = plan.numeric_fields[q];
      quantity.name = plan.names[f];
      quantity.unit = plan.info[f].unit;
      quantity.origin = QuantityOrigin::kFile;
      quantity.values.reserve(rows);
      AdviseHugePages(quantity.values.data(), rows * sizeof(double));
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

}  // namespace metro::internal
