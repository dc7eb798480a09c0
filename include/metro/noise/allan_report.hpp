// The report forms of an Allan curve and its noise terms (docs/noise.md).
//
// AllanReport is the "allan" object of a session report's quantity (session_report.hpp; its
// JSON in src/noise/allan_report_json.hpp):
//   {"estimator": "oadev", "tau_s": [...], "adev": [...], "ci_low": [...], "ci_high": [...],
//    "edf": [...], "n_terms": [...], "n_terms_gap_free": [...], "missing_fraction": [...],
//    "confidence": 0.683, "alpha": [...], "alpha_source": ["lag1_acf", ...],
//    "noise": {"quantization": T, "random_walk": T, "bias_instability": T,
//              "rate_random_walk": T, "rate_ramp": T},
//    "sample_period": {...}, "gaps": {...}?, "fit_error": "..."?, "model_check": {...}?}
// or {"error": "...", "gaps": {...}?} for a quantity that could not be analysed. "adev" holds
// the chosen estimator's deviation in the quantity's unit. Each T is
//   {"value", "u", "unit", "value_conventional", "unit_conventional", "u_conventional",
//    "supported", "tau_min_s", "tau_max_s", "readoff": {"value", "u", "tau_s"} | null}
// with value/u null when the fit does not support the term; random_walk also carries
// "density_one_sided", "u_density_one_sided", "unit_density" (sqrt(2) N, the figure a
// datasheet quotes) and their conventional forms; then (issue #36) "model_rejected", "u_model"
// and "selection": {"delta_chi2", "penalty_chi2", "decision"}. NaN (no EDF) is written as null.
// "model_check": {"tested", "not_tested", "chi2", "dof", "p_value", "alpha", "rejected",
//   "tau_s", "z", "contradicting_taus_s", "tau_range_model_holds_s", "holds_chi2",
//   "holds_dof", "holds_p_value", "summary"} (AllanModelCheckReport);
// "b_k": {"joint", "correlation", "b", "u_b", "k", "u_k"}? (AllanBkReport).
//
// AllanTypeALink is what sits beside the n_eff Type A result ("allan_type_a_link"):
//   {"allan_min_tau_s", "allan_min_dev", "allan_min_at_end", "duration_s",
//    "u_mean_allan", "u_u_mean_allan", "dominant_term", "extrapolated", "noise_model"?}
//
// AllanCurveCsv: header "tau_s,m,n_terms,alpha,alpha_source,edf,adev_<tok>,ci_low_<tok>,
// ci_high_<tok>,missing_fraction" (tok from NoiseUnits::column_token, e.g. adev_dps), one row
// per tau, numbers with 10 significant digits, empty fields for NaN. missing_fraction is the
// fraction of the tau's terms left out for missing samples (0 without gaps).
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "metro/noise/allan.hpp"
#include "metro/noise/noise_fit.hpp"
#include "metro/noise/noise_model.hpp"

namespace metro {

// "readoff" of a noise term: the value read off the curve at the term's characteristic tau
// (IEEE Std 952-1997 Annex C), beside the fitted one.
struct AllanReadOffReport {
  double value = std::nan("");
  double u = std::nan("");
  double tau_s = std::nan("");
};

// The white rate noise as a one-sided density d = sqrt(2) N (sigma(1 s) = d / sqrt 2), the
// figure a datasheet quotes; random_walk only.
struct AllanDensityReport {
  double density_one_sided = std::nan("");
  double u_density_one_sided = std::nan("");
  std::string unit_density;
  double density_one_sided_conventional = std::nan("");
  std::string unit_density_conventional;
};

// Why a term is in the model or not ("allan.noise.<key>.selection"): delta_chi2 is the chi2
// increase when the kept term is removed (the decrease when a left-out term is added), against
// penalty_chi2; decision "in" or "out" (delta_chi2 <= penalty_chi2, or a coefficient that is
// negative or insignificant, or a term the estimator cannot see). NaN (null) where the other
// subset has no fit.
struct AllanTermSelectionReport {
  double delta_chi2 = std::nan("");
  double penalty_chi2 = std::nan("");
  std::string decision;
};

// One fitted IEEE 952 term ("allan.noise.<key>"). value, u and their conventional forms are
// NaN (null) when the fit does not support the term.
struct AllanNoiseTermReport {
  double value = std::nan("");
  double u = std::nan("");
  std::string unit;
  double value_conventional = std::nan("");
  std::string unit_conventional;
  double u_conventional = std::nan("");
  bool supported = false;
  double tau_min_s = std::nan("");
  double tau_max_s = std::nan("");
  std::optional<AllanReadOffReport> readoff;  // null: not found on the curve.
  std::optional<AllanDensityReport> density;  // random_walk only.
  // Added by issue #36 (absent in older reports):
  // The IEEE 952 model was rejected over the curve's fitted range (allan.model_check): the
  // term describes at most the stretch where the model holds (tau_range_model_holds_s).
  std::optional<bool> model_rejected;
  // The part of u from the model error (sampling discretization, relative floor); NaN (null)
  // when the term is not supported.
  std::optional<double> u_model;
  std::optional<AllanTermSelectionReport> selection;
};

// "allan.sample_period": the sample period tau0 the curve was computed with.
struct AllanSamplePeriodReport {
  double tau0_s = std::nan("");
  double rate_hz = std::nan("");
  double mean_dt_s = std::nan("");
  double jitter_rms_s = std::nan("");
  double max_abs_jitter_s = std::nan("");
  int64_t missing_samples = 0;
  std::vector<std::string> warnings;
};

// "allan.gaps" (docs/noise.md "Gaps"): what was missing and what --gaps did about it.
struct AllanGapsReport {
  std::string policy;  // "skip", "split", "refuse".
  int64_t grid_samples = 0;
  int64_t missing_samples = 0;
  double missing_fraction = 0.0;
  // --gaps split: the stretches and the one analysed.
  std::optional<int64_t> stretches;
  std::optional<int64_t> analysed_first_sample;
  std::optional<int64_t> analysed_samples;
};

// "allan.model_check" (issue #36): the goodness of fit of the IEEE 952 model against the curve
// with the covariance the fit used (NoiseModelCheck). chi2/dof/p_value are null when the model
// could not be tested (tested false, not_tested says why). tau_range_model_holds_s is
// [min, max] of the fitted taus where the model is accepted (the whole range, a stretch the
// terms were then fitted in, or null: nowhere); summary says it in a sentence.
struct AllanModelCheckReport {
  bool tested = false;
  std::optional<std::string> not_tested;
  double chi2 = std::nan("");
  std::optional<int64_t> dof;
  double p_value = std::nan("");
  double alpha = std::nan("");
  bool rejected = false;
  std::vector<double> tau_s;  // Fitted taus and their standardized residuals.
  std::vector<double> z;
  std::vector<double> contradicting_taus_s;
  std::optional<std::array<double, 2>> tau_range_model_holds_s;
  double holds_chi2 = std::nan("");
  std::optional<int64_t> holds_dof;
  double holds_p_value = std::nan("");
  std::string summary;
};

// "allan.b_k" (issue #36): B and K together. joint false: both are in the model and
// correlation is that of B^2 and K^2 in its fit; joint true: only one is in the model
// because the record cannot separate them, and b/u_b, k/u_k are the fit with both (base
// units), with their correlation.
struct AllanBkReport {
  bool joint = false;
  double correlation = std::nan("");
  double b = std::nan("");
  double u_b = std::nan("");
  double k = std::nan("");
  double u_k = std::nan("");
};

// The "allan" object of a quantity. Either the curve (error empty) or the error form
// {"error", "gaps"?} of a quantity that could not be analysed. Arrays are per tau; NaN is
// null (no EDF).
struct AllanReport {
  std::string error;  // Not empty: the quantity could not be analysed (only `gaps` is kept).
  std::string estimator;
  std::vector<double> tau_s;
  std::vector<double> adev;  // The estimator's deviation, in the quantity's unit.
  std::vector<double> ci_low;
  std::vector<double> ci_high;
  std::vector<double> edf;
  std::vector<int64_t> n_terms;
  std::vector<int64_t> n_terms_gap_free;
  std::vector<double> missing_fraction;
  double confidence = std::nan("");
  std::vector<int64_t> alpha;
  std::vector<std::string> alpha_source;
  std::array<AllanNoiseTermReport, kNoiseTermCount> noise;  // Indexed by NoiseTerm.
  AllanSamplePeriodReport sample_period;
  std::optional<AllanGapsReport> gaps;
  std::optional<std::string> fit_error;              // Why the terms could not be fitted.
  std::optional<AllanModelCheckReport> model_check;  // With a fit (issue #36).
  std::optional<AllanBkReport> b_k;                  // See AllanBkReport.

  bool ok() const { return error.empty(); }
  const AllanNoiseTermReport& term(NoiseTerm t) const { return noise[static_cast<size_t>(t)]; }
};

// "allan_type_a_link": what sits beside the Type A result. NaN is null.
struct AllanTypeALink {
  double allan_min_tau_s = std::nan("");
  double allan_min_dev = std::nan("");
  bool allan_min_at_end = false;
  double duration_s = std::nan("");
  double u_mean_allan = std::nan("");  // Predicted u of the window's mean.
  double u_u_mean_allan = std::nan("");
  std::optional<std::string> dominant_term;
  std::optional<bool> extrapolated;
  // Whether u_mean_allan may stand for u(mean) (issue #36): "holds" (the model passed its
  // goodness-of-fit test), "rejected", "untested"; absent without a fit or in older reports.
  std::optional<std::string> noise_model;
};

// "holds", "rejected" or "untested" for a fit's model check.
const char* NoiseModelStatus(const NoiseModelCheck& check);

// The curve and fit of one quantity as its report object; sample_period and gaps are left for
// the caller (they are not the curve's).
AllanReport MakeAllanReport(const AllanCurve& curve, const NoiseFit& fit,
                            const std::string& quantity_unit);

AllanTypeALink MakeAllanTypeALink(const AllanCurve& curve, const NoiseFit& fit, double duration_s);

// "allan.model_check" when no IEEE 952 model could be fitted to the curve at all (FitNoiseTerms
// failed with `why`): tested false, not_tested and summary say so, no tau range where the model
// holds (issue #36: a model that cannot be tested says so and states no goodness of fit).
AllanModelCheckReport UnfittedModelCheck(const AllanCurve& curve, const std::string& why);

// The report object of a curve as the session report makes it: the IEEE 952 terms fitted with
// `options` (FitNoiseTerms; *fit_out, when not null, receives the fit, empty when none), the
// fit's error and the unfitted model check when there is none. sample_period and gaps are left
// for the caller.
AllanReport AllanReportOfCurve(const AllanCurve& curve, const NoiseFitOptions& options,
                               const std::string& quantity_unit, NoiseFit* fit_out = nullptr);

// The "allan" object as JSON text, indented as the session report is (NaN as null).
std::string ToJson(const AllanReport& allan);

std::string AllanCurveCsv(const AllanCurve& curve, const std::string& quantity_unit);

// 1 - n_terms / n_terms_gap_free at each tau (0 where nothing is missing).
std::vector<double> MissingFractions(const AllanCurve& curve);

}  // namespace metro
