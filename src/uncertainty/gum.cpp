#include "metro/uncertainty/gum.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <boost/math/distributions/normal.hpp>
#include <boost/math/distributions/students_t.hpp>
#include <cmath>
#include <map>
#include <numeric>
#include <optional>

#include "uncertainty/model.hpp"
#include "uncertainty/model_quote.hpp"
#include "uncertainty/symbolic_model.hpp"

// EvaluateGum runs these stages, in this order (the equations: gum.hpp):
//
//   estimate      BuildModel, InputEstimates     the model, x_i, u_i; y = f(x) in the driver
//   exact         ExactSensitivities             c_i from GiNaC, or why not (JCGM 100 5.1.3)
//   differences   DifferenceSensitivities        else c_i by central differences, the warning
//   combination   Combine                        r_ij, |c_i| u_i, u_c^2, correlated groups
//   second order  SecondOrderVariance            the JCGM 100 5.1.2 note terms, if asked
//   dof           WelchSatterthwaiteDenominator  nu_eff's denominator by the dof policy
//   expansion     Expand, BudgetLines            nu_eff, k, U, the interval; the budget table
//
// Each stage's errors are the messages for the user, at the budget's file.
namespace metro {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

Result<internal::MeasurementModel> BuildModel(const Budget& budget) {
  if (budget.model.empty()) {
    std::vector<double> c;
    for (const auto& in : budget.inputs) {
      if (!in.sensitivity) {
        return MakeError(budget.file, 0,
                         "input '" + in.name + "': missing 'sensitivity' (no model)");
      }
      c.push_back(*in.sensitivity);
    }
    return internal::MeasurementModel::Linear(std::move(c));
  }
  std::vector<std::string> names;
  for (const auto& in : budget.inputs) names.push_back(in.name);
  auto model = internal::MeasurementModel::FromExpression(budget.model, names);
  if (!model.ok()) return internal::ModelError(budget, model.error());
  return model;
}

// Finds the representative of i (union-find without ranks; budgets are small).
size_t Root(std::vector<size_t>* parent, size_t i) {
  while ((*parent)[i] != i) i = (*parent)[i] = (*parent)[(*parent)[i]];
  return i;
}

// ---- estimate -----------------------------------------------------------------------------

// The input estimates x_i and their standard uncertainties u_i, in the budget's order.
struct InputEstimates {
  std::vector<double> x;
  std::vector<double> u;
};

InputEstimates EstimatesOf(const Budget& budget) {
  const size_t n = budget.inputs.size();
  InputEstimates in{std::vector<double>(n), std::vector<double>(n)};
  for (size_t i = 0; i < n; ++i) {
    in.x[i] = budget.inputs[i].value;
    in.u[i] = budget.inputs[i].u;
  }
  return in;
}

// f at x with some coordinates displaced.
class DisplacedModel {
 public:
  DisplacedModel(const internal::MeasurementModel& model, const std::vector<double>& x)
      : model_(model), x_(x), work_(x) {}
  double operator()(std::initializer_list<std::pair<size_t, double>> shifts) {
    for (const auto& [i, dx] : shifts) work_[i] = x_[i] + dx;
    const double y = model_.Evaluate(work_.data());
    for (const auto& [i, dx] : shifts) work_[i] = x_[i];
    return y;
  }

 private:
  const internal::MeasurementModel& model_;
  const std::vector<double>& x_;
  std::vector<double> work_;
};

// ---- exact --------------------------------------------------------------------------------

// The model's exact derivatives (symbolic_model.hpp), when GiNaC takes the expression and
// gives the evaluator's value y at x: the two must read the expression alike. Returns the
// symbolic model with every c_i set, or nothing with *derivatives saying why not.
std::optional<internal::SymbolicModel> ExactSensitivities(const Budget& budget,
                                                          const std::vector<double>& x, double y,
                                                          std::vector<double>* c,
                                                          std::string* derivatives) {
  const size_t n = x.size();
  std::vector<std::string> names;
  for (const auto& in : budget.inputs) names.push_back(in.name);
  Result<internal::SymbolicModel> parsed =
      internal::SymbolicModel::Parse(budget.model, names, x.data());
  Result<double> value = parsed.ok() ? parsed.value().Value(x.data()) : parsed.error();
  // Sensitivity coefficients, JCGM 100 5.1.3, exact. Every coefficient is taken the same
  // way: one the symbolic form cannot give sends them all to differences (below).
  for (size_t i = 0; value.ok() && i < n; ++i) {
    Result<double> ci = parsed.value().First(i, x.data());
    if (ci.ok()) {
      (*c)[i] = ci.value();
    } else {
      value =
          MakeError("sensitivity to input '" + budget.inputs[i].name + "': " + ci.error().message);
    }
  }
  // The evaluator rounds each operation in double: where terms cancel (JCGM 101 9.3's
  // (mrc + dmrc)(...) - 100000 mg) its error is of the order of eps times the terms, sum_i
  // |c_i x_i|, not of the result. A misread expression (another precedence) differs by
  // far more.
  double scale = std::fabs(y);
  for (size_t i = 0; value.ok() && i < n; ++i) scale += std::fabs((*c)[i] * x[i]);
  if (value.ok() && !(std::fabs(value.value() - y) <= 1e-12 * std::max(scale, 1e-300))) {
    value =
        MakeError(fmt::format("GiNaC reads the model as {} at the estimates, the evaluator "
                              "as {}",
                              value.value(), y));
  }
  if (!value.ok()) {
    *derivatives = "central differences: " + value.error().message;
    return std::nullopt;
  }
  *derivatives = "exact (symbolic, GiNaC)";
  return std::move(parsed).value();
}

// ---- differences --------------------------------------------------------------------------

// The stated coefficients of a budget without a model, or, when the model has no exact
// derivatives (`symbolic` false), central differences (step scaled to u_i) with the warning
// that says so; with exact ones, *c is left as it is.
Status DifferenceSensitivities(const Budget& budget, const GumOptions& options,
                               const InputEstimates& in, bool symbolic, DisplacedModel* f_at,
                               std::vector<double>* c, GumResult* result) {
  const std::vector<double>& x = in.x;
  const std::vector<double>& u = in.u;
  std::string steps;  // The central-difference steps, input by input, for the warning.
  for (size_t i = 0; i < x.size(); ++i) {
    if (budget.model.empty()) {
      (*c)[i] = *budget.inputs[i].sensitivity;
      continue;
    }
    if (symbolic) continue;  // Taken by ExactSensitivities.
    const bool exact = u[i] == 0.0;
    const double h = exact ? 1e-6 * std::max(std::fabs(x[i]), 1e-6) : options.step_fraction * u[i];
    const double plus = (*f_at)({{i, h}});
    const double minus = (*f_at)({{i, -h}});
    (*c)[i] = (plus - minus) / (2.0 * h);
    if (!exact) {
      steps += fmt::format("{}'{}' h = {:.3g} (relative step h/|x| = {})",
                           steps.empty() ? "" : ", ", budget.inputs[i].name, h,
                           x[i] != 0.0 ? fmt::format("{:.3g}", h / std::fabs(x[i])) : "inf, x = 0");
    }
    if (!std::isfinite((*c)[i])) {
      if (exact) {
        (*c)[i] = 0.0;  // A constant: its coefficient multiplies u = 0 anyway.
        continue;
      }
      return MakeError(budget.file, 0,
                       "model is not finite at input '" + budget.inputs[i].name +
                           "' = " + std::to_string(x[i]) + " +- " + std::to_string(h) +
                           " (sensitivity by central differences)");
    }
  }
  if (!budget.model.empty() && !symbolic) {
    // Never silent (issue #36): rounding at a small relative step, or a step across a seam,
    // spoils a difference quotient, so the budget says so and states the Monte Carlo result.
    result->derivatives_exact = false;
    result->warnings.push_back(fmt::format(
        "model {} has no exact derivative at the estimates ({}): sensitivity coefficients by "
        "central differences with step_fraction {:g} of u: {}; the Monte Carlo result is the "
        "stated one (docs/uncertainty.md, \"Derivatives\")",
        internal::QuotedModel(budget),
        result->derivatives.substr(std::string("central differences: ").size()),
        options.step_fraction, steps.empty() ? "no input has u > 0" : steps));
  }
  return Status::Ok();
}

// ---- combination --------------------------------------------------------------------------

struct Combination {
  std::vector<std::vector<double>> r;  // Correlation matrix r_ij (JCGM 100 5.2.2).
  std::vector<double> contribution;    // u_i(y) = |c_i| u_i.
  double variance = 0.0;               // u_c^2, first order, >= 0.
  bool correlated = false;             // Some r_ij != 0 between contributing inputs.
  std::vector<size_t> parent;          // Union-find of the correlated groups (Root).
};

// Correlation matrix, JCGM 100 5.2.2, the combined variance and the correlated groups.
Result<Combination> Combine(const Budget& budget, const std::vector<double>& u,
                            const std::vector<double>& c) {
  const size_t n = u.size();
  std::vector<std::vector<double>> r(n, std::vector<double>(n, 0.0));
  for (size_t i = 0; i < n; ++i) r[i][i] = 1.0;
  std::map<std::string, size_t> index;
  for (size_t i = 0; i < n; ++i) index[budget.inputs[i].name] = i;
  for (const auto& corr : budget.correlations) {
    const size_t a = index.at(corr.a);
    const size_t b = index.at(corr.b);
    r[a][b] = r[b][a] = corr.r;
  }
  std::vector<double> contribution(n);
  for (size_t i = 0; i < n; ++i) contribution[i] = std::fabs(c[i]) * u[i];
  double variance = 0.0;
  for (size_t i = 0; i < n; ++i) {
    for (size_t j = 0; j < n; ++j) variance += c[i] * c[j] * u[i] * u[j] * r[i][j];
  }
  if (!std::isfinite(variance)) {
    // A c_i u_i of order 1e154 or more squares past the largest double: no u is reported
    // rather than an infinite or NaN one (issue #20).
    return MakeError(budget.file, 0,
                     "the combined variance sum c_i c_j u_i u_j r_ij overflows double precision "
                     "(a contribution |c_i| u_i of order 1e154 or more); express the measurand "
                     "and inputs in larger units");
  }
  if (variance < 0.0) variance = 0.0;  // Rounding only: R is positive definite.

  bool correlated = false;
  std::vector<size_t> parent(n);
  std::iota(parent.begin(), parent.end(), 0);
  for (size_t i = 0; i < n; ++i) {
    for (size_t j = i + 1; j < n; ++j) {
      if (r[i][j] != 0.0 && contribution[i] > 0.0 && contribution[j] > 0.0) {
        correlated = true;
        parent[Root(&parent, i)] = Root(&parent, j);
      }
    }
  }
  return Combination{std::move(r), std::move(contribution), variance, correlated,
                     std::move(parent)};
}

// ---- second order -------------------------------------------------------------------------

// u_c^2 with the JCGM 100 5.1.2 note terms: exact derivatives, else central differences with
// steps h_i = u_i (*symbolic is reset then, and the result says so).
Result<double> SecondOrderVariance(const Budget& budget, const InputEstimates& in,
                                   const std::vector<double>& c, const Combination& comb,
                                   std::optional<internal::SymbolicModel>* symbolic,
                                   DisplacedModel* f_at_model, GumResult* result) {
  if (comb.correlated) {
    return MakeError(budget.file, 0,
                     "second-order terms (JCGM 100 5.1.2 note) assume independent inputs; "
                     "the budget has correlated inputs");
  }
  const size_t n = in.x.size();
  const std::vector<double>& x = in.x;
  const std::vector<double>& u = in.u;
  const auto f_at = [&](std::initializer_list<std::pair<size_t, double>> shifts) {
    return (*f_at_model)(shifts);
  };
  const double f0 = result->value;
  std::string symbolic_error;
  const auto exact = [&](Result<double> d) {
    if (!d.ok() && symbolic_error.empty()) symbolic_error = d.error().message;
    return d.ok() ? d.value() : std::nan("");
  };
  const auto second_difference = [&](size_t i, size_t j) {
    const double hi = u[i];
    const double hj = u[j];
    if (i == j) return (f_at({{i, hi}}) - 2.0 * f0 + f_at({{i, -hi}})) / (hi * hi);
    return (f_at({{i, hi}, {j, hj}}) - f_at({{i, hi}, {j, -hj}}) - f_at({{i, -hi}, {j, hj}}) +
            f_at({{i, -hi}, {j, -hj}})) /
           (4.0 * hi * hj);
  };
  const auto second = [&](size_t i, size_t j) {
    return *symbolic ? exact((*symbolic)->Second(i, j, x.data())) : second_difference(i, j);
  };
  // d3f / (dxi dxj^2).
  const auto third_difference = [&](size_t i, size_t j) {
    const double hi = u[i];
    const double hj = u[j];
    if (i == j) {
      return (f_at({{i, 2.0 * hi}}) - 2.0 * f_at({{i, hi}}) + 2.0 * f_at({{i, -hi}}) -
              f_at({{i, -2.0 * hi}})) /
             (2.0 * hi * hi * hi);
    }
    const auto d2j = [&](double dxi) {
      return (f_at({{i, dxi}, {j, hj}}) - 2.0 * f_at({{i, dxi}}) + f_at({{i, dxi}, {j, -hj}})) /
             (hj * hj);
    };
    return (d2j(hi) - d2j(-hi)) / (2.0 * hi);
  };
  const auto third = [&](size_t i, size_t j) {
    return *symbolic ? exact((*symbolic)->Third(i, j, x.data())) : third_difference(i, j);
  };
  // sum_ij (f_ij^2 / 2 + f_i f_ijj) u_i^2 u_j^2 over the inputs with u > 0.
  const auto second_order_terms = [&] {
    double sum = 0.0;
    for (size_t i = 0; i < n; ++i) {
      if (u[i] == 0.0) continue;
      for (size_t j = 0; j < n; ++j) {
        if (u[j] == 0.0) continue;
        const double fij = second(i, j);
        const double fijj = third(i, j);
        sum += (0.5 * fij * fij + c[i] * fijj) * u[i] * u[i] * u[j] * u[j];
      }
    }
    return sum;
  };
  double extra = second_order_terms();
  if (!symbolic_error.empty()) {
    // The same terms by central differences (steps u_i), and the report says so.
    symbolic->reset();
    result->derivatives += "; second-order terms by central differences: " + symbolic_error;
    result->derivatives_exact = false;
    result->warnings.push_back(fmt::format(
        "model {}: second-order terms (JCGM 100 5.1.2 note) by central differences with "
        "steps h_i = u_i ({}); the Monte Carlo result is the stated one",
        internal::QuotedModel(budget), symbolic_error));
    extra = second_order_terms();
  }
  if (!std::isfinite(extra)) {
    return MakeError(budget.file, 0, "second-order terms are not finite (model NaN near x)");
  }
  return std::max(0.0, comb.variance + extra);
}

// ---- dof ----------------------------------------------------------------------------------

// sum_i u_i(y)^4 / nu_i over the contributing inputs with finite dof (JCGM 100 G.4.1).
double IndependentDenominator(const Budget& budget, const std::vector<double>& contribution) {
  double denominator = 0.0;
  for (size_t i = 0; i < contribution.size(); ++i) {
    if (contribution[i] > 0.0 && std::isfinite(budget.inputs[i].dof)) {
      denominator += std::pow(contribution[i], 4) / budget.inputs[i].dof;
    }
  }
  return denominator;
}

// The denominator of nu_eff, JCGM 100 G.4.1, with the stated policy for correlations, and
// *dof_note saying how it was formed.
Result<double> WelchSatterthwaiteDenominator(const Budget& budget, const GumOptions& options,
                                             const std::vector<double>& c,
                                             const std::vector<double>& u, const Combination& comb,
                                             std::string* dof_note) {
  const size_t n = u.size();
  const std::vector<std::vector<double>>& r = comb.r;
  const std::vector<double>& contribution = comb.contribution;
  if (!comb.correlated || options.correlated_dof == CorrelatedDofPolicy::kIgnore) {
    *dof_note = comb.correlated ? "Welch-Satterthwaite (JCGM 100 G.4.1) on the individual "
                                  "contributions; correlations ignored in nu_eff (policy "
                                  "'ignore')"
                                : "Welch-Satterthwaite (JCGM 100 G.4.1), independent inputs";
    return IndependentDenominator(budget, contribution);
  }
  if (options.correlated_dof == CorrelatedDofPolicy::kReject) {
    for (size_t i = 0; i < n; ++i) {
      for (size_t j = i + 1; j < n; ++j) {
        if (r[i][j] != 0.0 && contribution[i] > 0.0 && contribution[j] > 0.0 &&
            (std::isfinite(budget.inputs[i].dof) || std::isfinite(budget.inputs[j].dof))) {
          return MakeError(budget.file, 0,
                           "inputs '" + budget.inputs[i].name + "' and '" + budget.inputs[j].name +
                               "' are correlated and have finite degrees of freedom: "
                               "Welch-Satterthwaite does not apply (dof_policy 'reject')");
        }
      }
    }
    *dof_note =
        "Welch-Satterthwaite (JCGM 100 G.4.1); correlated inputs all have "
        "infinite dof (policy 'reject')";
    return IndependentDenominator(budget, contribution);
  }
  // kGroup: each group of linked inputs is one component with the smallest dof.
  std::vector<size_t> parent = comb.parent;
  std::map<size_t, std::pair<double, double>> groups;  // root -> (u_g^2, nu_g)
  for (size_t i = 0; i < n; ++i) {
    if (contribution[i] == 0.0) continue;
    auto& g = groups.try_emplace(Root(&parent, i), 0.0, kInf).first->second;
    g.second = std::min(g.second, budget.inputs[i].dof);
    for (size_t j = 0; j < n; ++j) {
      if (contribution[j] > 0.0 && Root(&parent, j) == Root(&parent, i)) {
        g.first += c[i] * c[j] * u[i] * u[j] * r[i][j];
      }
    }
  }
  double denominator = 0.0;
  for (const auto& [root, g] : groups) {
    (void)root;
    if (std::isfinite(g.second)) denominator += g.first * g.first / g.second;
  }
  *dof_note =
      "Welch-Satterthwaite (JCGM 100 G.4.1) with each group of correlated "
      "inputs as one component u_g^2 = sum c_i c_j u_i u_j r_ij at the "
      "group's smallest dof (policy 'group')";
  return denominator;
}

// ---- expansion ----------------------------------------------------------------------------

// nu_eff = u_c^4 / denominator (first-order u_c), k, U = k u and the interval.
void Expand(const GumOptions& options, double variance, double denominator, GumResult* result) {
  const double uc4 = variance * variance;
  result->dof_eff = (denominator > 0.0 && uc4 > 0.0) ? uc4 / denominator : kInf;
  if (options.truncate_dof && std::isfinite(result->dof_eff)) {
    result->dof_eff = std::max(1.0, std::floor(result->dof_eff));  // JCGM 100 G.6.4
  }
  result->k = CoverageFactor(options.coverage, result->dof_eff);
  result->expanded = result->k * result->u;
  result->interval_low = result->value - result->expanded;
  result->interval_high = result->value + result->expanded;
}

// The budget table, sorted by contribution, largest first.
std::vector<BudgetLine> BudgetLines(const Budget& budget, const std::vector<double>& c,
                                    const Combination& comb) {
  std::vector<BudgetLine> lines;
  for (size_t i = 0; i < c.size(); ++i) {
    const BudgetInput& in = budget.inputs[i];
    BudgetLine line;
    line.name = in.name;
    line.value = in.value;
    line.u = in.u;
    line.distribution = DistributionName(in.distribution);
    line.sensitivity = c[i];
    line.contribution = comb.contribution[i];
    line.dof = in.dof;
    line.percent = comb.variance > 0.0
                       ? 100.0 * comb.contribution[i] * comb.contribution[i] / comb.variance
                       : 0.0;
    lines.push_back(line);
  }
  std::stable_sort(lines.begin(), lines.end(), [](const BudgetLine& a, const BudgetLine& b) {
    return a.contribution > b.contribution;
  });
  return lines;
}

}  // namespace

double CoverageFactor(double coverage, double dof) {
  const double tail = 0.5 * (1.0 + coverage);
  if (!std::isfinite(dof)) return boost::math::quantile(boost::math::normal(), tail);
  return boost::math::quantile(boost::math::students_t(dof), tail);
}

Result<GumResult> EvaluateGum(const Budget& budget) { return EvaluateGum(budget, budget.gum); }

Result<GumResult> EvaluateGum(const Budget& budget, const GumOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) return MakeError(budget.file, 0, "GUM options: " + why);
  auto model_result = BuildModel(budget);
  if (!model_result.ok()) return model_result.error();
  const internal::MeasurementModel& model = model_result.value();
  const InputEstimates in = EstimatesOf(budget);
  GumResult result;
  result.coverage = options.coverage;
  result.second_order = options.second_order;
  result.dof_policy = options.correlated_dof;
  result.value = model.Evaluate(in.x.data());
  if (!std::isfinite(result.value)) {
    return MakeError(
        budget.file, 0,
        "model evaluates to " + std::to_string(result.value) + " at the input estimates");
  }
  DisplacedModel f_at(model, in.x);
  std::vector<double> c(in.x.size(), 0.0);
  std::optional<internal::SymbolicModel> symbolic;
  if (budget.model.empty()) {
    result.derivatives = "stated (no model)";
  } else {
    symbolic = ExactSensitivities(budget, in.x, result.value, &c, &result.derivatives);
  }
  const Status differences =
      DifferenceSensitivities(budget, options, in, symbolic.has_value(), &f_at, &c, &result);
  if (!differences.ok()) return differences.error();

  Result<Combination> combined = Combine(budget, in.u, c);
  if (!combined.ok()) return combined.error();
  const Combination& comb = combined.value();
  result.u_first_order = std::sqrt(comb.variance);
  result.correlated = comb.correlated;
  double total = comb.variance;
  if (options.second_order && !budget.model.empty()) {
    Result<double> second = SecondOrderVariance(budget, in, c, comb, &symbolic, &f_at, &result);
    if (!second.ok()) return second.error();
    total = second.value();
  }
  result.u = std::sqrt(total);

  Result<double> denominator =
      WelchSatterthwaiteDenominator(budget, options, c, in.u, comb, &result.dof_note);
  if (!denominator.ok()) return denominator.error();
  Expand(options, comb.variance, denominator.value(), &result);
  result.budget = BudgetLines(budget, c, comb);
  return result;
}

}  // namespace metro
