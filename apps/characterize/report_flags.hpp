// The flags of `characterize report`.
// Included by main.cpp only: the program's one translation unit with CLI11 (issue #39).
#pragma once

#include <CLI/CLI.hpp>
#include <memory>

#include "cli_flags.hpp"
#include "report_command.hpp"

namespace metro::apps {

inline void AddReportCommand(CLI::App& app, int* exit_code) {
  auto o = std::make_shared<ReportCommandOptions>();
  CLI::App* sub = app.add_subcommand(
      "report",
      "render a saved JSON (metro.report/1, metro.calibration/1, metro.accuracy-report/1, any "
      "other schema as tables) "
      "as a self-contained HTML page");
  sub->add_option("json", o->json, "REPORT.json")->required()->check(CLI::ExistingFile);
  sub->add_option("--html", o->html, "HTML file to write (- for stdout)")->required();
  sub->add_option("--session", o->session,
                  "accepted for older scripts and not used: a page is drawn from the report alone "
                  "(its plot data), no input is reloaded")
      ->check(CLI::ExistingFile);
  sub->add_option("--tags,--tag-registry", o->tags,
                  "tags file naming the tags on the page (docs/formats.md \"Tags file\"): a "
                  "session report's sensors, a calibration.json's tags (name, device_id, profile)")
      ->check(CLI::ExistingFile);
  sub->callback([o, exit_code] { *exit_code = RunReportCommand(*o); });
}

}  // namespace metro::apps
