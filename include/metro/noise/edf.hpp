// Equivalent degrees of freedom (EDF) and chi-squared confidence intervals of Allan-family
// variances.
//
// GreenhallRileyEdf: C. A. Greenhall and W. J. Riley, "Uncertainty of stability variances
// based on finite differences", Proc. 35th PTTI (2003); NIST SP 1065 5.4.1. It covers the
// overlapping and non-overlapping, modified and unmodified Allan (d = 2) and Hadamard
// (d = 3) variances for power-law noise S_y(f) ~ f^alpha, -4 <= alpha <= 2, alpha + 2d > 1.
// Parameters follow the paper: N phase points, averaging factor m, filter factor F (1 for a
// modified variance, m otherwise), stride S (m overlapping, 1 non-overlapping),
//   L = m/F + m d,  M = 1 + floor(S (N - L) / m),  J = min(M, (d+1) S),  r = M / S,
// and the sum
//   BasicSum(J, M, S, F) = sz(0)^2 + (1 - J/M) sz(J/S)^2 + 2 sum_{j=1}^{J-1} (1 - j/M) sz(j/S)^2
// of the generalized autocovariance sz of the d-th differences. With J_max = 100 the four
// cases of the paper (modified; unmodified alpha <= 0; alpha = 1; alpha = 2) use the sum when
// J <= J_max and the asymptotic forms of its Tables 1-3 otherwise, as Stable32 does. For
// alpha = 2 with ceil(r) <= d the sum is evaluated exactly (J = M there, no truncation).
//
// SimpleOadevEdf: the closed forms for the overlapping Allan variance (Howe, Allan & Barnes
// 1981; NIST TN 1337 Table 12-4; SP 1065 Table 5), kept as an independent check.
//
// DeviationInterval (SP 1065 5.3.2): for a deviation s with EDF nu and two-sided level p,
//   [s sqrt(nu / chi2_{(1+p)/2}(nu)),  s sqrt(nu / chi2_{(1-p)/2}(nu))]
// with Boost.Math chi-squared quantiles (nu may be fractional).
#pragma once

#include <cstdint>

#include "metro/core/status.hpp"

namespace metro {

// Errors: alpha out of [-4, 2], d not in {1, 2, 3}, alpha + 2d <= 1, m < 1, or N < L (the
// estimator has no term).
Result<double> GreenhallRileyEdf(int alpha, int d, int64_t m, int64_t n_phase, bool overlapping,
                                 bool modified);

// Errors: alpha not in {-2, ..., 2}, or fewer than 2m + 1 phase points (and N > 3 for the
// random-walk form).
Result<double> SimpleOadevEdf(int alpha, int64_t m, int64_t n_phase);

struct DeviationInterval {
  double low = 0.0;
  double high = 0.0;
};

// Errors: edf <= 0 or not finite, confidence outside (0, 1), deviation < 0.
Result<DeviationInterval> ChiSquaredInterval(double deviation, double edf, double confidence);

}  // namespace metro
