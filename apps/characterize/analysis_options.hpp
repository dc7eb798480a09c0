// The options `characterize SESSION` and `characterize batch` share: input format, window,
// tag names and the Allan analysis. One definition, so the two commands cannot drift apart.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "load_cli.hpp"
#include "metro/core/status.hpp"
#include "metro/io/session_io.hpp"
#include "metro/report/allan_section.hpp"
#include "metro/report/session_analysis.hpp"

namespace metro::apps {

struct AnalysisCliOptions {
  LoadCliOptions load;  // --format, --column, --rate-hz, ... (load_cli.hpp).
  // --skip-samples, --skip-seconds, --from-s, --to-s, --settle (none|auto: settle_auto) and
  // --settle-scope (quantity|tag: settle_tag_wide), bound to the library's struct; its
  // defaults are the flags' defaults.
  WindowOptions window;
  std::vector<int> sensors;
  std::vector<std::string> quantities;
  std::string tag_registry;
  bool allan = false;
  // --taus (ParseTauSpacing: allan.taus), --estimator (ParseAllanEstimator: allan.estimator)
  // and --gaps (skip|split|refuse: gaps; docs/noise.md, "Gaps"), bound to the library's
  // struct; its defaults are the flags' defaults. Used with --allan only.
  SessionAllanOptions allan_options;
};

// Which analysis registers the options: the Type A analysis (`analyze`, `batch`, and the
// top-level `characterize SESSION`), or the accuracy evaluation (`accuracy`), which takes the
// input and window options only.
enum class AnalysisCliKind { kTypeA, kAccuracy };

// The window the accuracy evaluation takes from these flags.
WindowOptions AccuracyWindow(const AnalysisCliOptions& o);

// The library options for these flags; `threads` is the worker count inside one session
// (0: all cores). Errors (an unreadable tag registry, an unknown tau spacing or
// estimator, invalid options) are usage errors.
Status MakeSessionAnalysisOptions(const AnalysisCliOptions& o, int threads,
                                  SessionAnalysisOptions* out);

}  // namespace metro::apps
