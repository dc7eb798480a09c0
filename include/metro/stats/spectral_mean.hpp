// Standard uncertainty of the mean of a stationary, autocorrelated series from the spectral
// density at frequency zero of a fitted autoregressive model (the "AR spectral" or
// "autoregressive variance" estimator of a long-run variance).
//
// Model (centred series d_t = x_t - x_bar, t = 0..n-1):
//   d_t = sum_{k=1}^{p} phi_k d_{t-k} + e_t,   e_t white with variance sigma_e^2.
// phi by Burg's method (Burg 1967; Brockwell & Davis, Introduction to Time Series and
// Forecasting, 2nd ed. (2002) 5.1.2): always a stationary model, less biased than
// Yule-Walker on short, strongly correlated series. The order p minimises AIC
//   AIC(p) = n ln sigma_e^2(p) + 2 p          (Akaike 1974; Shibata 1980),
// p <= p_max = min(floor(10 log10 n), floor(n / 10)) (the default order cap of R's ar()).
// The long-run variance and the uncertainty of the mean (Fishman, Management Science 18
// (1971) 21, the autoregressive method of simulation output analysis; the same estimator is
// CODA's spectrum0.ar, Plummer et al., R News 6 (2006) 7):
//   S(0) = sigma_e^2 / A(1)^2,  A(1) = 1 - sum phi_k  (2 pi times the spectral density at 0)
//   u^2(x_bar) = S(0) / n,
// with A(1) corrected for the small-sample bias of the fitted persistence,
//   A(1) = max(1 - sum phi_k - (1 + 3 sum phi_k) / n, (1 - sum phi_k) / 2)
// (the AR(1) bias of the estimate with the mean estimated, -(1 + 3 phi)/n: Marriott & Pope,
// Biometrika 41 (1954) 390; Kendall, Biometrika 41 (1954) 403; applied to the sum of an
// AR(p) as its persistence; coverage measured in docs/type-a.md).
// Degrees of freedom from the reliability of u (JCGM 100:2008 G.4.2, nu = 1 / (2 R^2)),
// with R^2 = Var(ln u) by the delta method on the asymptotic distribution of the estimates
// (Brockwell & Davis, Time Series: Theory and Methods, 2nd ed. (1991) Thm 8.1.1:
// phi_hat ~ N(phi, sigma_e^2 Gamma_p^-1 / n), independent of sigma_e_hat^2, whose relative
// variance is 2/n):
//   R^2 = 1/(2 n) + 1' sigma_e^2 Gamma_p^-1 1 / (n (1 - sum phi_k)^2),   nu <= n - 1
// (the fitted, uncorrected 1 - sum phi_k here: the spread of the estimate about itself),
// with sigma_e^2 Gamma_p^-1 from the Gohberg-Semencul formula (no matrix is inverted).
// For AR(1) this is R^2 = 1/(2 n) + (1 + phi) / (n (1 - phi)).
//
// Limits (docs/type-a.md): the model must describe the correlation within p_max lags; a
// drift or random walk (no finite S(0)) is fitted as sum phi_k -> 1 and gives a large,
// unreliable u, which the session report compares with the Allan deviation.
#pragma once

#include <cstddef>
#include <vector>

#include "metro/core/spill_file.hpp"
#include "metro/core/status.hpp"

namespace metro {

struct ArSpectralOptions {
  // Largest order tried; 0: min(floor(10 log10 n), floor(n / 10)).
  int max_order = 0;
  // How Burg's sums are formed (the same estimates either way, to rounding):
  // kLagProducts reads the record once for its lag products and forms each order's sums as
  // quadratic forms in O(p^2) (Vos 2013), falling back to the lattice when cancellation
  // would cost accuracy; kLattice runs the textbook error-series lattice, O(n) per order.
  enum class Method { kLagProducts, kLattice };
  Method method = Method::kLagProducts;
  // > 0: stop as soon as the AIC order's innovation variance is known to lie below this
  // value (in the squared unit of the series): with e_p the innovation variance at the order
  // p reached, AIC's choice p* has e_p* <= e_p exp(2 (p - p*) / n) <= e_p exp(2 p / n)
  // (Akaike 1974: n ln e_p* + 2 p* <= n ln e_p + 2 p). The result then holds that order and
  // e_p with `stopped_below` set; phi, u_mean and the rest are not computed. Type A uses it
  // to tell a deterministic pattern from noise without fitting every order.
  double stop_below_innovation_variance = 0.0;
};

struct ArSpectralResult {
  int order = 0;                     // p chosen by AIC.
  std::vector<double> phi;           // phi_1..phi_p.
  double innovation_variance = 0.0;  // sigma_e^2, in the squared unit of the series.
  double sum_phi = 0.0;              // sum phi_k as fitted.
  double a1 = 1.0;                   // A(1), bias-corrected.
  double long_run_variance = 0.0;    // S(0) = sigma_e^2 / A(1)^2.
  double u_mean = 0.0;               // sqrt(S(0) / n), unit of the series.
  double dof = 0.0;                  // nu = 1 / (2 R^2), at most n - 1.
  double relative_u_of_u = 0.0;      // R.
  int lattice_fallbacks = 0;         // 1 when kLagProducts handed over to the lattice.
  bool stopped_below = false;        // ArSpectralOptions::stop_below_innovation_variance.
};

// Requires n >= 4 finite values that are not all equal; returns an Error otherwise.
Result<ArSpectralResult> ArSpectralMeanUncertainty(const double* values, size_t n,
                                                   const ArSpectralOptions& options = {});

// The same estimate from a record read in chunks, three times, with memory independent of n.
// The sums are formed in the same blocks and lanes as ArSpectralMeanUncertainty's, so the
// result is the same to the last bit, except where that one hands over to the lattice (a
// strongly correlated series, see kLagProducts): the lattice needs the record in memory, and
// this returns an Error that says so. Only Method::kLagProducts.
Result<ArSpectralResult> ArSpectralMeanUncertaintyChunked(const ChunkReader& read, size_t n,
                                                          const ArSpectralOptions& options = {});

}  // namespace metro
