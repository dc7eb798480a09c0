// Private: the cut of a session.csv file into line-aligned blocks, shared by its two
// loaders (the clean fast path and the general path), and the loaders themselves.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "io/csv_plan.hpp"
#include "io/mapped_file.hpp"
#include "io/release_behind.hpp"
#include "metro/core/status.hpp"
#include "metro/io/session.hpp"
#include "metro/io/session_io.hpp"

namespace metro::internal {

struct BadRow {
  uint32_t local_line;
  int field;  // 1-based; 0 if not about one field
  std::string message;
};

// One block of the file, parsed row-major by the general path.
struct Block {
  size_t begin = 0;
  size_t end = 0;
  uint32_t lines = 0;  // Lines in the block (the last may lack its line end).
  std::vector<uint8_t> sensor;
  std::vector<double> t_s;    // Time in seconds (t_s columns).
  std::vector<int64_t> t_ns;  // Or exact integer time in ns (t_ms, t_us, t_ns columns).
  std::vector<uint32_t> local_line;
  std::vector<double> numeric;    // Row-major, plan.numeric_fields.size() per row.
  std::vector<std::string> text;  // Row-major, plan.text_fields.size() per row.
  std::vector<BadRow> bad;
  int64_t time_resolution_ns = 0;  // Coarsest E-notation time resolution seen (0: none).
  bool parsed = false;
};

// Cuts [data_begin, data_end) into blocks ending at line ends (`line_end`).
std::vector<Block> CutBlocks(const MappedFile& file, size_t data_begin, size_t data_end,
                             char line_end, int threads);

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

// The clean-file path (csv_clean.cpp): canonical files only (ColumnPlan::CleanPathCan).
// Returns no value when the file needs the general loader.
std::optional<Session> LoadCleanCsv(const std::string& path, const MappedFile& file,
                                    const HeaderLine& header, const ColumnPlan& plan, int threads,
                                    const std::vector<Block>& cut, BlockProgress* progress,
                                    ReleaseBehind* release);

// The general path (csv_general.cpp): every dialect, strict and lenient, exact errors.
Result<Session> LoadGeneralCsv(const std::string& path, const MappedFile& file,
                               const HeaderLine& header, const ColumnPlan& plan,
                               const LoadOptions& options, int threads, std::vector<Block>* blocks,
                               BlockProgress* progress, ReleaseBehind* release);

// The general path in groups of about group_bytes (the streaming mode, issue #38): each
// group's rows are handed to on_group as a session whose tags hold only those rows (no text
// columns), then dropped, and the file's pages behind the group are released; the rows are
// checked as LoadGeneralCsv checks them, across groups too. Returns the session without rows
// (path, format, dialect, columns, row and rejection counts).
Result<Session> StreamGeneralCsv(const std::string& path, const MappedFile& file,
                                 const HeaderLine& header, const ColumnPlan& plan,
                                 const LoadOptions& options, size_t group_bytes,
                                 const std::function<Status(Session& group)>& on_group);

}  // namespace metro::internal
