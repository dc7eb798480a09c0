// `characterize batch`: many sessions through AnalyzeSession in parallel, one JSON report
// per session, a summary across sessions (BatchSummaryReport, "metro.batch-summary/1",
// batch_summary.hpp, docs/reports.md), and every failure named with its error. One bad file
// never costs the other results.
#pragma once

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include "metro/core/file_lock.hpp"
#include "metro/core/status.hpp"
#include "metro/report/batch_summary.hpp"
#include "metro/report/session_analysis.hpp"
#include "metro/report/session_report.hpp"

namespace metro {

// The lock file batch keeps in its output directory (docs/reports.md, "One batch per
// folder"); it holds "pid N on HOST, since UNIX-TIME" of the run holding it.
inline constexpr const char* kBatchLockName = ".metro-batch.lock";

// Expands the command-line arguments into session files, sorted and without duplicates:
// a directory gives its *.csv and *.txt entries (not recursive), a pattern with * ? or [ is
// expanded with glob(3), anything else is taken as a file. Nothing is silently left out:
// every *.csv and *.txt entry of a directory is returned whatever it is (a symlink is
// followed; a dangling link, a FIFO or a directory then fails as its own session in
// RunBatch, with the reason), and a directory matched by a pattern is named in `skipped`
// ("skipping PATH: why") when `skipped` is given. Errors: an argument that names nothing
// (missing file, empty directory, pattern without a match), no argument.
Result<std::vector<std::string>> ExpandBatchInputs(const std::vector<std::string>& arguments,
                                                   std::vector<std::string>* skipped = nullptr);

// Report file names (without directory) for `inputs`: "<stem>.report.json", and
// "<stem>-<first 8 hex digits of the SHA-256 of the path>.report.json" for stems that
// occur more than once, so two sessions with one basename in different directories never
// overwrite each other. Never "summary.json".
std::vector<std::string> BatchReportNames(const std::vector<std::string>& inputs);

struct BatchOptions {
  SessionAnalysisOptions analysis;  // Per session; its thread counts are forced to 1.
  std::string output_dir;           // Created if missing.
  int jobs = 0;                     // Sessions in parallel; 0: all cores.
  // Also write each session's HTML page (RenderSessionAnalysisHtml) beside its JSON report,
  // "<report name without .json>.html", replaced together with the JSON; summary.json names
  // it ("page").
  bool session_pages = false;
  // Called after each session (from a worker thread, serialised): sessions done, total.
  std::function<void(size_t done, size_t total)> on_progress;

  bool IsValid(std::string* why) const;
};

struct BatchItem {
  std::string input;
  std::string report_path;  // Written when ok.
  std::string page_path;    // With BatchOptions::session_pages, written when ok.
  bool ok = false;
  Error error;  // When !ok.
  bool input_error = true;
};

// What RunBatch produced. The defaults read as failure.
struct BatchSummary {
  bool ok = false;               // Every session analysed and written, and the summary written.
  size_t failed = 0;             // Sessions that failed.
  std::vector<BatchItem> items;  // In input order.
  BatchSummaryReport summary;    // Also written to output_dir/summary.json (ToJson).
  std::string table;             // Also written to output_dir/summary.txt.
  // Inputs that were batch's own outputs in output_dir (summary.json, summary.txt,
  // *.report.json from an earlier run into the same folder), not analysed: "skipping PATH:
  // why", one per input.
  std::vector<std::string> skipped;
  Error error;  // Set when the run itself failed (bad options, output directory, summary).
};

// Takes the batch lock of `output_dir` (which exists): the file kBatchLockName in it, locked
// with flock(LOCK_EX | LOCK_NB), and records who holds it. Never waits: when another run
// holds it the error names that run ("pid N on HOST, since T") and says to wait or choose
// another directory.
Result<FileLock> LockBatchDirectory(const std::string& output_dir);

// Analyses every input. Per tag (sensor number and name) and quantity, across the sessions
// that evaluated it: the mean of the session means, the standard deviation of the session
// means (n - 1), and the worst (smallest) n_eff/n with its session. Angle quantities (unit
// deg or rad) are pooled with CircularStatisticsDeg (stats/circular.hpp): mean_of_means is the
// circular mean and std_of_means the circular sample_std ("statistics": "circular"). Per tag:
// frames, fresh, stale, never summed over the sessions and packet_loss_ratio = (stale + never) /
// frames ("tags"); a tag of a session with no fresh packet has a row there and in the
// table even without quantities, and a warning heads summary.json ("warnings") and the
// table.
//
// The output directory is created, then locked for the whole run (LockBatchDirectory: a
// second run into it fails with BatchSummary::error). Inputs that are batch's own outputs
// in that directory are left out and named in `skipped`; an input that is not a readable
// regular file, or whose report would be written over an input, fails as its own session.
// summary.json and summary.txt are replaced together (WriteFilesAtomically). Each entry of
// summary.json's "sessions" that was analysed also holds its own results for the batch page
// (batch_page.hpp): "tags" [{sensor, name, frames, fresh, stale, never, dead}] (dead: frames
// > 0 and no fresh packet) and "quantities" [{sensor, name, quantity, unit, mean, u_mean,
// n}] (u_mean as the session's report recommends it, in the quantity's unit).
BatchSummary RunBatch(const std::vector<std::string>& inputs, const BatchOptions& options);

}  // namespace metro
