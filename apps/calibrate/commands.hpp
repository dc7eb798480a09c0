// What the calibrate subcommands share: exit codes and how an error about calibration.json is
// printed. Each command's options and Run function are in its *_command.hpp; main.cpp binds
// them to the command line.
#pragma once

#include <fmt/format.h>

#include <cstdint>
#include <optional>
#include <string>

#include "exit_codes.hpp"
#include "metro/blob/blob.hpp"
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

// --slot-address of `blob` and `inspect`: "0x3B000" or "241664" -> address; a page-aligned slot A
// whose slot B (the next page) lies in the nRF51's 256 KiB of flash.
inline Result<uint32_t> ParseSlotAddress(const std::string& text) {
  size_t used = 0;
  unsigned long long v = 0;
  try {
    v = std::stoull(text, &used, 0);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != text.size() || text.empty() || v % blob::kPageSize != 0 ||
      v + 2 * blob::kPageSize > 0x40000) {
    return MakeError(fmt::format(
        "--slot-address '{}': expected a multiple of 0x400 below 0x3F800 (slot B is the next "
        "page)",
        text));
  }
  return static_cast<uint32_t>(v);
}

}  // namespace metro::calibrate_app
