#include "metro/noise/allan_report.hpp"

#include <fmt/format.h>

#include <cmath>

#include "metro/noise/noise_units.hpp"

namespace metro {
namespace {

std::string CsvNumber(double v) { return std::isfinite(v) ? fmt::format("{:.10g}", v) : ""; }

}  // namespace

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
  return r;
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
  }
  return link;
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
