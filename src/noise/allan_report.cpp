#include "metro/noise/allan_report.hpp"

#include <fmt/format.h>

#include <cmath>

#include "metro/noise/noise_units.hpp"

namespace metro {
namespace {

using Json = nlohmann::ordered_json;

Json Number(double v) { return std::isfinite(v) ? Json(v) : Json(nullptr); }

Json NumberArray(const std::vector<double>& v) {
  Json a = Json::array();
  for (double x : v) a.push_back(Number(x));
  return a;
}

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

Json AllanToJson(const AllanCurve& curve, const NoiseFit& fit, const std::string& quantity_unit) {
  const NoiseUnits units = NoiseUnitsFor(quantity_unit);
  const std::array<ReadOff, kNoiseTermCount> readoffs = ReadOffNoiseTerms(curve);
  Json j;
  j["estimator"] = AllanEstimatorName(curve.estimator);
  j["tau_s"] = NumberArray(curve.tau_s);
  j["adev"] = NumberArray(curve.dev);
  j["ci_low"] = NumberArray(curve.ci_low);
  j["ci_high"] = NumberArray(curve.ci_high);
  j["edf"] = NumberArray(curve.edf);
  j["n_terms"] = curve.n_terms;
  // Terms lost to missing samples at each tau (ComputeAllanWithGaps; 0 without gaps).
  j["n_terms_gap_free"] = curve.n_terms_gap_free;
  j["missing_fraction"] = NumberArray(MissingFractions(curve));
  // Two-sided confidence level of [ci_low, ci_high] and the power-law noise type alpha
  // (S_y ~ f^alpha) behind each tau's EDF, with where it came from (as in --allan-csv).
  j["confidence"] = Number(curve.confidence);
  j["alpha"] = curve.alpha;
  Json sources = Json::array();
  for (AlphaSource source : curve.alpha_source) sources.push_back(AlphaSourceName(source));
  j["alpha_source"] = sources;
  Json noise = Json::object();
  for (NoiseTerm t : kAllNoiseTerms) {
    const size_t i = static_cast<size_t>(t);
    const UnitConversion& conv = units.terms[i];
    const NoiseTermEstimate& est = fit.terms[i];
    const bool have = fit.success && est.supported;
    Json term;
    term["value"] = have ? Number(est.value) : Json(nullptr);
    term["u"] = have ? Number(est.u) : Json(nullptr);
    term["unit"] = conv.unit;
    term["value_conventional"] = have ? Number(est.value * conv.factor) : Json(nullptr);
    term["unit_conventional"] = conv.unit_conventional;
    term["u_conventional"] = have ? Number(est.u * conv.factor) : Json(nullptr);
    term["supported"] = have;
    term["tau_min_s"] = have ? Number(est.tau_min_s) : Json(nullptr);
    term["tau_max_s"] = have ? Number(est.tau_max_s) : Json(nullptr);
    const ReadOff& ro = readoffs[i];
    if (ro.found) {
      term["readoff"] = {
          {"value", Number(ro.value)}, {"u", Number(ro.u)}, {"tau_s", Number(ro.tau_read_s)}};
    } else {
      term["readoff"] = nullptr;
    }
    if (t == NoiseTerm::kRandomWalk) {
      // One-sided density of the white rate noise: d = sqrt(2) N (sigma(1 s) = d / sqrt 2).
      const double d = std::sqrt(2.0) * est.value;
      const double ud = std::sqrt(2.0) * est.u;
      term["density_one_sided"] = have ? Number(d) : Json(nullptr);
      term["u_density_one_sided"] = have ? Number(ud) : Json(nullptr);
      term["unit_density"] = units.density.unit;
      term["density_one_sided_conventional"] =
          have ? Number(d * units.density.factor) : Json(nullptr);
      term["unit_density_conventional"] = units.density.unit_conventional;
    }
    noise[NoiseTermKey(t)] = term;
  }
  j["noise"] = noise;
  return j;
}

Json AllanTypeALinkToJson(const AllanCurve& curve, const NoiseFit& fit, double duration_s) {
  Json j;
  const AllanMinimum min = FindAllanMinimum(curve);
  j["allan_min_tau_s"] = min.found ? Number(min.tau_s) : Json(nullptr);
  j["allan_min_dev"] = min.found ? Number(min.dev) : Json(nullptr);
  j["allan_min_at_end"] = min.at_end;
  j["duration_s"] = Number(duration_s);
  const Result<MeanUncertaintyPrediction> p = PredictMeanUncertainty(fit, duration_s);
  j["u_mean_allan"] = p.ok() ? Number(p.value().u) : Json(nullptr);
  j["u_u_mean_allan"] = p.ok() ? Number(p.value().u_of_u) : Json(nullptr);
  j["dominant_term"] = p.ok() ? Json(NoiseTermKey(p.value().dominant)) : Json(nullptr);
  j["extrapolated"] = p.ok() ? Json(p.value().extrapolated) : Json(nullptr);
  return j;
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
