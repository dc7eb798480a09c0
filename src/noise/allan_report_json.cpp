#include "allan_report_json.hpp"

#include <cmath>
#include <string>
#include <vector>

namespace metro {
namespace {

using Json = nlohmann::ordered_json;

// NaN (no EDF) and an infinity are null.
Json Number(double v) { return std::isfinite(v) ? Json(v) : Json(nullptr); }

Json Numbers(const std::vector<double>& v) {
  Json a = Json::array();
  for (double x : v) a.push_back(Number(x));
  return a;
}

Json ToJsonValue(const AllanGapsReport& g) {
  Json j;
  j["policy"] = g.policy;
  j["grid_samples"] = g.grid_samples;
  j["missing_samples"] = g.missing_samples;
  j["missing_fraction"] = Number(g.missing_fraction);
  if (g.stretches) j["stretches"] = *g.stretches;
  if (g.analysed_first_sample) j["analysed_first_sample"] = *g.analysed_first_sample;
  if (g.analysed_samples) j["analysed_samples"] = *g.analysed_samples;
  return j;
}

AllanGapsReport GapsFromJsonValue(const JsonCursor& c) {
  AllanGapsReport g;
  g.policy = c["policy"].String();
  g.grid_samples = c["grid_samples"].Integer();
  g.missing_samples = c["missing_samples"].Integer();
  g.missing_fraction = c["missing_fraction"].NumberOrNaN();
  g.stretches = c["stretches"].OptionalInteger();
  g.analysed_first_sample = c["analysed_first_sample"].OptionalInteger();
  g.analysed_samples = c["analysed_samples"].OptionalInteger();
  return g;
}

Json ToJsonValue(const AllanNoiseTermReport& t) {
  Json j;
  j["value"] = Number(t.value);
  j["u"] = Number(t.u);
  j["unit"] = t.unit;
  j["value_conventional"] = Number(t.value_conventional);
  j["unit_conventional"] = t.unit_conventional;
  j["u_conventional"] = Number(t.u_conventional);
  j["supported"] = t.supported;
  j["tau_min_s"] = Number(t.tau_min_s);
  j["tau_max_s"] = Number(t.tau_max_s);
  if (t.readoff) {
    j["readoff"] = {{"value", t.readoff->value}, {"u", t.readoff->u}, {"tau_s", t.readoff->tau_s}};
  } else {
    j["readoff"] = nullptr;
  }
  if (t.density) {
    const AllanDensityReport& d = *t.density;
    j["density_one_sided"] = Number(d.density_one_sided);
    j["u_density_one_sided"] = Number(d.u_density_one_sided);
    j["unit_density"] = d.unit_density;
    j["density_one_sided_conventional"] = Number(d.density_one_sided_conventional);
    j["unit_density_conventional"] = d.unit_density_conventional;
  }
  return j;
}

AllanNoiseTermReport NoiseTermFromJsonValue(const JsonCursor& c) {
  AllanNoiseTermReport t;
  t.value = c["value"].NumberOrNaN();
  t.u = c["u"].NumberOrNaN();
  t.unit = c["unit"].String();
  t.value_conventional = c["value_conventional"].NumberOrNaN();
  t.unit_conventional = c["unit_conventional"].String();
  t.u_conventional = c["u_conventional"].NumberOrNaN();
  t.supported = c["supported"].Bool();
  t.tau_min_s = c["tau_min_s"].NumberOrNaN();
  t.tau_max_s = c["tau_max_s"].NumberOrNaN();
  const JsonCursor readoff = c["readoff"];
  if (!readoff.IsNull()) {
    t.readoff = AllanReadOffReport{readoff["value"].NumberOrNaN(), readoff["u"].NumberOrNaN(),
                                   readoff["tau_s"].NumberOrNaN()};
  }
  if (c.Has("density_one_sided")) {
    AllanDensityReport d;
    d.density_one_sided = c["density_one_sided"].NumberOrNaN();
    d.u_density_one_sided = c["u_density_one_sided"].NumberOrNaN();
    d.unit_density = c["unit_density"].String();
    d.density_one_sided_conventional = c["density_one_sided_conventional"].NumberOrNaN();
    d.unit_density_conventional = c["unit_density_conventional"].String();
    t.density = d;
  }
  return t;
}

}  // namespace

Json ToJsonValue(const AllanReport& a) {
  Json j;
  if (!a.ok()) {
    j["error"] = a.error;
    if (a.gaps) j["gaps"] = ToJsonValue(*a.gaps);
    return j;
  }
  j["estimator"] = a.estimator;
  j["tau_s"] = Numbers(a.tau_s);
  j["adev"] = Numbers(a.adev);
  j["ci_low"] = Numbers(a.ci_low);
  j["ci_high"] = Numbers(a.ci_high);
  j["edf"] = Numbers(a.edf);
  j["n_terms"] = a.n_terms;
  j["n_terms_gap_free"] = a.n_terms_gap_free;
  j["missing_fraction"] = Numbers(a.missing_fraction);
  j["confidence"] = Number(a.confidence);
  j["alpha"] = a.alpha;
  j["alpha_source"] = a.alpha_source;
  Json noise = Json::object();
  for (NoiseTerm t : kAllNoiseTerms) noise[NoiseTermKey(t)] = ToJsonValue(a.term(t));
  j["noise"] = noise;
  const AllanSamplePeriodReport& p = a.sample_period;
  j["sample_period"] = {{"tau0_s", Number(p.tau0_s)},
                        {"rate_hz", Number(p.rate_hz)},
                        {"mean_dt_s", Number(p.mean_dt_s)},
                        {"jitter_rms_s", Number(p.jitter_rms_s)},
                        {"max_abs_jitter_s", Number(p.max_abs_jitter_s)},
                        {"missing_samples", p.missing_samples},
                        {"warnings", p.warnings}};
  if (a.gaps) j["gaps"] = ToJsonValue(*a.gaps);
  if (a.fit_error) j["fit_error"] = *a.fit_error;
  return j;
}

AllanReport AllanReportFromJsonValue(const JsonCursor& c) {
  AllanReport a;
  if (!c.IsObject()) {
    c.Fail("an object");
    return a;
  }
  if (c["gaps"].Present()) a.gaps = GapsFromJsonValue(c["gaps"]);
  if (c.Has("error")) {
    a.error = c["error"].String();
    return a;
  }
  a.estimator = c["estimator"].String();
  a.tau_s = c["tau_s"].NumbersOrNaN();
  a.adev = c["adev"].NumbersOrNaN();
  a.ci_low = c["ci_low"].NumbersOrNaN();
  a.ci_high = c["ci_high"].NumbersOrNaN();
  a.edf = c["edf"].NumbersOrNaN();
  a.n_terms = c["n_terms"].Integers();
  a.n_terms_gap_free = c["n_terms_gap_free"].Integers();
  a.missing_fraction = c["missing_fraction"].NumbersOrNaN();
  a.confidence = c["confidence"].NumberOrNaN();
  a.alpha = c["alpha"].Integers();
  a.alpha_source = c["alpha_source"].Strings();
  const JsonCursor noise = c["noise"];
  for (NoiseTerm t : kAllNoiseTerms) {
    a.noise[static_cast<size_t>(t)] = NoiseTermFromJsonValue(noise[NoiseTermKey(t)]);
  }
  const JsonCursor p = c["sample_period"];
  a.sample_period.tau0_s = p["tau0_s"].NumberOrNaN();
  a.sample_period.rate_hz = p["rate_hz"].NumberOrNaN();
  a.sample_period.mean_dt_s = p["mean_dt_s"].NumberOrNaN();
  a.sample_period.jitter_rms_s = p["jitter_rms_s"].NumberOrNaN();
  a.sample_period.max_abs_jitter_s = p["max_abs_jitter_s"].NumberOrNaN();
  a.sample_period.missing_samples = p["missing_samples"].Integer();
  a.sample_period.warnings = p["warnings"].Strings();
  a.fit_error = c["fit_error"].OptionalString();
  return a;
}

Json ToJsonValue(const AllanTypeALink& link) {
  Json j;
  j["allan_min_tau_s"] = Number(link.allan_min_tau_s);
  j["allan_min_dev"] = Number(link.allan_min_dev);
  j["allan_min_at_end"] = link.allan_min_at_end;
  j["duration_s"] = Number(link.duration_s);
  j["u_mean_allan"] = Number(link.u_mean_allan);
  j["u_u_mean_allan"] = Number(link.u_u_mean_allan);
  j["dominant_term"] = link.dominant_term ? Json(*link.dominant_term) : Json(nullptr);
  j["extrapolated"] = link.extrapolated ? Json(*link.extrapolated) : Json(nullptr);
  return j;
}

AllanTypeALink AllanTypeALinkFromJsonValue(const JsonCursor& c) {
  AllanTypeALink link;
  link.allan_min_tau_s = c["allan_min_tau_s"].NumberOrNaN();
  link.allan_min_dev = c["allan_min_dev"].NumberOrNaN();
  link.allan_min_at_end = c["allan_min_at_end"].Bool();
  link.duration_s = c["duration_s"].NumberOrNaN();
  link.u_mean_allan = c["u_mean_allan"].NumberOrNaN();
  link.u_u_mean_allan = c["u_u_mean_allan"].NumberOrNaN();
  link.dominant_term = c["dominant_term"].OptionalString();
  if (!c["extrapolated"].IsNull()) link.extrapolated = c["extrapolated"].Bool();
  return link;
}

}  // namespace metro
