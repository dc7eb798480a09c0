// session.csv loader: the chooser between its two paths (docs/formats.md).
//
// The file is memory-mapped; its dialect and columns are planned from its first lines
// (csv_plan.cpp); it is cut into line-aligned blocks; canonical files take the clean fast
// path (csv_clean.cpp), and anything irregular, or any other dialect, the general path
// (csv_general.cpp), which explains every error exactly.
// The mapping's pages are released behind the parser and the SHA-256 hasher, whichever is
// slower (ReleaseBehind), so the file's pages give way to the parsed numbers. A hasher faster
// than the parser maps the pages ahead of it, which then stay until the parser is past them:
// holding the hasher within 12 MB of the parser took 29 MiB off the peak of a 389 MB session
// but cost 6 % of wall time (the free hasher prefaults the pages the parse threads read), so
// it runs free (issue #38, docs/benchmarks.md).
#include <algorithm>
#include <optional>
#include <thread>

#include "core/parallel.hpp"
#include "io/csv_blocks.hpp"
#include "io/session_internal.hpp"
#include "metro/core/file.hpp"

namespace metro::internal {
namespace {

// The hasher reports its progress (and so lets pages go) this many bytes at a time.
constexpr size_t kHashChunkBytes = size_t{4} << 20;
// The file's pages kept mapped ahead of a hasher slower than the parser (a CPU without SHA
// extensions, or one the hasher shares with other work) (ReleaseBehind): 16 MB, so the peak
// stays within a few tens of MB of the session's columns however slow the hasher. Pages
// released ahead of it are mapped again from the page cache when it gets there (a minor
// fault per 64 kB). A quarter of the file (as before) put up to 97 MB of a 389 MB file on
// the peak when the hasher lagged.
constexpr size_t kReleaseGapBytes = size_t{16} << 20;

Result<Session> LoadMappedCsv(const std::string& path, const MappedFile& file,
                              const LoadOptions& options, SessionFormat format,
                              bool allow_clean_path, ReleaseBehind* release) {
  if (file.size() == 0) {
    return MakeError(path, 0,
                     "empty file: expected a session.csv header line (t_s,...) "
                     "followed by data rows");
  }
  HeaderLine header;
  auto plan_or = PlanCsv(path, file, options, format, &header);
  if (!plan_or.ok()) return plan_or.error();
  const ColumnPlan& plan = plan_or.value();

  const int threads = ResolveThreads(options.threads);
  // One cut of the file, shared by the clean path and the general loader (so a block is
  // the same block for both, which BlockProgress relies on).
  const char line_end = plan.dialect.line_ends == "CR" ? '\r' : '\n';
  std::vector<Block> blocks = CutBlocks(file, header.data_begin, plan.data_end, line_end, threads);
  BlockProgress progress(options.on_bytes_parsed, blocks.size());
  // The comments and the header line before the first block, and a footer left out.
  if (options.on_bytes_parsed) {
    options.on_bytes_parsed(static_cast<int64_t>(header.data_begin + file.size() -
                                                 std::max(plan.data_end, header.data_begin)));
  }
  if (allow_clean_path && plan.CleanPathCan()) {
    if (auto session =
            LoadCleanCsv(path, file, header, plan, threads, blocks, &progress, release)) {
      session->format = plan.format;
      session->input = plan.dialect;
      session->columns = plan.names;
      return *std::move(session);
    }
  }
  return LoadGeneralCsv(path, file, header, plan, options, threads, &blocks, &progress, release);
}

}  // namespace

Result<Session> LoadSessionCsv(const std::string& path, const LoadOptions& options,
                               bool allow_clean_path, bool hash, SessionFormat format) {
  MappedFile file;
  if (Status s = file.Open(path); !s.ok()) return s.error();
  // The SHA-256 of the bytes, on a second thread while the parser works, from the parser's
  // own mapping: the file's pages are mapped once for both and released once both are past
  // them; a hasher slower than the parser keeps at most kReleaseGapBytes mapped behind the
  // parser (ReleaseBehind).
  ReleaseBehind release([&file](size_t begin, size_t end) { file.ReleaseBelow(begin, end); }, hash,
                        kReleaseGapBytes);
  std::string digest;
  std::optional<Result<Session>> session;
  RunBeside(
      [&] {
        if (!hash) return;
        digest = Sha256Hex(std::string_view(file.data(), file.size()), kHashChunkBytes,
                           [&release](size_t hashed) { release.Hashed(hashed); });
      },
      [&] { session = LoadMappedCsv(path, file, options, format, allow_clean_path, &release); });
  // A file truncated or rewritten while it was read: whatever was parsed (or whatever error
  // its zeros caused) is discarded for the one error that says what happened.
  if (const std::string changed = file.ChangedSinceOpen(); !changed.empty()) {
    return MakeError(path, 0, changed);
  }
  if (session->ok() && hash) session->value().sha256 = std::move(digest);
  return *std::move(session);
}

}  // namespace metro::internal
