// The stages of the accuracy evaluation (EvaluateAccuracy, accuracy.hpp), each usable and
// testable on its own; method and formulas in docs/accuracy.md.
//
//   plateaus       FindPlateaus (plateaus.hpp) on the unwrapped reference, settling by the
//                  tag's modelled lag (ResponseTransient) as well as settle_s
//   errors         PlateauErrors: e_i, and u_i from the pooled AR(1) noise (PlateauNoiseOf)
//   fit            FitErrorCurve: the weighted curve, with a hysteresis term when measured
//   linearity      LinearityOf
//   hysteresis     HysteresisOf
//   repeatability  RepeatabilityOf
//   cross-axis     CrossAxisOf
//   budgets        ReadingBudgets: corrected and uncorrected single-reading U
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "metro/accuracy/accuracy.hpp"

namespace metro {

// Var(mean of n observations of a stationary AR(1) series) / sigma^2
//   = (1/n^2) [n + 2 sum_{k=1}^{n-1} (n - k) phi^k]     (e.g. Box & Jenkins, Zwiers & von
// Storch 1995 eq. 4); 1/n for phi = 0.
double Ar1MeanVarianceFactor(size_t n, double phi);

// The tag's reading noise on the plateaus as one stationary AR(1) process (lag-1 correlation
// phi per observation, standard deviation sigma), fitted to all plateaus at once by restricted
// maximum likelihood (REML) with one unknown mean per plateau, which accounts exactly for the
// removed means (a short plateau's own r1 is biased low by about (1 + 4 phi)/n). u of plateau
// i's mean = sigma sqrt(F(n_i, phi)) (Ar1MeanVarianceFactor); dof = 2 / var(ln u^2) at the
// median plateau length (JCGM 100 G.4.2), with var(ln u^2) from the innovations' sum (n_i - 1)
// dof and phi's variance from the curvature of the profile likelihood. Each plateau's slice is
// unwrapped before use.
PlateauNoise PlateauNoiseOf(const std::vector<double>& series_deg,
                            const std::vector<Plateau>& plateaus);

// The tag's modelled lag behind the reference at each observation: L_tau[r](t) - r(t)
// (FirstOrderLag, alignment.hpp); 0 everywhere for tau = 0, NaN where r is unknown.
std::vector<double> ResponseTransient(const std::vector<double>& t_s,
                                      const std::vector<double>& reference_deg, double tau_s);

// errors: one point per plateau of the error series e_k = WrapDeg180(tag_k - r_k) (JCGM 100
// 4.2.1 mean, 4.2.3 with the AR(1) u above, floored at q / sqrt(12 n), F.2.2.1), with the
// direction of travel and the sweep (direction from the plateaus' unwrapped reference).
std::vector<AccuracyPoint> PlateauErrors(const std::vector<double>& error_deg,
                                         const Segmentation& segmentation,
                                         const PlateauNoise& noise, double resolution_deg);

SystematicError SystematicErrorOf(const std::vector<AccuracyPoint>& points);

struct ErrorCurve {
  ErrorModel model = ErrorModel::kLinear;
  HarmonicFit fit;
  bool hysteresis_term = false;       // h d / 2 fitted (an angle visited both ways).
  double max_prediction_u_deg = 0.0;  // max over the points of u_fit(theta_i) (d = 0).
};
// fit: the model by the order rule (error_fit.hpp), weights 1/u_i^2, plus the hysteresis
// term when some angle was reached both turning up and turning down. Errors: the order rule.
Result<ErrorCurve> FitErrorCurve(const std::vector<AccuracyPoint>& points, ErrorModel model,
                                 double angle_match_deg);

Linearity LinearityOf(const std::vector<AccuracyPoint>& points, double angle_match_deg);
Hysteresis HysteresisOf(const std::vector<AccuracyPoint>& points, double angle_match_deg);
Repeatability RepeatabilityOf(const std::vector<AccuracyPoint>& points, double angle_match_deg);

// cross-axis: the plateau means of one axis not turned (mean_deg per point) with their u.
CrossAxis CrossAxisOf(const std::string& quantity, const std::vector<AccuracyPoint>& points,
                      const std::vector<double>& mean_deg, const std::vector<double>& u_deg,
                      double angle_match_deg);

// budgets: fills result->corrected, uncorrected, random_expanded_deg,
// uncorrected_max_abs_expanded_deg and the notes from the stages above.
Status ReadingBudgets(const AccuracyOptions& options, AccuracyResult* result);

// The expanded uncertainty of an uncorrected reading over the range: the U with
//   (1/m) sum_i P(|e_i + N(0, s_i^2)| <= U) = p,  s_i^2 = u_random^2 + u_i^2
// the distribution of the uncorrected error over the covered range (the plateau errors as
// the systematic part, each with the random part), evaluated exactly (JCGM 101 5.1 in
// spirit: the distribution, not a coverage factor times u, where the systematic part is far
// from normal).
double UncorrectedMixtureU(const std::vector<AccuracyPoint>& points, double u_random_deg,
                           double coverage);

}  // namespace metro
