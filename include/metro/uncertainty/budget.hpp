// Budget: a validated uncertainty budget (measurand, inputs, correlations, options), parsed
// from the JSON format of docs/budget-format.md.
//
// Each input carries what both frameworks need:
//   - the GUM view (JCGM 100:2008): estimate x_i (`value`), standard uncertainty u(x_i) and
//     degrees of freedom nu_i (infinity when not stated);
//   - the JCGM 101:2008 view: the distribution assigned to X_i and its parameters.
// Standard uncertainties of Type B inputs follow JCGM 100 4.3 / JCGM 101 6.4 (half-width a):
//   rectangular a/sqrt(3); triangular a/sqrt(6); arcsine a/sqrt(2);
//   trapezoidal (top half-width beta*a) a*sqrt((1 + beta^2)/6);
//   curvilinear trapezoid (semi-width a inexact by +-d) sqrt(a^2/3 + d^2/9);
//   normal from U and k: U/k; from U at coverage p: U/z_p, or U/t_p(nu) when nu is stated;
//   scaled and shifted t_nu(mu, s^2): u = s with nu degrees of freedom (as Type A, 4.2).
// Type A inputs (JCGM 100 4.2): mean, u = s/sqrt(n), nu = n - 1; or a session quantity
// summarised by a caller-supplied resolver (this module never loads sessions).
// A relative reliability R of u gives nu = 1/(2 R^2) (JCGM 100 G.4.2).
// The measurand is y = f(x) with f a muparser expression over the input names, or, without
// a model, y = sum_i c_i x_i with each c_i given as the input's `sensitivity`.
#pragma once

#include <cstdint>
#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "metro/core/status.hpp"
#include "metro/core/units.hpp"

namespace metro {

enum class Distribution {
  kNormal,       // N(x, u^2); sampled as t_nu(x, u^2) when nu is finite (JCGM 101 6.4.9.7).
  kRectangular,  // R(x - a, x + a).
  kTriangular,   // T(x - a, x + a).
  kArcsine,      // U(x - a, x + a), U-shaped.
  kTrapezoidal,  // Trap(x - a, x + a, beta).
  kCurvilinearTrapezoid,  // CTrap(x - a, x + a, d).
  kStudentT,              // Scaled and shifted t_nu(x, s^2).
  kTypeA,                 // From observations: t_{n-1}(mean, (s/sqrt(n))^2) (JCGM 101 6.4.9).
};

// "normal", "rectangular", "triangular", "arcsine", "trapezoidal", "ctrap", "t", "type_a".
const char* DistributionName(Distribution distribution);

// A Type A input that refers to a quantity of a logged session. `session` is resolved
// against the budget file's directory (empty when the budget names no file: the caller's
// own session is meant, e.g. `characterize SESSION --type-a --budget B.json`).
struct SessionQuantityRef {
  std::string session;
  int sensor = 1;
  std::string quantity;
};

// What a resolver returns for a session quantity: the mean, the standard uncertainty of
// the mean u (autocorrelation-aware if the resolver knows how), its degrees of freedom and
// the number of observations, plus a free-text note for the report.
struct TypeASummary {
  double mean = 0.0;
  double u = 0.0;
  double dof = 0.0;
  int64_t n = 0;
  std::string note;
  // The quantity's unit in metro/core/units.hpp syntax ("deg", "deg/s", "g_n", "degC"); ""
  // when the session does not say. ParseBudget converts mean and u to the input's unit.
  std::string unit;
};

using SessionQuantityResolver = std::function<Result<TypeASummary>(const SessionQuantityRef&)>;

struct BudgetInput {
  std::string name;
  Distribution distribution = Distribution::kNormal;
  double value = 0.0;  // Estimate x_i (centre of a symmetric distribution, mean for Type A).
  double u = 0.0;      // Standard uncertainty u(x_i), in the input's unit.
  double dof = std::numeric_limits<double>::infinity();  // nu_i; infinity when not stated.
  double half_width = 0.0;            // a, for rectangular/triangular/arcsine/trapezoidal/ctrap.
  double beta = 0.0;                  // Trapezoid: top half-width / bottom half-width, in [0, 1].
  double d = 0.0;                     // Curvilinear trapezoid: half-width of the uncertain limit.
  double scale = 0.0;                 // Student t scale s (also Type A: s/sqrt(n)).
  std::optional<double> sensitivity;  // c_i, only for budgets without a model.
  int64_t n = 0;                      // Type A: number of observations.
  std::optional<SessionQuantityRef> session;  // Type A from a session quantity.
  // Parsed by UDUNITS-2 (metro/core/units.hpp; docs/budget-format.md, "Units"). "" = not
  // stated. A session quantity's value and u are converted to it (unit_conversion).
  std::string unit;
  std::string note;  // How u was obtained (for the report).
  // A session quantity in another unit than `unit`: the conversion applied to its mean and u
  // (value_before/u_before in the session's unit).
  std::optional<UnitConversion> unit_conversion;
  double value_before_conversion = 0.0;
  double u_before_conversion = 0.0;
};

struct Correlation {
  std::string a;
  std::string b;
  double r = 0.0;  // Correlation coefficient r(x_a, x_b), |r| <= 1.
};

// How nu_eff is formed when inputs are correlated (JCGM 100 G.4.1 assumes independence).
enum class CorrelatedDofPolicy {
  // Default. Inputs linked by non-zero correlations form one group; the group's
  // contribution u_g^2 = sum_{i,j in g} c_i c_j u_i u_j r_ij enters Welch-Satterthwaite with
  // the smallest nu_i of the group. Reduces to G.4.1 without correlations; for an ensemble
  // of means from the same n observations (GUM H.2) it gives nu = n - 1.
  kGroup,
  // Welch-Satterthwaite on the individual |c_i| u_i, correlations ignored in the
  // denominator (what many spreadsheets do silently); stated in the report.
  kIgnore,
  // Refuse: an error when correlated inputs have finite degrees of freedom.
  kReject,
};
const char* CorrelatedDofPolicyName(CorrelatedDofPolicy policy);

struct GumOptions {
  double coverage = 0.95;     // p of the expanded uncertainty, in (0, 1).
  bool second_order = false;  // Add the JCGM 100 5.1.2 note second-order terms.
  bool truncate_dof = false;  // Round nu_eff down to an integer (JCGM 100 G.6.4).
  CorrelatedDofPolicy correlated_dof = CorrelatedDofPolicy::kGroup;
  // Central-difference step for c_i, as a fraction of u(x_i) (second-order terms use
  // steps of u(x_i) itself, the scale on which curvature matters).
  double step_fraction = 1e-3;
  bool IsValid(std::string* why) const;
};

struct McOptions {
  bool enabled = true;
  double coverage = 0.95;    // p of the coverage intervals, in (0, 1).
  int64_t trials = 1000000;  // M, for a fixed-size run.
  uint64_t seed = 1;
  bool adaptive = false;          // JCGM 101 7.9 with the robust stopping rule.
  int ndig = 2;                   // Significant digits of u(y) to stabilise (adaptive, clause 8).
  int64_t max_trials = 20000000;  // Cap for the adaptive run (memory: 8 bytes per trial).
  int threads = 0;                // 0: std::thread::hardware_concurrency(), at most 2.
  // Progress: called with the number of trials just simulated (in steps of about 2^16
  // per worker thread), from the worker threads, so it must be thread-safe. The counts add
  // up to the trials run (McResult::trials). Unset: no calls. Results never depend on it.
  std::function<void(int64_t trials)> on_trials_done;
  bool IsValid(std::string* why) const;
};

struct Budget {
  std::string file;  // Path the budget was read from ("" for a string).
  std::string measurand;
  std::string unit;
  std::string model;  // Empty: y = sum c_i x_i.
  // Where `model` is written in `file` (ParseBudget; 0 and "" for a budget built in code): the
  // line and column of its opening quote and the JSON string as written there (escapes not
  // decoded), so that an error in the model names the file:line:column of its byte.
  int64_t model_line = 0;
  int64_t model_column = 0;
  std::string model_json;
  std::string description;
  std::vector<BudgetInput> inputs;
  std::vector<Correlation> correlations;
  GumOptions gum;
  McOptions monte_carlo;
};

// Parses and validates a budget. `budget_path` is used in messages and to resolve
// relative session paths. Session quantities are summarised through `resolver`; without a
// resolver such an input is an error naming it. Errors name the input and the problem:
// unknown distribution or key, missing or contradictory parameter, negative or non-finite
// u, |r| > 1, a correlation matrix that is not positive definite, a model using an
// undefined name or evaluating to NaN at the estimates.
Result<Budget> ParseBudget(const std::string& json_text, const std::string& budget_path,
                           const SessionQuantityResolver& resolver = nullptr);
Result<Budget> LoadBudget(const std::string& path,
                          const SessionQuantityResolver& resolver = nullptr);

// The session files a budget's inputs name (`"session"`, resolved like ParseBudget does), read
// without loading them, so a command can refuse an output that would overwrite one before it
// does any work. A file that is not a budget names none (LoadBudget reports why).
std::vector<std::string> SessionsNamedInBudget(const std::string& budget_path);

// Checks the cross-input rules (names unique, correlations, model, units) on a Budget built
// in code. ParseBudget calls it.
Status ValidateBudget(const Budget& budget);

// What the unit check of a budget found (docs/budget-format.md, "Units"). Every stated unit
// is parsed (an unknown unit is an error). With a model and a unit stated anywhere, every input
// the model uses needs a unit, the model's terms must agree (the rules in the docs) and the
// model's unit must be the measurand's (the same unit; only a model with a constant factor is
// compared by dimension alone). Without a model each c_i is taken in (measurand unit)/(input
// unit), so nothing is compared.
struct BudgetUnits {
  bool checked = false;     // The model's units were compared.
  std::string model_unit;   // The unit f(x) has (UDUNITS-2 notation); "" when not checked.
  bool scale_known = true;  // False: a constant factor; the model was checked by dimension.
  std::string note;         // Why not checked, or how.
};
Result<BudgetUnits> CheckBudgetUnits(const Budget& budget);

}  // namespace metro
