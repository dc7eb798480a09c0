// The batch summary ("metro.batch-summary/1", docs/reports.md, "summary.json") as plain data:
// what `characterize batch` writes beside the session reports, what the batch page renders
// and what `characterize report summary.json` re-renders. One codec: ToJson writes the text
// batch has always written (keys, order, numbers byte for byte) and BatchSummaryFromJson
// reads it back, failing at the offending value's file:line:column with its path (e.g.
// `summary.json:12:18: sessions[0].tags[1].frames: expected an integer, found a string`).
//
// Conventions (as session_report.hpp): a number written as null when not finite is NaN here;
// a member that may be absent is std::optional (absent when nullopt). Keys added by later
// metro versions are optional when reading, so older summaries still load and are written
// back with the keys they had: "warnings", "tags", quantities[].statistics (issue #21) and
// sessions[].page, sessions[].tags, sessions[].quantities (issue #25).
#pragma once

#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "metro/core/status.hpp"
#include "metro/report/session_report.hpp"

namespace metro {

inline constexpr const char* kBatchSummarySchema = "metro.batch-summary/1";

// "sessions[i].tags[j]": one tag's receiver frame counts in one session.
struct BatchSessionTag {
  int64_t sensor = 0;
  std::string name;
  int64_t frames = 0;
  int64_t fresh = 0;
  int64_t stale = 0;
  int64_t never = 0;
  bool dead = false;  // frames > 0 and no fresh packet.
};

// "sessions[i].quantities[j]": one tag's quantity in one session, in the quantity's unit.
struct BatchSessionQuantity {
  int64_t sensor = 0;
  std::string name;  // The tag's name.
  std::string quantity;
  std::string unit;
  double mean = std::nan("");
  double u_mean = std::nan("");  // As the session's report recommends it.
  double n = std::nan("");       // Observations (written as a JSON number with a fraction).
};

// "sessions[i]": one input, in input order.
struct BatchSessionEntry {
  std::string input;
  bool ok = false;
  // When ok:
  std::string sha256;
  std::string report;               // File name in output_dir.
  std::optional<std::string> page;  // With --html: the session's page in output_dir.
  // This session's results (what the batch page plots); absent in summaries before issue #25.
  std::optional<std::vector<BatchSessionTag>> tags;
  std::optional<std::vector<BatchSessionQuantity>> quantities;
  // When !ok:
  std::string error;         // "file:line:column: message".
  bool input_error = false;  // true: bad input; false: the work failed.
};

// "quantities[i]": one tag's quantity across the sessions that evaluated it.
struct BatchQuantitySummary {
  int64_t sensor = 0;
  std::string name;  // The tag's name.
  std::string quantity;
  std::string unit;
  int64_t sessions = 0;                    // Number of session means.
  std::optional<std::string> statistics;   // "circular" or "linear"; absent before issue #21.
  double mean_of_means = std::nan("");     // NaN: null (angles cancelling on the circle).
  double std_of_means = std::nan("");      // NaN: null (fewer than 2 sessions).
  std::optional<double> resultant_length;  // Circular statistics only.
  double worst_n_eff_ratio = std::nan("");
  std::string worst_n_eff_session;
  std::optional<std::string> warning;
};

// "tags[i]": one tag over all sessions.
struct BatchTagSummary {
  int64_t sensor = 0;
  std::string name;
  int64_t sessions = 0;
  int64_t frames = 0;
  int64_t fresh = 0;
  int64_t stale = 0;
  int64_t never = 0;
  double packet_loss_ratio = 0.0;  // (stale + never) / frames; 0 without frames.
  int64_t sessions_without_fresh = 0;
};

// A "metro.batch-summary/1" document, keys in the order written.
struct BatchSummaryReport {
  std::string schema = kBatchSummarySchema;
  ReportTool tool;
  std::optional<std::vector<std::string>> warnings;  // Absent before issue #21.
  std::string output_dir;
  int64_t sessions_total = 0;
  int64_t sessions_failed = 0;
  std::vector<BatchSessionEntry> sessions;
  std::vector<BatchQuantitySummary> quantities;
  std::optional<std::vector<BatchTagSummary>> tags;  // Absent before issue #21.
};

// The summary as JSON text, indent 2, without a trailing newline: exactly what batch writes.
std::string ToJson(const BatchSummaryReport& summary);

// Reads a summary written by ToJson (or by an older metro). `file` names it in errors.
// Errors: a syntax error, a missing member or a value of the wrong type, at its
// file:line:column with its path; a "schema" other than "metro.batch-summary/1";
// sessions_total or sessions_failed that disagree with "sessions".
Result<BatchSummaryReport> BatchSummaryFromJson(std::string_view text, const std::string& file);

}  // namespace metro
