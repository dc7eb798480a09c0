// GUM framework (JCGM 100:2008): law of propagation of uncertainty, Welch-Satterthwaite
// effective degrees of freedom and the expanded uncertainty.
//
//   y = f(x)                                     estimate at the input estimates
//   c_i = (f(x + h_i e_i) - f(x - h_i e_i)) / (2 h_i),  h_i = step_fraction * u(x_i)   (5.1.3)
//   u_c^2 = sum_i c_i^2 u_i^2 + 2 sum_{i<j} c_i c_j u_i u_j r_ij                      (5.2.2)
//   optional second-order terms for independent inputs (5.1.2 note):
//   + sum_i sum_j [ (1/2) (d2f/dxi dxj)^2 + df/dxi * d3f/(dxi dxj^2) ] u_i^2 u_j^2
//   nu_eff = u_c^4 / sum_i (u_i(y)^4 / nu_i),  u_i(y) = |c_i| u_i                    (G.4.1)
//     kept fractional; with correlations the GumOptions policy applies
//   k = t_{(1+p)/2}(nu_eff) (Boost.Math students_t, fractional nu; normal for nu = inf)
//   U = k u_c, interval [y - U, y + U]                                                (6.2)
#pragma once

#include <limits>
#include <string>
#include <vector>

#include "metro/core/status.hpp"
#include "metro/uncertainty/budget.hpp"

namespace metro {

// One row of the budget table.
struct BudgetLine {
  std::string name;
  double value = 0.0;         // x_i
  double u = 0.0;             // u(x_i)
  std::string distribution;   // DistributionName()
  double sensitivity = 0.0;   // c_i
  double contribution = 0.0;  // u_i(y) = |c_i| u(x_i), in the measurand's unit
  double dof = std::numeric_limits<double>::infinity();  // nu_i
  double percent = 0.0;  // 100 u_i(y)^2 / u_c^2 (sums to 100 without correlations)
};

struct GumResult {
  double value = std::numeric_limits<double>::quiet_NaN();  // y = f(x)
  double u = std::numeric_limits<double>::quiet_NaN();      // u_c(y), incl. second order if asked
  double u_first_order = std::numeric_limits<double>::quiet_NaN();
  double dof_eff = std::numeric_limits<double>::quiet_NaN();  // infinity allowed
  double k = std::numeric_limits<double>::quiet_NaN();
  double expanded = std::numeric_limits<double>::quiet_NaN();  // U = k u_c
  double coverage = std::numeric_limits<double>::quiet_NaN();
  double interval_low = std::numeric_limits<double>::quiet_NaN();
  double interval_high = std::numeric_limits<double>::quiet_NaN();
  bool second_order = false;
  CorrelatedDofPolicy dof_policy = CorrelatedDofPolicy::kGroup;
  bool correlated = false;  // Non-zero correlations between contributing inputs.
  std::string dof_note;     // How nu_eff was formed, in words.
  // How the sensitivity coefficients (and second-order terms) were taken: "exact
  // (symbolic, GiNaC)", "stated (no model)", or "central differences: <why the model could
  // not be differentiated symbolically>" (docs/uncertainty.md, "Derivatives").
  std::string derivatives;
  // False when any derivative was taken by central differences: the budget then states the
  // Monte Carlo result (or is refused without one; budget_report.hpp).
  bool derivatives_exact = true;
  // Said on stderr by the commands: central differences, with each input's relative step.
  std::vector<std::string> warnings;
  std::vector<BudgetLine> budget;  // Sorted by contribution, largest first.
};

// Evaluates the budget with its own GumOptions (budget.gum).
Result<GumResult> EvaluateGum(const Budget& budget);
// Evaluates with explicit options (budget.gum ignored).
Result<GumResult> EvaluateGum(const Budget& budget, const GumOptions& options);

// Student t quantile t_{(1+p)/2}(nu) for coverage p; the normal quantile for infinite nu.
double CoverageFactor(double coverage, double dof);

}  // namespace metro
