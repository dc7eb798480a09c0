#include "metro/stats/settle.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "metro/stats/type_a.hpp"

namespace metro {

namespace {

// Least-squares fit of x_i - x_bar = c + A r^i, r = exp(-1 / tau), for one tau. The sums
// of r^i and r^2i are closed forms (expm1 keeps them accurate for r near 1).
struct ExpFit {
  double tau = 0.0;
  double amplitude = 0.0;
  double sum_e = 0.0;     // sum r^i
  double centred = 0.0;   // sum r^2i - (sum r^i)^2 / n: the regressor's centred sum of squares
  double reduction = -1;  // Drop of the residual sum of squares the term buys.
};

ExpFit FitForTau(const std::vector<double>& xc, double tau) {
  const size_t n = xc.size();
  const double dn = static_cast<double>(n);
  const double r = std::exp(-1.0 / tau);
  ExpFit f;
  f.tau = tau;
  f.sum_e = -std::expm1(-dn / tau) / -std::expm1(-1.0 / tau);
  const double sum_ee = -std::expm1(-2.0 * dn / tau) / -std::expm1(-2.0 / tau);
  f.centred = sum_ee - f.sum_e * f.sum_e / dn;
  double sxe = 0.0, e = 1.0;
  for (size_t i = 0; i < n && e > 1e-30; ++i, e *= r) sxe += xc[i] * e;
  if (!(f.centred > 0.0)) return f;
  f.amplitude = sxe / f.centred;
  f.reduction = sxe * sxe / f.centred;
  return f;
}

}  // namespace

bool SettleOptions::IsValid(std::string* why) const {
  auto fail = [&](const char* m) {
    if (why) *why = m;
    return false;
  };
  if (!(max_bias_fraction > 0.0 && max_bias_fraction <= 1.0)) {
    return fail("settle max_bias_fraction must be in (0, 1]");
  }
  if (!(min_t_ratio >= 0.0) || !std::isfinite(min_t_ratio)) {
    return fail("settle min_t_ratio must be a finite number >= 0");
  }
  if (!(max_cut_fraction > 0.0 && max_cut_fraction < 1.0)) {
    return fail("settle max_cut_fraction must be in (0, 1)");
  }
  return true;
}

SettleResult DetectSettleTransient(const double* values, size_t n, const SettleOptions& options) {
  SettleResult result;
  constexpr size_t kMinSamples = 20;
  if (n < kMinSamples) {
    result.note =
        fmt::format("{} observations: at least {} are needed to fit a transient", n, kMinSamples);
    return result;
  }
  const double dn = static_cast<double>(n);
  double mean = 0.0;
  for (size_t i = 0; i < n; ++i) mean += values[i];
  mean /= dn;
  std::vector<double> xc(n);
  double ss = 0.0;
  for (size_t i = 0; i < n; ++i) {
    xc[i] = values[i] - mean;
    ss += xc[i] * xc[i];
  }
  if (!(ss > 0.0) || !std::isfinite(ss)) {
    result.note = "constant (or non-finite) series: no transient to fit";
    return result;
  }

  // Grid in log tau (ratio 1.1) from half a sample to 2 n, then golden-section refinement
  // of log tau between the neighbours of the best grid point.
  constexpr double kRatio = 1.1;
  std::vector<ExpFit> grid;
  for (double tau = 0.5; tau <= 2.0 * dn; tau *= kRatio) grid.push_back(FitForTau(xc, tau));
  size_t best = 0;
  for (size_t k = 1; k < grid.size(); ++k) {
    if (grid[k].reduction > grid[best].reduction) best = k;
  }
  ExpFit fit = grid[best];
  {
    double lo = std::log(grid[best == 0 ? 0 : best - 1].tau);
    double hi = std::log(grid[std::min(best + 1, grid.size() - 1)].tau);
    const double g = 0.5 * (std::sqrt(5.0) - 1.0);
    double a = hi - g * (hi - lo), b = lo + g * (hi - lo);
    ExpFit fa = FitForTau(xc, std::exp(a)), fb = FitForTau(xc, std::exp(b));
    for (int it = 0; it < 30 && hi - lo > 1e-4; ++it) {
      if (fa.reduction > fb.reduction) {
        hi = b;
        b = a;
        fb = fa;
        a = hi - g * (hi - lo);
        fa = FitForTau(xc, std::exp(a));
      } else {
        lo = a;
        a = b;
        fa = fb;
        b = lo + g * (hi - lo);
        fb = FitForTau(xc, std::exp(b));
      }
    }
    for (const ExpFit* f : {&fa, &fb}) {
      if (f->reduction > fit.reduction) fit = *f;
    }
  }
  if (!(fit.reduction >= 0.0)) {
    result.note = "the transient model could not be fitted";
    return result;
  }

  // Residuals and their autocorrelation-aware u of the mean (Zhang 2006).
  const double r = std::exp(-1.0 / fit.tau);
  const double c = -fit.amplitude * fit.sum_e / dn;  // Centred intercept.
  std::vector<double> residual(n);
  {
    double e = 1.0;
    for (size_t i = 0; i < n; ++i, e *= r) residual[i] = xc[i] - c - fit.amplitude * e;
  }
  auto ta = EvaluateTypeA(residual.data(), n);
  if (!ta.ok() || !(ta.value().std > 0.0)) {
    result.note = "the residuals of the fit are constant: no noise to compare the transient with";
    return result;
  }
  const TypeAResult& res = ta.value();
  // Least-squares standard error of A with the residual variance (n - 3 parameters: m,
  // A, tau), inflated by the residuals' variance factor F = n / n_eff.
  const double s2 = std::max(0.0, ss - fit.reduction) / std::max(1.0, dn - 3.0);
  const double u_amplitude =
      std::sqrt(s2 / fit.centred * std::max(1.0, dn / std::max(1.0, res.n_eff)));
  result.fitted = true;
  result.tau_samples = fit.tau;
  result.amplitude = fit.amplitude;
  result.t_ratio = u_amplitude > 0.0 ? std::abs(fit.amplitude) / u_amplitude : 0.0;
  result.significant = result.t_ratio >= options.min_t_ratio;
  result.u_mean_residual = res.std_of_mean_autocorr;

  // |b(d)| / u(d) for a cut of d samples.
  const double one_minus_r = -std::expm1(-1.0 / fit.tau);
  auto bias_over_u = [&](size_t d) {
    const double kept = dn - static_cast<double>(d);
    const double tail = std::exp(-static_cast<double>(d) / fit.tau) * -std::expm1(-kept / fit.tau) /
                        one_minus_r;  // sum_{i >= d} r^i
    const double bias = std::abs(fit.amplitude) * tail / kept;
    const double u = result.u_mean_residual * std::sqrt(dn / kept);
    return u > 0.0 ? bias / u : std::numeric_limits<double>::infinity();
  };
  result.bias_over_u_uncut = bias_over_u(0);
  result.bias_over_u_kept = result.bias_over_u_uncut;
  if (!result.significant) return result;
  const size_t d_max = static_cast<size_t>(options.max_cut_fraction * dn);
  size_t d = 0;
  while (d < d_max && bias_over_u(d) > options.max_bias_fraction) ++d;
  result.samples = d;
  result.at_limit = d == d_max && bias_over_u(d) > options.max_bias_fraction;
  result.bias_over_u_kept = bias_over_u(d);
  return result;
}

SettleResult DetectSettleMser5(const double* values, size_t n) {
  constexpr size_t kBatch = 5;
  SettleResult result;
  const size_t m = n / kBatch;
  if (m < 2) return result;
  std::vector<double> batch(m);
  double grand = 0.0;
  for (size_t j = 0; j < m; ++j) {
    double s = 0.0;
    for (size_t i = 0; i < kBatch; ++i) s += values[j * kBatch + i];
    batch[j] = s / kBatch;
    grand += batch[j];
  }
  grand /= static_cast<double>(m);
  // Suffix sums of centred batch means: MSER(d) for every d in O(m).
  std::vector<double> sum(m + 1, 0.0), sum2(m + 1, 0.0);
  for (size_t j = m; j-- > 0;) {
    const double b = batch[j] - grand;
    sum[j] = sum[j + 1] + b;
    sum2[j] = sum2[j + 1] + b * b;
  }
  const size_t d_max = m / 2;
  double best = std::numeric_limits<double>::infinity();
  size_t best_d = 0;
  for (size_t d = 0; d <= d_max; ++d) {
    const double k = static_cast<double>(m - d);
    const double ss = sum2[d] - sum[d] * sum[d] / k;
    const double mser = ss / (k * k);
    if (mser < best) {
      best = mser;
      best_d = d;
    }
  }
  result.samples = best_d * kBatch;
  result.mser = best;
  result.at_limit = best_d == d_max;
  return result;
}

}  // namespace metro
