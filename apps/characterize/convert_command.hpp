// characterize convert INPUT... -o session.csv: any supported input as the canonical
// session.csv (docs/formats.md).
#pragma once

#include <string>
#include <vector>

#include "load_cli.hpp"

namespace metro::apps {

struct ConvertOptions {
  std::vector<std::string> inputs;
  std::string from;    // --from FORMAT, the older spelling of --format (and of --imutk).
  bool imutk = false;  // --imutk: the inputs are imu_tk's two files, ACC GYRO.
  std::string output;
  LoadCliOptions load;  // --format and the other load flags.
};

int RunConvert(const ConvertOptions& o);

}  // namespace metro::apps
