#include "budget_command.hpp"

#include <fmt/format.h>

#include <cstdio>
#include <memory>
#include <utility>

#include "cli_progress.hpp"
#include "metro/core/file.hpp"
#include "metro/core/progress.hpp"
#include "metro/report/budget_page.hpp"
#include "metro/uncertainty/budget_report.hpp"
#include "metro/uncertainty/session_resolver.hpp"
#include "output.hpp"

namespace metro {

void AddBudgetCommand(CLI::App& app, int* exit_code) {
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
  sub->callback([options, exit_code]() {
    const int code = RunBudget(*options);
    if (exit_code != nullptr) {
      *exit_code = code;
    } else if (code != 0) {
      throw CLI::RuntimeError(code);
    }
  });
}

int RunBudget(const BudgetOptions& options) {
  std::vector<apps::NamedPath> inputs = {{"BUDGET", options.budget_path}};
  for (std::string& session : SessionsNamedInBudget(options.budget_path)) {
    inputs.push_back({"a session of BUDGET", std::move(session)});
  }
  if (options.html_path == "-" && (options.output_path.empty() || options.output_path == "-")) {
    return apps::PrintErrorExit(
        MakeError("--html - and the JSON both go to stdout: name a file with -o or with --html"));
  }
  if (Status s =
          apps::CheckOutputs({{"-o", options.output_path}, {"--html", options.html_path}}, inputs);
      !s.ok()) {
    return apps::PrintErrorExit(s.error());
  }
  auto budget = LoadBudget(options.budget_path, options.session_resolver);
  if (!budget.ok()) {
    return apps::PrintErrorExit(budget.error());
  }
  // Named before any trial is drawn (JCGM 101 6.4.9.4, docs/uncertainty.md).
  if (budget.value().monte_carlo.enabled) {
    for (const std::string& name : InputsWithoutVariance(budget.value())) {
      apps::PrintWarning(
          fmt::format("input {} has no variance in the Monte Carlo method (t with nu <= 2): u(y) "
                      "will be undefined, the coverage intervals are still reported",
                      name));
    }
  }
  TerminalProgress progress(stderr, apps::CliProgressOptions());  // The Monte Carlo trials.
  auto evaluation = EvaluateBudget(budget.value(), &progress);
  progress.Finish();
  if (!evaluation.ok()) {
    // Bad models (NaN, undefined) and impossible joint distributions are input errors.
    return apps::PrintErrorExit(evaluation.error());
  }
  for (const std::string& w : evaluation.value().gum.warnings) {
    apps::PrintWarning(fmt::format("{}: {}", options.budget_path, w));
  }
  const BudgetReport report = MakeBudgetReport(evaluation.value());
  const std::string json = ToJson(report) + "\n";
  // No -o: the JSON to stdout and no table; -o -: the same, and the table to stderr.
  const std::string output = options.output_path.empty() ? "-" : options.output_path;
  std::string html;
  if (!options.html_path.empty()) {
    Result<std::string> page = RenderBudgetReportHtml(report);
    if (!page.ok()) {
      // The page of the evaluation just made: a failure is the run's, not the input's.
      return apps::PrintErrorExit(page.error().WithKind(ErrorKind::kFailed));
    }
    html = std::move(page).value();
  }
  // The JSON and the page are replaced together or not at all.
  const Status written = apps::WriteOutputs({{output, json}, {options.html_path, html}});
  if (!written.ok()) {
    return apps::PrintErrorExit(written.error());
  }
  if (!options.output_path.empty()) {
    apps::PrintTable(BudgetReportTable(report), options.output_path);
  }
  if (!evaluation.value().ok) {
    return apps::PrintErrorExit(MakeFailedError(evaluation.value().monte_carlo
                                                    ? evaluation.value().monte_carlo->message
                                                    : std::string("evaluation failed")));
  }
  return 0;
}

}  // namespace metro
