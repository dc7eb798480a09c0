// characterize accuracy SESSION [--table-axis yaw|pitch|roll] [--reference LOG]
//   [--reference-u DEG|BUDGET.json] [-o REPORT.json]: accuracy against a rotation table
// (docs/accuracy.md). Also spelled characterize SESSION --accuracy ...: there the options
// live on the top-level app next to the main job's, and the analyze path calls RunAccuracy
// when --accuracy is given.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "analysis_options.hpp"
#include "load_cli.hpp"
#include "metro/accuracy/accuracy.hpp"
#include "metro/stats/session_type_a.hpp"

namespace metro::apps {

struct AccuracyCliOptions {
  bool enabled = false;
  std::string table_axis = "yaw";
  std::string reference;    // Separate reference log (t_s, table_angle_deg).
  std::string reference_u;  // Standard uncertainty in deg, or a budget file.
  std::string model = "auto";
  // --min-dwell-s, --settle-s, --plateau-tolerance-deg, --assumed-hysteresis-deg,
  // --lag-tau-s and --reference-offset-s, bound to the library's options (their defaults are
  // the library's); RunAccuracy sets the rest.
  AccuracyOptions library;
  bool no_lag_model = false;
  bool keep_departures = false;
};

// What the accuracy run shares with the main job's options.
struct AccuracyRunInputs {
  std::string session;
  LoadCliOptions load;
  std::vector<int> sensors;
  std::string output;
  bool settle_auto = false;  // --settle auto: MSER-5 within each plateau too.
  int threads = 0;
  bool type_a = false;   // --type-a given as well: a usage error.
  std::string html;      // Also write the HTML view here (docs/reports.md).
  WindowOptions window;  // --skip-samples, --skip-seconds, --from-s, --to-s.
  std::string tags;      // --tags FILE: the tag's name and device ID in the report.
};

// The options of --accuracy that only the accuracy evaluation uses (refused without it).
const std::vector<std::string>& AccuracyOnlyOptionNames();
int RunAccuracy(const AccuracyCliOptions& options, const AccuracyRunInputs& inputs);

// `characterize accuracy SESSION ...` (--accuracy implied).
struct AccuracyCommandOptions {
  std::string session;
  AnalysisCliOptions analysis;  // Input and window (AnalysisCliKind::kAccuracy).
  AccuracyCliOptions accuracy;
  std::string output;
  std::string html;
  int threads = 0;
};

int RunAccuracyCommand(AccuracyCommandOptions o);

}  // namespace metro::apps
