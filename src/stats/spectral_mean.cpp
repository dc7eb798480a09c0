#include "metro/stats/spectral_mean.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace metro {
namespace {

// Order cap: min(floor(10 log10 n), floor(n / 10)), at least 1.
int DefaultMaxOrder(size_t n) {
  const int by_log = static_cast<int>(std::floor(10.0 * std::log10(static_cast<double>(n))));
  const int by_length = static_cast<int>(n / 10);
  return std::max(1, std::min(by_log, by_length));
}

// 1' sigma_e^2 Gamma_p^-1 1 of the AR(p) model phi, by the Gohberg-Semencul formula
// sigma_e^2 Gamma_p^-1 = A A' - B B', A and B lower-triangular Toeplitz with first columns
// (1, -phi_1, ..., -phi_{p-1}) and (phi_p, phi_{p-1}, ..., phi_1):
//   1' A A' 1 = sum_j (sum_{m=0}^{p-1-j} a_m)^2,  1' B B' 1 = sum_j (sum_{m=0}^{p-1-j} b_m)^2.
double GohbergSemencul11(const std::vector<double>& phi) {
  const size_t p = phi.size();
  double a_sum = 0.0, b_sum = 0.0, aa = 0.0, bb = 0.0;
  // Partial sums over m = 0..p-1-j for j = p-1 down to 0 (m grows as j falls).
  for (size_t m = 0; m < p; ++m) {
    a_sum += m == 0 ? 1.0 : -phi[m - 1];
    b_sum += phi[p - 1 - m];
    aa += a_sum * a_sum;
    bb += b_sum * b_sum;
  }
  return aa - bb;
}

}  // namespace

Result<ArSpectralResult> ArSpectralMeanUncertainty(const double* values, size_t n,
                                                   const ArSpectralOptions& options) {
  if (n < 4) {
    return MakeError(fmt::format("{} observations: an autoregressive fit needs at least 4", n));
  }
  const double dn = static_cast<double>(n);
  double mean = 0.0;
  for (size_t i = 0; i < n; ++i) mean += values[i];
  mean /= dn;
  std::vector<double> f(n), b(n);
  double e0 = 0.0;
  for (size_t i = 0; i < n; ++i) {
    f[i] = values[i] - mean;
    e0 += f[i] * f[i];
  }
  if (!std::isfinite(e0)) return MakeError("the series is not finite");
  if (e0 == 0.0) return MakeError("a constant series has no autocorrelation");
  b = f;
  const int max_order = std::min(options.max_order > 0 ? options.max_order : DefaultMaxOrder(n),
                                 static_cast<int>(n) - 2);
  // Burg's recursion: f and b hold the forward and backward prediction errors of the
  // current order (b[t] is the backward error of x_{t-p} from x_{t-p+1..t}).
  std::vector<double> phi, next;
  double e = e0 / dn;
  double best_aic = dn * std::log(e);
  ArSpectralResult best;
  best.innovation_variance = e;
  for (int p = 1; p <= max_order; ++p) {
    double num = 0.0, den = 0.0;
    for (size_t t = static_cast<size_t>(p); t < n; ++t) {
      num += f[t] * b[t - 1];
      den += f[t] * f[t] + b[t - 1] * b[t - 1];
    }
    if (!(den > 0.0)) break;
    const double k = 2.0 * num / den;  // |k| <= 1 (Cauchy-Schwarz): a stationary model.
    // Levinson update: phi_p,j = phi_{p-1},j - k phi_{p-1},p-j; phi_p,p = k.
    next.assign(static_cast<size_t>(p), 0.0);
    for (int j = 1; j < p; ++j) {
      next[static_cast<size_t>(j - 1)] =
          phi[static_cast<size_t>(j - 1)] - k * phi[static_cast<size_t>(p - j - 1)];
    }
    next[static_cast<size_t>(p - 1)] = k;
    phi.swap(next);
    for (size_t t = n - 1; t >= static_cast<size_t>(p); --t) {
      const double ft = f[t];
      f[t] = ft - k * b[t - 1];
      b[t] = b[t - 1] - k * ft;
    }
    e *= 1.0 - k * k;
    if (!(e > 0.0)) break;
    const double aic = dn * std::log(e) + 2.0 * p;  // Akaike 1974
    if (aic < best_aic) {
      best_aic = aic;
      best.order = p;
      best.phi = phi;
      best.innovation_variance = e;
    }
  }
  double sum_phi = 0.0;
  for (double v : best.phi) sum_phi += v;
  // A(1) = 1 - sum phi > 0 for a stationary model (no root of A(z) in |z| <= 1).
  const double a1_fitted = std::max(1.0 - sum_phi, 1e-12);
  // The fitted persistence sum phi is biased low by about (1 + 3 phi) / n (AR(1) with the
  // mean estimated: Marriott & Pope, Biometrika 41 (1954) 390; Kendall, Biometrika 41
  // (1954) 403), which makes u too small by ~15 % at phi = 0.9, n = 200. The correction is
  // applied to the sum, and at most halves A(1).
  const double a1 = std::max(a1_fitted - (1.0 + 3.0 * sum_phi) / dn, 0.5 * a1_fitted);
  best.sum_phi = sum_phi;
  best.a1 = a1;
  best.long_run_variance = best.innovation_variance / (a1 * a1);
  best.u_mean = std::sqrt(best.long_run_variance / dn);
  const double q = best.order > 0 ? GohbergSemencul11(best.phi) : 0.0;
  // Delta method on the fitted estimates (their own spread, about the fitted A(1)).
  const double r2 = 0.5 / dn + std::max(q, 0.0) / (dn * a1_fitted * a1_fitted);
  best.relative_u_of_u = std::sqrt(r2);
  best.dof = std::min(0.5 / r2, dn - 1.0);  // JCGM 100:2008 G.4.2
  if (!std::isfinite(best.u_mean)) {
    return MakeError("the autoregressive long-run variance overflows double precision");
  }
  return best;
}

}  // namespace metro
