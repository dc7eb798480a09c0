#include "metro/noise/allan_report.hpp"

#include <fmt/format.h>

#include <cmath>

#include "metro/noise/noise_units.hpp"

namespace metro {
namespace {

std::string CsvNumber(double v) { return std::isfinite(v) ? fmt::format("{:.10g}", v) : ""; }

std::string TauList(const std::vector<double>& taus) {
  std::string out;
  for (double t : taus) out += (out.empty() ? "" : ", ") + fmt::format("{:.3g}", t);
  return out;
}

// The model check in a sentence (report and stderr).
std::string ModelCheckSummary(const NoiseModelCheck& c, double fit_tau_min_s,
                              double fit_tau_max_s) {
  const double lo = c.tau_s.empty() ? fit_tau_min_s : c.tau_s.front();
  const double hi = c.tau_s.empty() ? fit_tau_max_s : c.tau_s.back();
  if (!c.tested) {
    return fmt::format(
        "the IEEE 952 noise model was not tested against the curve ({}): no goodness of fit "
        "is stated, and u(mean) is not taken from the model",
        c.not_tested);
  }
  const std::string stat =
      fmt::format("chi2 = {:.4g} at {} dof, p = {:.2g}", c.chi2, c.dof, c.p_value);
  if (!c.rejected) {
    return fmt::format("the IEEE 952 noise model holds over tau {:.3g}-{:.3g} s ({})", lo, hi,
                       stat);
  }
  std::string out = fmt::format(
      "the IEEE 952 noise model is rejected by the Allan curve over tau {:.3g}-{:.3g} s ({}, "
      "below the {:.2g} level)",
      lo, hi, stat, c.alpha);
  if (!c.contradicting_taus_s.empty()) {
    out += fmt::format(
        "; the points at tau {} s lie more than {:.3g} of their standard "
        "deviations from it",
        TauList(c.contradicting_taus_s), c.contradiction_z);
  }
  if (c.holds_somewhere()) {
    std::vector<double> outside;
    for (double t : c.tau_s) {
      if (t < c.holds_tau_min_s || t > c.holds_tau_max_s) outside.push_back(t);
    }
    out += fmt::format(
        "; it holds over tau {:.3g}-{:.3g} s (chi2 = {:.4g} at {} dof, p = {:.2g}), where the "
        "terms are fitted; outside it (tau {} s) the curve has structure the model lacks",
        c.holds_tau_min_s, c.holds_tau_max_s, c.holds_chi2, c.holds_dof, c.holds_p_value,
        TauList(outside));
  } else {
    out += "; it holds over no stretch of the curve, and the terms describe nothing reliably";
  }
  return out + "; u(mean) is not taken from the model";
}

}  // namespace

const char* NoiseModelStatus(const NoiseModelCheck& check) {
  if (!check.tested) return "untested";
  return check.rejected ? "rejected" : "holds";
}

AllanReport MakeAllanReport(const AllanCurve& curve, const NoiseFit& fit,
                            const std::string& quantity_unit) {
  const NoiseUnits units = NoiseUnitsFor(quantity_unit);
  const std::array<ReadOff, kNoiseTermCount> readoffs = ReadOffNoiseTerms(curve);
  const double nan = std::nan("");
  AllanReport r;
  r.estimator = AllanEstimatorName(curve.estimator);
  r.tau_s = curve.tau_s;
  r.adev = curve.dev;
  r.ci_low = curve.ci_low;
  r.ci_high = curve.ci_high;
  r.edf = curve.edf;
  r.n_terms = curve.n_terms;
  // Terms lost to missing samples at each tau (ComputeAllanWithGaps; 0 without gaps).
  r.n_terms_gap_free = curve.n_terms_gap_free;
  r.missing_fraction = MissingFractions(curve);
  // Two-sided confidence level of [ci_low, ci_high] and the power-law noise type alpha
  // (S_y ~ f^alpha) behind each tau's EDF, with where it came from (as in --allan-csv).
  r.confidence = curve.confidence;
  r.alpha.assign(curve.alpha.begin(), curve.alpha.end());
  for (AlphaSource source : curve.alpha_source) r.alpha_source.push_back(AlphaSourceName(source));
  for (NoiseTerm t : kAllNoiseTerms) {
    const size_t i = static_cast<size_t>(t);
    const UnitConversion& conv = units.terms[i];
    const NoiseTermEstimate& est = fit.terms[i];
    const bool have = fit.success && est.supported;
    AllanNoiseTermReport& term = r.noise[i];
    term.value = have ? est.value : nan;
    term.u = have ? est.u : nan;
    term.unit = conv.unit;
    term.value_conventional = have ? est.value * conv.factor : nan;
    term.unit_conventional = conv.unit_conventional;
    term.u_conventional = have ? est.u * conv.factor : nan;
    term.supported = have;
    term.tau_min_s = have ? est.tau_min_s : nan;
    term.tau_max_s = have ? est.tau_max_s : nan;
    if (fit.success) {
      term.model_rejected = fit.model_check.tested && fit.model_check.rejected;
      term.u_model = have ? est.u_model : nan;
      term.selection =
          AllanTermSelectionReport{est.delta_chi2, est.penalty_chi2, have ? "in" : "out"};
    }
    const ReadOff& ro = readoffs[i];
    if (ro.found) term.readoff = AllanReadOffReport{ro.value, ro.u, ro.tau_read_s};
    if (t == NoiseTerm::kRandomWalk) {
      // One-sided density of the white rate noise: d = sqrt(2) N (sigma(1 s) = d / sqrt 2).
      const double d = std::sqrt(2.0) * est.value;
      const double ud = std::sqrt(2.0) * est.u;
      AllanDensityReport density;
      density.density_one_sided = have ? d : nan;
      density.u_density_one_sided = have ? ud : nan;
      density.unit_density = units.density.unit;
      density.density_one_sided_conventional = have ? d * units.density.factor : nan;
      density.unit_density_conventional = units.density.unit_conventional;
      term.density = density;
    }
  }
  if (fit.success) {
    const NoiseModelCheck& c = fit.model_check;
    AllanModelCheckReport m;
    m.tested = c.tested;
    if (!c.tested) m.not_tested = c.not_tested;
    m.chi2 = c.tested ? c.chi2 : nan;
    if (c.tested) m.dof = c.dof;
    m.p_value = c.tested ? c.p_value : nan;
    m.alpha = c.alpha;
    m.rejected = c.tested && c.rejected;
    m.tau_s = c.tau_s;
    m.z = c.z;
    m.contradicting_taus_s = c.contradicting_taus_s;
    if (c.holds_somewhere()) {
      m.tau_range_model_holds_s = std::array<double, 2>{c.holds_tau_min_s, c.holds_tau_max_s};
      m.holds_chi2 = c.holds_chi2;
      m.holds_dof = c.holds_dof;
      m.holds_p_value = c.holds_p_value;
    }
    m.summary = ModelCheckSummary(c, fit.fit_tau_min_s, fit.fit_tau_max_s);
    r.model_check = std::move(m);
    if (fit.bk_joint || std::isfinite(fit.bk_correlation)) {
      const NoiseTermEstimate& b =
          fit.bk_joint ? fit.joint_b : fit.term(NoiseTerm::kBiasInstability);
      const NoiseTermEstimate& k =
          fit.bk_joint ? fit.joint_k : fit.term(NoiseTerm::kRateRandomWalk);
      r.b_k = AllanBkReport{fit.bk_joint, fit.bk_correlation, b.value, b.u, k.value, k.u};
    }
  }
  return r;
}

AllanReport AllanReportOfCurve(const AllanCurve& curve, const NoiseFitOptions& options,
                               const std::string& quantity_unit, NoiseFit* fit_out) {
  const Result<NoiseFit> fit = FitNoiseTerms(curve, options);
  const NoiseFit noise_fit = fit.ok() ? fit.value() : NoiseFit{};
  AllanReport allan = MakeAllanReport(curve, noise_fit, quantity_unit);
  if (!fit.ok()) {
    allan.fit_error = fit.error().message;
    // No model at all: the report says so as for a model it could not test (issue #36).
    allan.model_check = UnfittedModelCheck(curve, fit.error().message);
  }
  if (fit_out != nullptr) *fit_out = noise_fit;
  return allan;
}

AllanTypeALink MakeAllanTypeALink(const AllanCurve& curve, const NoiseFit& fit, double duration_s) {
  AllanTypeALink link;
  const AllanMinimum min = FindAllanMinimum(curve);
  if (min.found) {
    link.allan_min_tau_s = min.tau_s;
    link.allan_min_dev = min.dev;
  }
  link.allan_min_at_end = min.at_end;
  link.duration_s = duration_s;
  const Result<MeanUncertaintyPrediction> p = PredictMeanUncertainty(fit, duration_s);
  if (p.ok()) {
    link.u_mean_allan = p.value().u;
    link.u_u_mean_allan = p.value().u_of_u;
    link.dominant_term = NoiseTermKey(p.value().dominant);
    link.extrapolated = p.value().extrapolated;
    link.noise_model = NoiseModelStatus(fit.model_check);
  }
  return link;
}

AllanModelCheckReport UnfittedModelCheck(const AllanCurve& curve, const std::string& why) {
  AllanModelCheckReport m;
  m.tested = false;
  m.not_tested = "no IEEE 952 model could be fitted to the curve: " + why;
  const std::string range =
      curve.tau_s.empty()
          ? std::string()
          : fmt::format(" over tau {:.3g}-{:.3g} s", curve.tau_s.front(), curve.tau_s.back());
  m.summary = fmt::format(
      "the IEEE 952 noise model could not be fitted to the Allan curve{} ({}): no goodness of "
      "fit is stated, no tau range where it holds was found (none could be tested), and u(mean) "
      "is not taken from a model",
      range, why);
  return m;
}

std::vector<double> MissingFractions(const AllanCurve& curve) {
  std::vector<double> f(curve.size(), 0.0);
  for (size_t i = 0; i < curve.size() && i < curve.n_terms_gap_free.size(); ++i) {
    if (curve.n_terms_gap_free[i] > 0) {
      f[i] = 1.0 -
             static_cast<double>(curve.n_terms[i]) / static_cast<double>(curve.n_terms_gap_free[i]);
    }
  }
  return f;
}

std::string AllanCurveCsv(const AllanCurve& curve, const std::string& quantity_unit) {
  const std::string tok = NoiseUnitsFor(quantity_unit).column_token;
  std::string out = fmt::format(
      "tau_s,m,n_terms,alpha,alpha_source,edf,{0}_{1},ci_low_{1},ci_high_{1},"
      "missing_fraction\n",
      AllanEstimatorName(curve.estimator), tok);
  const std::vector<double> missing = MissingFractions(curve);
  for (size_t i = 0; i < curve.size(); ++i) {
    out += fmt::format("{},{},{},{},{},{},{},{},{},{}\n", CsvNumber(curve.tau_s[i]), curve.m[i],
                       curve.n_terms[i], curve.alpha[i], AlphaSourceName(curve.alpha_source[i]),
                       CsvNumber(curve.edf[i]), CsvNumber(curve.dev[i]), CsvNumber(curve.ci_low[i]),
                       CsvNumber(curve.ci_high[i]), CsvNumber(missing[i]));
  }
  return out;
}

}  // namespace metro
