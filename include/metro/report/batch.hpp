// `characterize batch`: many sessions through AnalyzeSession in parallel, one JSON report
// per session, a summary across sessions ("metro.batch-summary/1", docs/reports.md), and
// every failure named with its error. One bad file never costs the other results.
#pragma once

#include <cstddef>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "metro/core/status.hpp"
#include "metro/report/session_analysis.hpp"

namespace metro {

inline constexpr const char* kBatchSummarySchema = "metro.batch-summary/1";

// Expands the command-line arguments into session files, sorted and without duplicates:
// a directory gives its *.csv and *.txt files (not recursive), a pattern with * ? or [ is
// expanded with glob(3), anything else is taken as a file. Errors: an argument that names
// nothing (missing file, empty directory, pattern without a match), no argument.
Result<std::vector<std::string>> ExpandBatchInputs(const std::vector<std::string>& arguments);

// Report file names (without directory) for `inputs`: "<stem>.report.json", and
// "<stem>-<first 8 hex digits of the SHA-256 of the path>.report.json" for stems that
// occur more than once, so two sessions with one basename in different directories never
// overwrite each other. Never "summary.json".
std::vector<std::string> BatchReportNames(const std::vector<std::string>& inputs);

struct BatchOptions {
  SessionAnalysisOptions analysis;  // Per session; its thread counts are forced to 1.
  std::string output_dir;           // Created if missing.
  int jobs = 0;                     // Sessions in parallel; 0: all cores.
  // Called after each session (from a worker thread, serialised): sessions done, total.
  std::function<void(size_t done, size_t total)> on_progress;

  bool IsValid(std::string* why) const;
};

struct BatchItem {
  std::string input;
  std::string report_path;  // Written when ok.
  bool ok = false;
  Error error;  // When !ok.
  bool input_error = true;
};

// What RunBatch produced. The defaults read as failure.
struct BatchSummary {
  bool ok = false;                 // Every session analysed and written, and the summary written.
  size_t failed = 0;               // Sessions that failed.
  std::vector<BatchItem> items;    // In input order.
  nlohmann::ordered_json summary;  // Also written to output_dir/summary.json.
  std::string table;               // Also written to output_dir/summary.txt.
  Error error;  // Set when the run itself failed (bad options, output directory, summary).
};

// Analyses every input. Per tag (sensor number and name) and quantity, across the sessions
// that evaluated it: the mean of the session means, the standard deviation of the session
// means (n - 1), and the worst (smallest) n_eff/n with its session.
BatchSummary RunBatch(const std::vector<std::string>& inputs, const BatchOptions& options);

}  // namespace metro
