// How the metro programs show progress on stderr (include/metro/core/progress.hpp).
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <system_error>

#include "metro/core/progress.hpp"

namespace metro::apps {

// On a terminal only, and only for work that runs longer than half a second, so quick runs
// stay quiet.
inline ProgressOptions CliProgressOptions() {
  ProgressOptions options;
  options.delay_s = 0.5;
  return options;
}

// Begins the phase "load FILE" of `progress`, counted in MB of the file.
inline void BeginLoadPhase(ProgressSink* progress, const std::string& path) {
  std::error_code ec;
  const auto bytes = std::filesystem::file_size(path, ec);
  progress->BeginPhase("load " + std::filesystem::path(path).filename().string(),
                       ec ? 0 : static_cast<int64_t>(bytes), "MB", 1e6);
}

}  // namespace metro::apps
