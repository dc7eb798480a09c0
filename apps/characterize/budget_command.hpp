// `characterize budget BUDGET.json [-o REPORT.json]`: evaluates an uncertainty budget (GUM
// framework, Monte Carlo, GUF validation) and writes the "metro.budget-report/1" JSON.
// With -o the JSON goes to the file and the readable table to stdout; with -o -, the JSON
// to stdout and the table to stderr (no table under --quiet); without -o, the JSON to
// stdout. --html PAGE.html also writes the budget page (metro/report/budget_page.hpp). Exit codes:
// 0 ok, 1 the work failed (adaptive Monte Carlo did not settle, output not written), 2 usage or
// input error (the message names the input).
#pragma once

#include <string>

#include "metro/uncertainty/budget.hpp"

namespace metro {

struct BudgetOptions {
  std::string budget_path;
  std::string output_path;  // Empty or "-": JSON to stdout.
  std::string html_path;    // Empty: no page; "-": the page to stdout (then -o must name a file).
  // Answers the budget's session quantities ("type_a_from_session" inputs). Empty: such
  // inputs are errors naming the input. AddBudgetCommand sets one that evaluates each named
  // session in full (no window; MakeSessionQuantityResolver).
  SessionQuantityResolver session_resolver;
};

int RunBudget(const BudgetOptions& options);

}  // namespace metro
