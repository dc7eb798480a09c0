// How the metro programs show progress on stderr (include/metro/core/progress.hpp).
#pragma once

#include "metro/core/progress.hpp"
#include "unix_cli.hpp"

namespace metro::apps {

// On a terminal only, and only for work that runs longer than half a second, so quick runs
// stay quiet; never under --quiet.
inline ProgressOptions CliProgressOptions() {
  ProgressOptions options;
  options.delay_s = 0.5;
  if (Quiet()) options.mode = ProgressMode::kNever;
  return options;
}

}  // namespace metro::apps
