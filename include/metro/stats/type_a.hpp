// GUM Type A evaluation of a series of observations, with an autocorrelation-aware
// standard uncertainty of the mean.
//
// Classical (JCGM 100:2008 4.2), for observations q_1..q_n:
//   mean q_bar = (1/n) sum q_k                                     (4.2.1, eq. 3)
//   s^2(q_k) = 1/(n-1) sum (q_k - q_bar)^2                          (4.2.2, eq. 4)
//   s^2(q_bar) = s^2(q_k) / n,  dof = n - 1                         (4.2.3, eq. 5; 4.2.6)
// computed with the corrected two-pass algorithm (no naive sum of squares).
//
// Autocorrelated observations (Zhang, Metrologia 43 (2006) S276; JCGM 100 4.2.7 notes
// that s(q_bar) assumes independence):
//   rho_k = sum_{i=1}^{n-k} (q_i - q_bar)(q_{i+k} - q_bar) / sum_{i=1}^{n} (q_i - q_bar)^2
//   F = 1 + 2 sum_{k=1}^{n_c} (1 - k/n) rho_k
//   s^2(q_bar)_autocorr = F s^2(q_k) / n,   n_eff = n / F
// n_c is the last lag, scanning k = 1, 2, ... upward, whose |rho_k| lies outside the
// Bartlett band  t_{0.975}(n-1) sqrt((1 + 2 sum_{j<k} rho_j^2) / n)  (the first lag inside
// the band ends the scan; lag n_c itself is included), and at most n/4.
// rho_k is computed directly for the first lags and by FFT (FFTW) when the correlation
// extends further, so the cost is O(n log n) in the worst case.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "metro/core/status.hpp"

namespace metro {

struct TypeAOptions {
  // Two-sided confidence of the Bartlett band that decides the cut-off lag n_c.
  double band_confidence = 0.95;
  // Largest lag considered, as a fraction of n (Zhang: n/4).
  double max_lag_fraction = 0.25;
  // Compute n_eff and std_of_mean_autocorr.
  bool autocorrelation = true;

  bool IsValid(std::string* why) const;
};

struct TypeAResult {
  int64_t n = 0;
  double mean = 0.0;
  double variance = 0.0;          // s^2(q_k), n - 1 in the denominator.
  double std = 0.0;               // s(q_k).
  double variance_of_mean = 0.0;  // s^2(q_bar) = s^2 / n.
  double std_of_mean = 0.0;       // s(q_bar).
  int64_t dof = 0;                // n - 1.
  // Autocorrelation-aware (Zhang 2006); equal to the classical values when
  // autocorrelation is off or n < 4.
  double n_eff = 0.0;
  double std_of_mean_autocorr = 0.0;
  int64_t cutoff_lag = 0;        // n_c.
  double rho1 = 0.0;             // Lag-1 sample autocorrelation.
  double variance_factor = 1.0;  // F.
  // True when the lag scan reached max_lag_fraction * n without entering the band: the
  // series is dominated by drift and even n_eff is optimistic.
  bool cutoff_reached_limit = false;
};

// Evaluates n observations. Requires n >= 2 (one observation has no Type A evaluation)
// and finite values; returns an Error otherwise.
Result<TypeAResult> EvaluateTypeA(const double* values, size_t n, const TypeAOptions& options = {});

// Sample autocorrelation rho_0..rho_max_lag of x (rho_0 = 1), normalised by
// sum (x - mean)^2, via FFT. Exposed for tests and for the noise module.
void Autocorrelation(const double* x, size_t n, size_t max_lag, double* rho);

}  // namespace metro
