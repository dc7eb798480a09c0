// Start-up transient detection (`--settle auto`).
//
// Two rules live here.
//
// 1. DetectSettleTransient, the rule of `--settle auto` for Type A (docs/type-a.md,
//    "Windows and `--settle auto`"): a fitted exponential transient and a cut where what
//    remains of it biases the mean by at most a small fraction of u. The warm-up of an
//    IMU or a DMP filter is a first-order response, so the series is modelled as
//      x_i = m + A exp(-i / tau) + e_i,   i = 0 .. n-1 (samples)
//    with e_i stationary (possibly autocorrelated) noise. For each tau on a log grid
//    (1 sample .. 2 n) m and A follow by linear least squares; the tau of the smallest
//    residual sum of squares is refined by golden-section search. u_res, the
//    autocorrelation-aware standard uncertainty of the mean of the residuals (Zhang 2006,
//    stats/type_a.hpp), and the standard error of A (least squares, inflated by n / n_eff
//    of the residuals) follow. The transient is taken as real when |A| / u(A) >=
//    min_t_ratio (a significance test); then the cut is the smallest d with
//      |b(d)| <= max_bias_fraction * u(d),
//      b(d) = A / (n - d) * sum_{i >= d} exp(-i / tau)   (bias of the mean of x_d..x_{n-1})
//      u(d) = u_res * sqrt(n / (n - d))                 (u of the mean of n - d samples)
//    i.e. the remaining transient is negligible against the uncertainty of the mean in
//    the sense of JCGM 100:2008 3.4.4 / F.2.4.5 (a correction smaller than a small
//    fraction of u is left out). MSER-5 (below) minimises the standard error of the mean
//    instead, which keeps a transient as large as one batch mean's noise (White 1997;
//    Hoad, Robinson & Davies, J. Oper. Res. Soc. 61 (2010) 1389 report its
//    under-truncation of slow transients). d is at most max_cut_fraction * n; a cut that
//    would need more stops there with at_limit set.
//
// 2. DetectSettleMser5, the Marginal Standard Error Rule on batch means of 5 (White,
//    Simulation 69 (1997) 323; Franklin & White, WSC 2008), kept for the accuracy
//    plateaus. The series is cut into m batches of 5 and their means b_j. For each
//    candidate truncation d (batches), over the first half of the series,
//      MSER(d) = 1/(m - d)^2 * sum_{j > d} (b_j - mean_{j > d} b)^2
//    is the squared standard error of the mean of what remains; the truncation is the d
//    that minimises it. The result is in samples (5 d).
#pragma once

#include <cstddef>
#include <string>

namespace metro {

struct SettleResult {
  size_t samples = 0;     // Observations to drop from the start.
  double mser = 0.0;      // MSER at the chosen truncation (MSER-5 only).
  bool at_limit = false;  // The cut stopped at its limit (half the series): the series
                          // may not have settled (or drifts); inspect it.
  // DetectSettleTransient only (NaN / false when not fitted).
  bool fitted = false;           // A transient model was fitted (n large enough, not constant).
  bool significant = false;      // |A| / u(A) >= min_t_ratio: the transient is real.
  double tau_samples = 0.0;      // Fitted time constant [samples].
  double amplitude = 0.0;        // Fitted A, in the unit of the series, at i = 0.
  double t_ratio = 0.0;          // |A| / u(A).
  double u_mean_residual = 0.0;  // u_res, in the unit of the series.
  // Bias of the mean of what is kept, from the fitted transient, over u of that mean:
  // before the cut and after it.
  double bias_over_u_uncut = 0.0;
  double bias_over_u_kept = 0.0;
  std::string note;  // Why there is no fit, when !fitted ("" otherwise).
};

struct SettleOptions {
  double max_bias_fraction = 0.1;  // Cut until the remaining bias <= this x u.
  double min_t_ratio = 4.0;        // Significance of A needed for any cut.
  double max_cut_fraction = 0.5;   // Never cut more than this fraction of the series.

  bool IsValid(std::string* why) const;
};

// Requires n >= 20; with fewer (or a constant series) returns 0 samples, !fitted, a note.
SettleResult DetectSettleTransient(const double* values, size_t n,
                                   const SettleOptions& options = {});

// Requires n >= 10 (two batches); with fewer, returns 0 samples.
SettleResult DetectSettleMser5(const double* values, size_t n);

}  // namespace metro
