// The options `characterize noise-export` and `noise-compare` share: which tag of the report,
// the reduction over axes and the formats' own settings, and the report they read (issue #40).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "metro/core/status.hpp"
#include "metro/noise/noise_export.hpp"

namespace metro::apps {

struct NoiseExportCliOptions {
  std::string report;             // REPORT.json (metro.report/1 made with --allan).
  std::optional<int64_t> sensor;  // --sensor N.
  NoiseExportOptions library;     // --axis-reduction, --rostopic, --px4-predict-rate-hz.
};

// The formats' names (NoiseExportFormatName of kAllNoiseExportFormats), for CLI11's checks.
std::vector<std::string> NoiseExportFormatNames();

// The spec library shipped with metro (datasets/specs/specs.json of the source tree).
std::string DefaultSpecLibrary();

// The record of REPORT.json's tag (report/noise_export_input.hpp).
Result<NoiseExportInput> LoadNoiseExportInput(const NoiseExportCliOptions& o);

}  // namespace metro::apps
