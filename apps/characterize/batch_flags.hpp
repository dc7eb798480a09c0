// The flags of `characterize batch`.
// Included by main.cpp only: the program's one translation unit with CLI11 (issue #39).
#pragma once

#include <CLI/CLI.hpp>
#include <memory>

#include "analysis_flags.hpp"
#include "batch_command.hpp"
#include "cli_flags.hpp"

namespace metro::apps {

inline void AddBatchCommand(CLI::App& app, int* exit_code) {
  auto o = std::make_shared<BatchCommandOptions>();
  CLI::App* sub = app.add_subcommand(
      "batch",
      "analyse many sessions in parallel: one JSON report each, summary.json and a summary "
      "table per tag and quantity; a failing session is named and the others go on");
  sub->add_option("inputs", o->inputs,
                  "session files, directories (their *.csv and *.txt) or glob patterns")
      ->required();
  sub->add_option("-o,--output-dir", o->output_dir, "directory for the reports (created)")
      ->required();
  sub->add_option("--jobs", o->jobs, "sessions in parallel (default: all cores)")
      ->check(CLI::NonNegativeNumber);
  sub->add_option("--html", o->html,
                  "also write the batch page here (- for stdout): a row per session and tag with "
                  "dead tags marked, spread plots per quantity, links to each session's page, "
                  "written beside its JSON report (docs/reports.md, \"Batch page\")");
  sub->add_flag("--type-a", o->type_a, "GUM Type A evaluation (always done)");
  AddAnalysisCliOptions(sub, &o->analysis);
  sub->callback([o, exit_code] { *exit_code = RunBatchCommand(*o); });
}

}  // namespace metro::apps
