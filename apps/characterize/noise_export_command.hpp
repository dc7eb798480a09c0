// characterize noise-export REPORT.json --to FORMAT [-o FILE], or --from-spec PART: the noise
// terms of a report's tag as an estimator's noise file (docs/noise.md "Export to estimators").
#pragma once

#include <string>

#include "metro/noise/spec_library.hpp"
#include "noise_export_options.hpp"

namespace metro::apps {

struct NoiseExportCommandOptions {
  NoiseExportCliOptions common;
  std::string output = "-";
  // --from-spec PART: a datasheet's figures as Kalibr's imu.yaml (docs/specs.md "To Kalibr").
  std::string from_spec;
  std::string spec_library = DefaultSpecLibrary();
  SpecToKalibrOptions spec;
};

int RunNoiseExport(const NoiseExportCommandOptions& o);

}  // namespace metro::apps
