// characterize noise-compare FILE REPORT.json, or --spec-part PART: an estimator's noise file
// against a report's measurement, or a part's published figures side by side
// (docs/noise.md, docs/specs.md).
#pragma once

#include <string>

#include "noise_export_options.hpp"

namespace metro::apps {

struct NoiseCompareOptions {
  std::string file;
  std::string format;  // --format: empty, told by the keys.
  NoiseExportCliOptions common;
  // --spec-part PART [--reference DOC]: the part's published figures compared with each other.
  std::string spec_part;
  std::string spec_library = DefaultSpecLibrary();
  std::string reference;
};

int RunNoiseCompare(const NoiseCompareOptions& o);

}  // namespace metro::apps
