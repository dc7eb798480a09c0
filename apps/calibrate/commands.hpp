// The calibrate subcommands. Each Add*Command registers its options and callback on the CLI11
// app; the callback runs the command and records its exit code.
#pragma once

#include <CLI/CLI.hpp>

namespace metro::calibrate_app {

// Exit codes (STYLE.md rule 16).
inline constexpr int kExitOk = 0;
inline constexpr int kExitFailed = 1;
inline constexpr int kExitUsage = 2;

void AddFitCommand(CLI::App& app, int* exit_code);
void AddApplyCommand(CLI::App& app, int* exit_code);
void AddReportCommand(CLI::App& app, int* exit_code);

}  // namespace metro::calibrate_app
