// session.csv's clean fast path (docs/formats.md; its speed: docs/benchmarks.md, "Type A").
//
// Most session files have no malformed row, no text column and time increasing per tag.
// For those, one parallel pass parses each block (512 kB) into a stage, the block's rows
// tag by tag and column by column, runs of machine-written rows four fields per
// instruction (DecimalRows, AVX-512), and the stages are appended to the tag columns in
// block order as they complete. No buffer or column asks for transparent huge pages (on a
// VM whose host takes back free huge pages, a cold huge page faults in at ~1 GB/s; both
// loaders measured faster without them: docs/benchmarks-history.md, "Huge pages").
#include <fast_float/fast_float.h>
#include <sys/mman.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <condition_variable>
#include <cstring>
#include <limits>
#include <memory>
#include <mutex>
#include <new>
#include <optional>

#include "core/parallel.hpp"
#include "core/plain_decimal.hpp"
#include "io/csv_blocks.hpp"
#include "io/decimal_rows.hpp"
#include "io/session_internal.hpp"
#include "metro/core/check.hpp"

namespace metro::internal {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
std::atomic<int64_t> clean_path_loads{0};

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
// whole, but 128 kB to 8 MB blocks measured no faster (docs/benchmarks-history.md, "One-pass
// clean path and block size").
constexpr size_t kCleanBlockBytes = size_t{512} << 10;

// Pieces of a file block: its bytes in kCleanBlockBytes steps, the last piece taking the
// remainder (kCleanBlockBytes to 2 kCleanBlockBytes).
size_t PieceCount(const Block& block) {
  return std::max<size_t>(1, (block.end - block.begin) / kCleanBlockBytes);
}

// Just after the end of the line holding byte `at` of `block`, or the block's end.
size_t LineBoundaryAfter(const MappedFile& file, const Block& block, size_t at) {
  const char* from = file.data() + at;
  const char* nl = static_cast<const char*>(
      std::memchr(from, '\n', static_cast<size_t>(file.data() + block.end - from)));
  return nl != nullptr ? static_cast<size_t>(nl - file.data()) + 1 : block.end;
}

// Turns piece k of n of `block` (piece->begin = k, piece->end = n, as queued) into its byte
// range: its ends are the line boundaries after the nominal offsets k and k + 1 times
// kCleanBlockBytes, so neighbouring pieces, placed by different workers, meet exactly; a
// line longer than a piece leaves a piece empty.
void PlacePiece(const MappedFile& file, const Block& block, CleanBlock* piece) {
  const size_t k = piece->begin, n = piece->end;
  piece->begin =
      k == 0 ? block.begin : LineBoundaryAfter(file, block, block.begin + k * kCleanBlockBytes);
  piece->end = k + 1 == n
                   ? block.end
                   : LineBoundaryAfter(file, block, block.begin + (k + 1) * kCleanBlockBytes);
}

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
// leaves little faulted in for nothing. 2^15 rows (256 kB of a double column, the smallest
// range queued): 2^17 left up to 1 MB per column faulted in ahead, 30 MiB of the peak of a
// 15-tag, 9-column session (422 -> 391 MiB on 5.4 M rows; CPU within 1.5 %, 8 alternating
// runs; issue #38 step 3).
constexpr size_t kRowsAhead = size_t{1} << 15;

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

// Appends parsed blocks' stages to the tag columns, in block order, one block at a time
// (the caller serialises the calls). A tag's columns are reserved, when the tag first
// appears, for the rows it would have if the rest of the file held them at that block's
// rate, 5% over (only the pages written are ever faulted in); a tag that outgrows that is
// reallocated (correct, only slower).
class CleanAppender {
 public:
  CleanAppender(const ColumnPlan& plan, const MappedFile& file, int64_t first_line,
                PageQueue* pages)
      : plan_(plan), file_(file), next_line_(first_line), pages_(pages) {}

  // Appends the stage of `block`. False when its rows do not fit the clean path (a time
  // that does not increase strictly within its tag, or a line beyond 32 bits): the general
  // loader then reports (or, with --lenient, rejects) the rows in file order.
  bool Append(const CleanBlock& block, const BlockStage& stage) {
    if (next_line_ + stage.lines - 1 > kMaxLineNumber) return false;
    for (const StagedTag& st : stage) {
      Tag& tag = TagFor(st, block);
      QueuePages(st.sensor, tag);
      if (!AppendRows(st, &tag)) return false;
    }
    next_line_ += stage.lines;
    return true;
  }

  // The tags, sorted by sensor; empty if a tag has more rows than 32-bit line numbers.
  std::vector<Tag> TakeTags() {
    std::vector<Tag> out;
    for (std::unique_ptr<Tag>& tag : tags_) {
      if (tag == nullptr) continue;
      if (tag->t_s.size() > UINT32_MAX) return {};
      tag->counts.frames = tag->counts.fresh = static_cast<int64_t>(tag->t_s.size());
      out.push_back(std::move(*tag));
    }
    return out;
  }

 private:
  Tag& TagFor(const StagedTag& st, const CleanBlock& block) {
    std::unique_ptr<Tag>& slot = tags_[static_cast<size_t>(st.sensor)];
    if (slot != nullptr) return *slot;
    slot = std::make_unique<Tag>();
    Tag& tag = *slot;
    tag.sensor = st.sensor;
    const double rate = static_cast<double>(st.rows) / static_cast<double>(block.end - block.begin);
    const size_t expected =
        static_cast<size_t>(rate * static_cast<double>(file_.size() - block.begin));
    for (const int f : plan_.numeric_fields) {
      Quantity quantity;
      quantity.name = plan_.names[static_cast<size_t>(f)];
      quantity.unit = plan_.info[static_cast<size_t>(f)].UnitSymbol();
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
      // The guess can exceed what the system lets one allocation have (a tag dense in its
      // first block, rare after it, on a file of tens of GB); the columns then grow as they
      // fill. If they cannot, the load fails with a clear error.
      reserve(2 * st.rows);
    }
    return tag;
  }

  void QueuePages(int sensor, const Tag& tag) {
    std::vector<uintptr_t>& queued = queued_pages_[static_cast<size_t>(sensor)];
    queued.resize(tag.quantities.size() + 2);
    QueueColumnPages(tag.t_s, &queued[0], pages_);
    QueueColumnPages(tag.line, &queued[1], pages_);
    for (size_t q = 0; q < tag.quantities.size(); ++q) {
      QueueColumnPages(tag.quantities[q].values, &queued[q + 2], pages_);
    }
  }

  bool AppendRows(const StagedTag& st, Tag* tag) const {
    const size_t n = st.rows;
    const double* t = st.values.data();
    // Time must increase strictly per tag; checked here, while the stage is in cache,
    // rather than in another pass over the columns.
    double last_t = tag->t_s.empty() ? -std::numeric_limits<double>::infinity() : tag->t_s.back();
    bool increasing = true;
    for (size_t r = 0; r < n; ++r) {
      increasing &= t[r] > last_t;
      last_t = t[r];
    }
    if (!increasing) return false;
    tag->t_s.insert(tag->t_s.end(), t, t + n);
    for (size_t q = 0; q < tag->quantities.size(); ++q) {
      const double* v = st.values.data() + (q + 1) * st.room;
      tag->quantities[q].values.insert(tag->quantities[q].values.end(), v, v + n);
    }
    const uint32_t first = static_cast<uint32_t>(next_line_);
    // Block-relative lines copied, then made absolute where they now lie (in cache; a loop
    // of push_backs checks the capacity per row).
    const size_t at = tag->line.size();
    tag->line.insert(tag->line.end(), st.line.data(), st.line.data() + n);
    uint32_t* lines = tag->line.data() + at;
    for (size_t r = 0; r < n; ++r) lines[r] += first;
    return true;
  }

  const ColumnPlan& plan_;
  const MappedFile& file_;
  int64_t next_line_;  // First line of the next block to append.
  PageQueue* pages_;
  std::array<std::unique_ptr<Tag>, 256> tags_;
  // How far each column's pages are queued (t_s, line, then the quantities), by sensor.
  std::array<std::vector<uintptr_t>, 256> queued_pages_;
};

}  // namespace

int64_t CleanPathLoads() { return clean_path_loads.load(); }

// The clean-file path. Returns no value when the file needs the general loader.
// `cut` is the file's blocks (CutBlocks), the same the general loader parses.
std::optional<Session> LoadCleanCsv(const std::string& path, const MappedFile& file,
                                    const HeaderLine& header, const ColumnPlan& plan, int threads,
                                    const std::vector<Block>& cut, BlockProgress* progress,
                                    ReleaseBehind* release) {
  if (!plan.CleanPathCan() || cut.empty()) return std::nullopt;
  // The file's blocks cut again into clean-path blocks; a file block counts as parsed
  // (progress) once all of its pieces are. A piece's ends are found by the worker that parses
  // it (PlacePiece), not here: finding them all up front touched a page every 512 kB, and
  // the kernel maps a page-cache folio around each touch, so most of the file was mapped
  // before the first row was parsed (peak RSS, issue #38).
  std::vector<CleanBlock> blocks;
  std::vector<std::atomic<uint32_t>> pieces_left(cut.size());
  for (size_t c = 0; c < cut.size(); ++c) {
    const size_t pieces = PieceCount(cut[c]);
    for (size_t k = 0; k < pieces; ++k) blocks.push_back(CleanBlock{k, pieces, c});
    pieces_left[c].store(static_cast<uint32_t>(pieces));
  }
  const size_t workers = std::min(static_cast<size_t>(ResolveThreads(threads)), blocks.size());
  std::vector<int> staged_fields{plan.time_field};
  staged_fields.insert(staged_fields.end(), plan.numeric_fields.begin(), plan.numeric_fields.end());
  StagePool pool(workers + 2, staged_fields);

  PageQueue pages;
  CleanAppender appender(plan, file, header.line_number + 1, &pages);
  // False once a block's rows do not fit the clean path (a line neither parser accepts,
  // or a time that does not increase strictly within its tag).
  std::atomic<bool> clean{true};
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
      if (!appender.Append(blocks[next_append], *next)) clean.store(false);
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
      PlacePiece(file, cut[blocks[i].cut], &blocks[i]);
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
  session.tags = appender.TakeTags();
  if (session.tags.empty()) return std::nullopt;  // Header only: the general loader words it.
  for (const Tag& tag : session.tags) session.rows += tag.counts.fresh;
  clean_path_loads.fetch_add(1);
  return session;
}

}  // namespace metro::internal
