// One session through the main job: load, Type A (JCGM 100 4.2) per tag and quantity, and
// optionally the Allan deviation (IEEE Std 952) and an uncertainty budget (JCGM 100/101).
// `characterize SESSION --type-a` and `characterize batch` both call AnalyzeSession, so a
// report means the same thing whichever way it was made.
#pragma once

#include <string>
#include <vector>

#include "metro/core/progress.hpp"
#include "metro/core/status.hpp"
#include "metro/io/session.hpp"
#include "metro/io/session_io.hpp"
#include "metro/io/tag_registry.hpp"
#include "metro/report/allan_section.hpp"
#include "metro/report/plot_data.hpp"
#include "metro/report/session_report.hpp"
#include "metro/stats/session_type_a.hpp"

namespace metro {

struct SessionAnalysisOptions {
  LoadOptions load;
  SessionTypeAOptions type_a;
  TagRegistry registry = TagRegistry::Default();
  bool allan = false;
  SessionAllanOptions allan_options;  // Used when `allan`.
  bool allan_csv = false;             // Also render the Allan curves as CSV.
  // What the session page will plot, computed here and kept in the report (each quantity's
  // "plot", plot_data.hpp).
  PlotDataOptions plot;
  // With `allan` and no quantities named: a session without any rate quantity (gyroscope
  // or accelerometer column) is still reported, with "allan_skipped" saying why, instead
  // of failing. `characterize batch` sets this: one angle-only session in a fleet
  // directory must not cost its Type A report.
  bool allan_skip_without_rates = false;
  // Uncertainty budget file (docs/budget-format.md); empty: none. Inputs without a
  // "session" refer to the analysed session, in the same window.
  std::string budget_path;
  // Optional, not owned: hears of each phase (load with its bytes, Type A, Allan, the
  // budget's Monte Carlo trials) as it runs. Results never depend on it.
  ProgressSink* progress = nullptr;
  // AnalyzeSessionStreamed: bytes of the file read per group of rows (memory 3-15x this).
  size_t stream_group_bytes = size_t{8} << 20;

  bool IsValid(std::string* why) const;
};

// What AnalyzeSession produced. The defaults read as failure.
struct SessionAnalysis {
  bool ok = false;
  // Set when !ok. `input_error` distinguishes bad input or options (exit 2) from a
  // computation that failed on valid input (exit 1).
  Error error;
  bool input_error = true;

  Session session;
  SessionTypeA type_a;
  SessionReport report;   // "metro.report/1" (docs/report-schema.md).
  std::string table;      // TypeAReportTable + the budget table, for people.
  std::string allan_csv;  // When options.allan_csv and a curve was made.
  // A line per requested analysis that produced nothing for a quantity ("--allan: sensor 3
  // gx_dps: <reason>"), for stderr; the report holds the same reason.
  std::vector<std::string> failures;
  // Doubtful numbers of a requested analysis, for stderr ("--budget: ..."; the budget's
  // central-difference derivatives, issue #36).
  std::vector<std::string> warnings;
  // A requested analysis produced nothing for any quantity (the app exits 1, issue #21).
  bool nothing_produced = false;
};

SessionAnalysis AnalyzeSession(const std::string& path, const SessionAnalysisOptions& options);

// The same on a session already in memory (loaded by LoadSession, or built by a caller such as
// the Python module's Session.from_arrays); options.load is not used. A budget's inputs
// without a "session" refer to this session.
SessionAnalysis AnalyzeLoadedSession(Session session, const SessionAnalysisOptions& options);

}  // namespace metro
