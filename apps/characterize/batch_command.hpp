// characterize batch INPUTS... -o DIR [--html PAGE] [--jobs N]: many sessions in parallel
// (docs/reports.md "Batch page").
#pragma once

#include <string>
#include <vector>

#include "analysis_options.hpp"

namespace metro::apps {

struct BatchCommandOptions {
  std::vector<std::string> inputs;
  std::string output_dir;
  std::string html;  // The batch page; each session's page goes beside its JSON report.
  int jobs = 0;
  bool type_a = false;
  AnalysisCliOptions analysis;  // Input, window, tag names, Allan (analysis_options.hpp).
};

int RunBatchCommand(const BatchCommandOptions& o);

}  // namespace metro::apps
