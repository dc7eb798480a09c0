// The options `characterize SESSION` and `characterize batch` share: input format, window,
// tag names and the Allan analysis. One definition, so the two commands cannot drift apart.
#pragma once

#include <CLI/CLI.hpp>
#include <optional>
#include <string>
#include <vector>

#include "load_cli.hpp"
#include "metro/core/status.hpp"
#include "metro/io/session_io.hpp"
#include "metro/report/session_analysis.hpp"

namespace metro::apps {

struct AnalysisCliOptions {
  LoadCliOptions load;  // --format, --column, --rate-hz, ... (load_cli.hpp).
  int64_t skip_samples = 0;
  double skip_seconds = 0.0;
  std::optional<double> from_s;
  std::optional<double> to_s;
  std::string settle = "none";
  std::string settle_scope = "quantity";  // "tag": one cut per tag (--settle-scope).
  std::vector<int> sensors;
  std::vector<std::string> quantities;
  std::string tag_registry;
  bool allan = false;
  std::string taus = "octave";
  std::string estimator = "oadev";
  std::string gaps = "skip";  // --gaps: skip, split or refuse (docs/noise.md, "Gaps").
};

// Registers the load flags (load_cli.hpp), --skip-samples, --skip-seconds,
// --from-s, --to-s, --settle, --settle-scope, --sensor, --quantity, --tag-registry,
// --allan, --taus, --estimator and --gaps on `app`.
void AddAnalysisCliOptions(CLI::App* app, AnalysisCliOptions* o);

// The library options for these flags; `threads` is the worker count inside one session
// (0: all cores). Errors (an unreadable tag registry, an unknown tau spacing or
// estimator, invalid options) are usage errors.
Status MakeSessionAnalysisOptions(const AnalysisCliOptions& o, int threads,
                                  SessionAnalysisOptions* out);

}  // namespace metro::apps
