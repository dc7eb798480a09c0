// The flags of `characterize budget`.
// Included by main.cpp only: the program's one translation unit with CLI11 (issue #39).
#pragma once

#include <CLI/CLI.hpp>
#include <memory>

#include "budget_command.hpp"
#include "cli_flags.hpp"
#include "metro/uncertainty/session_resolver.hpp"

namespace metro::apps {

inline void AddBudgetCommand(CLI::App& app, int* exit_code) {
  auto options = std::make_shared<BudgetOptions>();
  // Budget files may name sessions; they are evaluated in full (no window).
  options->session_resolver = MakeSessionQuantityResolver("", {}, {});
  CLI::App* sub = app.add_subcommand(
      "budget", "Evaluate an uncertainty budget (GUM + JCGM 101 Monte Carlo) from a JSON file");
  sub->add_option("BUDGET", options->budget_path, "Budget file (docs/budget-format.md)")
      ->required()
      ->check(CLI::ExistingFile);
  sub->add_option("-o,--output", options->output_path,
                  "Write the metro.budget-report/1 JSON here and print the table; -o - "
                  "writes it to stdout and the table to stderr");
  sub->add_option("--html", options->html_path,
                  "Also write the budget page here: the statement, both coverage intervals, the "
                  "GUF validation, the Monte Carlo histogram with the GUF density, the "
                  "contributions (docs/reports.md, \"Budget page\"); - for stdout");
  sub->callback([options, exit_code] { *exit_code = RunBudget(*options); });
}

}  // namespace metro::apps
