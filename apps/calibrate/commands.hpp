// What the calibrate subcommands share: exit codes and how an error about calibration.json is
// printed. Each command's options and Run function are in its *_command.hpp; main.cpp binds
// them to the command line.
#pragma once

#include <fmt/format.h>

#include <optional>
#include <string>

#include "exit_codes.hpp"
#include "metro/core/status.hpp"

namespace metro::calibrate_app {

using apps::kExitFailed;
using apps::kExitOk;
using apps::kExitUsage;

// An error about calibration.json `calibration` as printed: at the file:line:column of the
// value when the library found it there (CalibrationErrorAt), else after the file's name.
inline std::string CalibrationErrorText(const std::string& calibration, const Error& error) {
  return error.file.empty() ? fmt::format("{}: {}", calibration, error.ToString())
                            : error.ToString();
}

}  // namespace metro::calibrate_app
