// IEEE Std 952-1997 Annex C noise terms from an Allan (or Hadamard) curve: a weighted least-
// squares fit of the model of noise_model.hpp, the classic slope read-offs, the Allan
// minimum, and the uncertainty of a mean predicted from the fitted model.
//
// Fit. The model is linear in c = [Q^2, N^2, B^2, K^2, R^2]. Every non-empty subset of the
// allowed terms is fitted to the variances s_i^2 by generalized least squares with the full
// covariance of the overlapping estimates (AllanVarianceCovariance: neighbouring taus share
// most of their data), iterated on the subset's own fitted model, plus relative_floor on the
// diagonal and the model error of the sampling (discretization_error); the start weights each
// point by its chi-squared variance 2 s^4 / edf. A subset is admissible when every coefficient
// is positive and at least min_significance times its standard uncertainty; among admissible
// subsets the one with the smallest chi2 + sum of its terms' penalties wins (a likelihood-ratio
// test of each term: it enters only when it lowers chi2 by more than its penalty; issue #36;
// before, BIC = chi2 + k ln(n)). u(c) = (A' Cov^-1 A)^-1, scaled by chi2 / (n - k) (Birge) only
// when chi2 exceeds its 95 % quantile; u of a term is u(c) / (2 sqrt(c)).
//
// Goodness of fit (issue #36): chi2 of the chosen model against chi-squared with n - k dof
// (model_check), the standardized residual of each fitted tau, and, when the model is
// rejected, the widest stretch of fitted taus where a refit is accepted; the terms are then
// those of that stretch. With dof 0 the model is not tested, and says so. Measured coverage over
// simulated records with known terms: docs/noise.md section 4. Non-overlapping curves (adev,
// hdev) keep the diagonal chi-squared weights. Points without an EDF get edf = 1. With
// thin_to_octave the fit uses points at least a factor 1.9 apart. Each term reports the tau
// range where it contributes at least 25 % of the fitted variance.
//
// Read-offs (IEEE 952 Annex C), only where the curve has the term's slope near the read-off
// tau: the line of the term's slope through the curve points within a factor 2.5 of
// Q: tau = sqrt(3) s, N: 1 s, K: 3 s, R: sqrt(2) s (edf-weighted mean in log space), given
// only when each of those points has a local slope (to the points a factor ~2 below and above)
// within 0.15 of the term's; B = sigma_min / 0.6643 (Allan) at an interior minimum whose
// slopes to the points a factor ~2 either side are both within 0.15 of 0. u from the points'
// confidence intervals (half-width / 1, as 68 % ~ 1 sigma).
//
// Mean uncertainty. For the mean of the rate over a duration T, the fitted deviation at
// tau = T, sigma_model(T), is the repeatability of successive T-averages. It equals the
// Type A s / sqrt(n) when the noise is white and keeps its meaning for flicker and random-
// walk rate noise, where the autocorrelation-corrected n_eff of a single record does not
// converge. It is an extrapolation when T lies outside the fitted tau range.
#pragma once

#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "metro/core/status.hpp"
#include "metro/noise/allan.hpp"
#include "metro/noise/noise_model.hpp"

namespace metro {

struct NoiseFitOptions {
  std::array<bool, kNoiseTermCount> allow = {true, true, true, true, true};
  double relative_floor = 0.0;    // Model error on the deviation (e.g. 0.01); >= 0.
  double min_significance = 2.0;  // c / u(c) for a term to count as supported; >= 0.
  double tau_min_s = 0.0;         // Fit only points with tau_min_s <= tau <= tau_max_s.
  double tau_max_s = 1e300;
  bool thin_to_octave = true;
  int iterations = 8;  // IRLS passes; >= 1.
  // Model error of the sampling (issue #36): the IEEE 952 factors are those of an integrating
  // sampler; a point-sampled flicker (Kasdin 1992) or random walk reads higher at the shortest
  // taus, by e (from the subset's own B and K). The model is taken at the midpoint of the two
  // discretizations (+e/2) with a systematic pattern of standard deviation e/2 in the
  // covariance, so no term rests on the model holding better than that (and a Q or N is not
  // invented to explain it) and neither kind of sampler biases a term.
  bool discretization_error = true;
  // A term enters only when it lowers chi2 by more than its penalty (indexed by NoiseTerm):
  // the chosen subset minimizes chi2 + sum of its terms' penalties. Defaults: the chi-squared
  // 1-dof quantiles 0.95 (3.841) for N, B, K and 0.99 (6.635) for Q and R, a likelihood-ratio
  // test of each term at 5 % (1 %). Each >= 0.
  std::array<double, kNoiseTermCount> term_penalty = {6.635, 3.841, 3.841, 3.841, 6.635};
  // Goodness of fit: the fitted model is rejected when P(chi2_dof >= chi2) < model_alpha.
  double model_alpha = 0.01;  // In (0, 1).
  // A point contradicts the model when |standardized residual| > contradiction_z.
  double contradiction_z = 2.576;  // > 0.
  // When the model is rejected over the whole range, fit the terms only in the widest
  // stretch of consecutive fitted taus (at least min_holding_points) where it is accepted.
  bool restrict_to_holding_range = true;
  int min_holding_points = 4;  // >= 2.

  bool IsValid(std::string* why) const;
};

struct NoiseTermEstimate {
  bool supported = false;  // Kept by the fit.
  double value = 0.0;      // Coefficient in base units (0 if not supported).
  double u = 0.0;          // Standard uncertainty, base units.
  double tau_min_s = 0.0;  // Where the term carries >= 25 % of the fitted variance.
  double tau_max_s = 0.0;
  double u_model = 0.0;  // The part of u from the model error (discretization, relative_floor):
                         // sqrt(u^2 - u_stat^2), u_stat from the covariance without it.
  // Selection statistic: for a kept term, chi2 of the chosen subset without it minus chi2 of
  // the chosen subset; for a term left out, chi2 of the chosen subset minus chi2 with it
  // added. NaN when that other subset has no fit. The term is in when it exceeds
  // penalty_chi2 (and every coefficient is positive and significant).
  double delta_chi2 = std::nan("");
  double penalty_chi2 = 0.0;
};

// Goodness of fit of the chosen model against the curve it was fitted to, with the covariance
// the GLS used (AllanVarianceCovariance of the fitted model plus the model error):
// chi2 = r' Cov^-1 r with r the residuals of the variances, against chi-squared with
// dof = points - terms (issue #36). The defaults read as "not tested".
struct NoiseModelCheck {
  bool tested = false;     // false: nothing below is a goodness of fit (see not_tested).
  std::string not_tested;  // Why the model could not be tested (dof 0, ...).
  double chi2 = std::nan("");
  int dof = 0;
  double p_value = std::nan("");  // P(chi2_dof >= chi2).
  double alpha = std::nan("");    // Rejected when p_value < alpha.
  bool rejected = false;
  std::vector<double> tau_s;  // The fitted taus and their standardized residuals
  std::vector<double> z;      // (s^2 - model) / sqrt(Cov_ii).
  double contradiction_z = std::nan("");
  std::vector<double> contradicting_taus_s;  // |z| > contradiction_z.
  // Where the model holds: the whole fitted range when it is not rejected, else the widest
  // stretch of fitted taus where a refit is accepted (then the terms are fitted there only),
  // NaN when there is none; with the test in that stretch.
  double holds_tau_min_s = std::nan("");
  double holds_tau_max_s = std::nan("");
  double holds_chi2 = std::nan("");
  int holds_dof = 0;
  double holds_p_value = std::nan("");

  bool holds() const { return tested && !rejected; }
  bool holds_somewhere() const { return std::isfinite(holds_tau_min_s); }
};

// Summary of the fit; the defaults read as failure.
struct NoiseFit {
  bool success = false;
  std::string message = "not fitted";
  AllanEstimator estimator = AllanEstimator::kOadev;
  std::array<NoiseTermEstimate, kNoiseTermCount> terms;  // Indexed by NoiseTerm.
  // Covariance of the squared coefficients c (zero rows/columns for unsupported terms).
  std::array<std::array<double, kNoiseTermCount>, kNoiseTermCount> covariance_c{};
  double chi2 = 0.0;
  int n_points = 0;          // Points used.
  int dof = 0;               // n_points - supported terms.
  double birge_ratio = 0.0;  // sqrt(chi2 / dof), 0 when dof = 0.
  double fit_tau_min_s = 0.0;
  double fit_tau_max_s = 0.0;
  // B and K (issue #36). Both kept: the correlation of their squared coefficients in the
  // fit. One kept while the subset with both has both coefficients positive but not both
  // significant: the record cannot separate them, and bk_joint holds that fit's B and K (u
  // from its covariance) with their correlation; the kept term alone is the chosen model.
  double bk_correlation = std::nan("");
  bool bk_joint = false;
  NoiseTermEstimate joint_b, joint_k;

  // The test over the whole fit range. When it rejects the model and a holding stretch was
  // found, terms, covariance_c, chi2 and fit_tau_* are those of the fit in that stretch.
  NoiseModelCheck model_check;

  const NoiseTermEstimate& term(NoiseTerm t) const { return terms[static_cast<int>(t)]; }
};

// Errors: invalid options, mdev curve, fewer than 2 usable points, no admissible subset.
Result<NoiseFit> FitNoiseTerms(const AllanCurve& curve,
                               const NoiseFitOptions& options = NoiseFitOptions());

// Covariance of the variance estimates dev_a^2, dev_b^2 of an overlapping curve (oadev, ohdev)
// whose noise has the given IEEE 952 coefficients [Q, N, B, K, R] (base units), for Gaussian
// noise (Isserlis), from the generalized autocovariance of each noise type (see the .cpp). The
// diagonal agrees with the Greenhall-Riley EDF: var(s^2) = 2 s^4 / edf. With missing samples
// the terms are taken as contiguous and the covariance scaled by the lost fraction (an
// approximation). Errors: adev, hdev, mdev.
Result<std::vector<std::vector<double>>> AllanVarianceCovariance(
    const AllanCurve& curve, const std::array<double, kNoiseTermCount>& coefficients);

// Fitted variance at tau (sum over supported terms); 0 for a failed fit.
double ModelVariance(const NoiseFit& fit, double tau_s);

struct ReadOff {
  bool found = false;
  double value = 0.0;  // Base units.
  double u = 0.0;
  double tau_read_s = 0.0;  // Where the line is read (1 s for N, ...).
  double tau_min_s = 0.0;   // Curve points used.
  double tau_max_s = 0.0;
};

// One read-off per term (indexed by NoiseTerm). Bias instability uses 0.6643 (Allan) or
// sqrt((4 ln2 - 1.5 ln3)/pi) = 0.5984 (Hadamard); mdev curves get nothing.
std::array<ReadOff, kNoiseTermCount> ReadOffNoiseTerms(const AllanCurve& curve);

struct AllanMinimum {
  bool found = false;
  double tau_s = 0.0;  // Where the deviation is smallest: averaging longer stops helping.
  double dev = 0.0;
  double ci_low = 0.0;
  double ci_high = 0.0;
  bool at_end = false;  // The minimum is the longest tau: averaging still helped there.
};
AllanMinimum FindAllanMinimum(const AllanCurve& curve);

struct MeanUncertaintyPrediction {
  double duration_s = 0.0;
  double u = 0.0;                               // sigma_model(T) [q].
  double u_of_u = 0.0;                          // Its standard uncertainty from the fit covariance.
  NoiseTerm dominant = NoiseTerm::kRandomWalk;  // Largest contribution at T.
  bool extrapolated = false;                    // T outside [fit_tau_min_s, fit_tau_max_s].
};

// Errors: failed fit, duration not finite or <= 0.
Result<MeanUncertaintyPrediction> PredictMeanUncertainty(const NoiseFit& fit, double duration_s);

}  // namespace metro
