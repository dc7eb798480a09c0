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

namespace {

// The outputs, checked before anything is evaluated: not both to stdout, none that names the
// budget or a session it names.
Status CheckBudgetOutputs(const BudgetOptions& options) {
  std::vector<apps::NamedPath> inputs = {{"BUDGET", options.budget_path}};
  for (std::string& session : SessionsNamedInBudget(options.budget_path)) {
    inputs.push_back({"a session of BUDGET", std::move(session)});
  }
  if (options.html_path == "-" && (options.output_path.empty() || options.output_path == "-")) {
    return MakeError("--html - and the JSON both go to stdout: name a file with -o or with --html");
  }
  return apps::CheckOutputs({{"-o", options.output_path}, {"--html", options.html_path}}, inputs);
}

// The budget evaluated (a progress line for the Monte Carlo trials on a terminal), its warnings
// printed. Inputs without a variance in the Monte Carlo method are named before any trial is
// drawn (JCGM 101 6.4.9.4, docs/uncertainty.md). Bad models (NaN, undefined) and impossible
// joint distributions are input errors.
Result<BudgetEvaluation> Evaluate(const BudgetOptions& options) {
  Result<Budget> budget = LoadBudget(options.budget_path, options.session_resolver);
  if (!budget.ok()) return budget.error();
  if (budget.value().monte_carlo.enabled) {
    for (const std::string& name : InputsWithoutVariance(budget.value())) {
      apps::PrintWarning(
          fmt::format("input {} has no variance in the Monte Carlo method (t with nu <= 2): u(y) "
                      "will be undefined, the coverage intervals are still reported",
                      name));
    }
  }
  TerminalProgress progress(stderr, apps::CliProgressOptions());
  Result<BudgetEvaluation> evaluation = EvaluateBudget(budget.value(), &progress);
  progress.Finish();
  if (!evaluation.ok()) return evaluation;
  for (const std::string& w : evaluation.value().gum.warnings) {
    apps::PrintWarning(fmt::format("{}: {}", options.budget_path, w));
  }
  return evaluation;
}

}  // namespace

int RunBudget(const BudgetOptions& options) {
  if (Status s = CheckBudgetOutputs(options); !s.ok()) return apps::PrintErrorExit(s.error());
  Result<BudgetEvaluation> evaluation = Evaluate(options);
  if (!evaluation.ok()) return apps::PrintErrorExit(evaluation.error());
  const BudgetReport report = MakeBudgetReport(evaluation.value());
  std::string html;
  if (!options.html_path.empty()) {
    Result<std::string> page = RenderBudgetReportHtml(report);
    // The page of the evaluation just made: a failure is the run's, not the input's.
    if (!page.ok()) return apps::PrintErrorExit(page.error().WithKind(ErrorKind::kFailed));
    html = std::move(page).value();
  }
  // No -o: the JSON to stdout and no table; -o -: the same, and the table to stderr. The JSON
  // and the page are replaced together or not at all.
  const std::string output = options.output_path.empty() ? "-" : options.output_path;
  if (Status w = apps::WriteOutputs({{output, ToJson(report) + "\n"}, {options.html_path, html}});
      !w.ok()) {
    return apps::PrintErrorExit(w.error());
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
