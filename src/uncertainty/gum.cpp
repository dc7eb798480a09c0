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
  const size_t n = budget.inputs.size();
  std::vector<double> x(n);
  std::vector<double> u(n);
  for (size_t i = 0; i < n; ++i) {
    x[i] = budget.inputs[i].value;
    u[i] = budget.inputs[i].u;
  }
  GumResult result;
  result.coverage = options.coverage;
  result.second_order = options.second_order;
  result.dof_policy = options.correlated_dof;
  result.value = model.Evaluate(x.data());
  if (!std::isfinite(result.value)) {
    return MakeError(
        budget.file, 0,
        "model evaluates to " + std::to_string(result.value) + " at the input estimates");
  }
  // f at x with some coordinates displaced.
  std::vector<double> work = x;
  const auto f_at = [&](std::initializer_list<std::pair<size_t, double>> shifts) {
    for (const auto& [i, dx] : shifts) work[i] = x[i] + dx;
    const double y = model.Evaluate(work.data());
    for (const auto& [i, dx] : shifts) work[i] = x[i];
    return y;
  };

  // The model's exact derivatives (symbolic_model.hpp), when GiNaC takes the expression and
  // gives the evaluator's value at x: the two must read the expression alike.
  std::optional<internal::SymbolicModel> symbolic;
  std::vector<double> c(n, 0.0);
  if (budget.model.empty()) {
    result.derivatives = "stated (no model)";
  } else {
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
        c[i] = ci.value();
      } else {
        value = MakeError("sensitivity to input '" + budget.inputs[i].name +
                          "': " + ci.error().message);
      }
    }
    // The evaluator rounds each operation in double: where terms cancel (JCGM 101 9.3's
    // (mrc + dmrc)(...) - 100000 mg) its error is of the order of eps times the terms, sum_i
    // |c_i x_i|, not of the result. A misread expression (another precedence) differs by
    // far more.
    double scale = std::fabs(result.value);
    for (size_t i = 0; value.ok() && i < n; ++i) scale += std::fabs(c[i] * x[i]);
    if (value.ok() &&
        !(std::fabs(value.value() - result.value) <= 1e-12 * std::max(scale, 1e-300))) {
      value =
          MakeError(fmt::format("GiNaC reads the model as {} at the estimates, the evaluator "
                                "as {}",
                                value.value(), result.value));
    }
    if (value.ok()) {
      symbolic = std::move(parsed).value();
      result.derivatives = "exact (symbolic, GiNaC)";
    } else {
      result.derivatives = "central differences: " + value.error().message;
    }
  }

  // Else central differences (step scaled to u_i).
  std::string steps;  // The central-difference steps, input by input, for the warning.
  for (size_t i = 0; i < n; ++i) {
    if (budget.model.empty()) {
      c[i] = *budget.inputs[i].sensitivity;
      continue;
    }
    if (symbolic) continue;  // Taken above.
    const bool exact = u[i] == 0.0;
    const double h = exact ? 1e-6 * std::max(std::fabs(x[i]), 1e-6) : options.step_fraction * u[i];
    const double plus = f_at({{i, h}});
    const double minus = f_at({{i, -h}});
    c[i] = (plus - minus) / (2.0 * h);
    if (!exact) {
      steps += fmt::format("{}'{}' h = {:.3g} (relative step h/|x| = {})",
                           steps.empty() ? "" : ", ", budget.inputs[i].name, h,
                           x[i] != 0.0 ? fmt::format("{:.3g}", h / std::fabs(x[i])) : "inf, x = 0");
    }
    if (!std::isfinite(c[i])) {
      if (exact) {
        c[i] = 0.0;  // A constant: its coefficient multiplies u = 0 anyway.
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
    result.derivatives_exact = false;
    result.warnings.push_back(fmt::format(
        "model {} has no exact derivative at the estimates ({}): sensitivity coefficients by "
        "central differences with step_fraction {:g} of u: {}; the Monte Carlo result is the "
        "stated one (docs/uncertainty.md, \"Derivatives\")",
        internal::QuotedModel(budget),
        result.derivatives.substr(std::string("central differences: ").size()),
        options.step_fraction, steps.empty() ? "no input has u > 0" : steps));
  }

  // Correlation matrix, JCGM 100 5.2.2.
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
  result.u_first_order = std::sqrt(variance);

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
  result.correlated = correlated;

  double total = variance;
  if (options.second_order && !budget.model.empty()) {
    if (correlated) {
      return MakeError(budget.file, 0,
                       "second-order terms (JCGM 100 5.1.2 note) assume independent inputs; "
                       "the budget has correlated inputs");
    }
    // JCGM 100 5.1.2 note: exact derivatives, else central differences with steps h_i = u_i.
    const double f0 = result.value;
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
      return symbolic ? exact(symbolic->Second(i, j, x.data())) : second_difference(i, j);
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
      return symbolic ? exact(symbolic->Third(i, j, x.data())) : third_difference(i, j);
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
      symbolic.reset();
      result.derivatives += "; second-order terms by central differences: " + symbolic_error;
      result.derivatives_exact = false;
      result.warnings.push_back(fmt::format(
          "model {}: second-order terms (JCGM 100 5.1.2 note) by central differences with "
          "steps h_i = u_i ({}); the Monte Carlo result is the stated one",
          internal::QuotedModel(budget), symbolic_error));
      extra = second_order_terms();
    }
    if (!std::isfinite(extra)) {
      return MakeError(budget.file, 0, "second-order terms are not finite (model NaN near x)");
    }
    total = std::max(0.0, variance + extra);
  }
  result.u = std::sqrt(total);

  // Effective degrees of freedom, JCGM 100 G.4.1, with the stated policy for correlations.
  double denominator = 0.0;
  if (!correlated || options.correlated_dof == CorrelatedDofPolicy::kIgnore) {
    for (size_t i = 0; i < n; ++i) {
      if (contribution[i] > 0.0 && std::isfinite(budget.inputs[i].dof)) {
        denominator += std::pow(contribution[i], 4) / budget.inputs[i].dof;
      }
    }
    result.dof_note = correlated ? "Welch-Satterthwaite (JCGM 100 G.4.1) on the individual "
                                   "contributions; correlations ignored in nu_eff (policy "
                                   "'ignore')"
                                 : "Welch-Satterthwaite (JCGM 100 G.4.1), independent inputs";
  } else if (options.correlated_dof == CorrelatedDofPolicy::kReject) {
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
    for (size_t i = 0; i < n; ++i) {
      if (contribution[i] > 0.0 && std::isfinite(budget.inputs[i].dof)) {
        denominator += std::pow(contribution[i], 4) / budget.inputs[i].dof;
      }
    }
    result.dof_note =
        "Welch-Satterthwaite (JCGM 100 G.4.1); correlated inputs all have "
        "infinite dof (policy 'reject')";
  } else {
    // kGroup: each group of linked inputs is one component with the smallest dof.
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
    for (const auto& [root, g] : groups) {
      (void)root;
      if (std::isfinite(g.second)) denominator += g.first * g.first / g.second;
    }
    result.dof_note =
        "Welch-Satterthwaite (JCGM 100 G.4.1) with each group of correlated "
        "inputs as one component u_g^2 = sum c_i c_j u_i u_j r_ij at the "
        "group's smallest dof (policy 'group')";
  }
  const double uc4 = variance * variance;
  result.dof_eff = (denominator > 0.0 && uc4 > 0.0) ? uc4 / denominator : kInf;
  if (options.truncate_dof && std::isfinite(result.dof_eff)) {
    result.dof_eff = std::max(1.0, std::floor(result.dof_eff));  // JCGM 100 G.6.4
  }
  result.k = CoverageFactor(options.coverage, result.dof_eff);
  result.expanded = result.k * result.u;
  result.interval_low = result.value - result.expanded;
  result.interval_high = result.value + result.expanded;

  for (size_t i = 0; i < n; ++i) {
    const BudgetInput& in = budget.inputs[i];
    BudgetLine line;
    line.name = in.name;
    line.value = in.value;
    line.u = in.u;
    line.distribution = DistributionName(in.distribution);
    line.sensitivity = c[i];
    line.contribution = contribution[i];
    line.dof = in.dof;
    line.percent = variance > 0.0 ? 100.0 * contribution[i] * contribution[i] / variance : 0.0;
    result.budget.push_back(line);
  }
  std::stable_sort(
      result.budget.begin(), result.budget.end(),
      [](const BudgetLine& a, const BudgetLine& b) { return a.contribution > b.contribution; });
  return result;
}

}  // namespace metro
