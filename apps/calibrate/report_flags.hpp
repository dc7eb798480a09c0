// The flags of `calibrate report`.
// Included by main.cpp only: the program's one translation unit with CLI11 (issue #39).
#pragma once

#include <CLI/CLI.hpp>
#include <memory>

#include "cli_flags.hpp"
#include "common_flags.hpp"
#include "report_command.hpp"

namespace metro::calibrate_app {

inline void AddReportCommand(CLI::App& app, int* exit_code) {
  auto o = std::make_shared<ReportOptions>();
  CLI::App* sub = app.add_subcommand("report", "print a readable summary of calibration.json");
  sub->add_option("calibration", o->calibration, "calibration.json")
      ->required()
      ->check(CLI::ExistingFile);
  sub->add_option("--html", o->html, "also write the calibration certificate (HTML) here");
  sub->add_flag("--accept-rejected-model", o->accept_rejected_model,
                "certify constants marked model_rejected (a model the data reject or an exact "
                "fit), with that notice on the certificate");
  AddTagsOption(sub, &o->tags);
  sub->callback([o, exit_code] { *exit_code = RunReport(*o); });
}

}  // namespace metro::calibrate_app
