// The calibrate subcommands. Each Add*Command registers its options and callback on the CLI11
// app; the callback runs the command and records its exit code.
#pragma once

#include <CLI/CLI.hpp>

#include "exit_codes.hpp"

namespace metro::calibrate_app {

using apps::kExitFailed;
using apps::kExitOk;
using apps::kExitUsage;

void AddFitCommand(CLI::App& app, int* exit_code);
void AddApplyCommand(CLI::App& app, int* exit_code);
void AddReportCommand(CLI::App& app, int* exit_code);
void AddBlobCommand(CLI::App& app, int* exit_code);
void AddInspectCommand(CLI::App& app, int* exit_code);
void AddPushCommand(CLI::App& app, int* exit_code);

}  // namespace metro::calibrate_app
