#include "allan_report_json.hpp"

#include <cmath>
#include <string>
#include <vector>

#include "core/json_text.hpp"
#include "metro/noise/noise_export.hpp"

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
  if (t.model_rejected) j["model_rejected"] = *t.model_rejected;
  if (t.u_model) j["u_model"] = Number(*t.u_model);
  if (t.selection) {
    j["selection"] = {{"delta_chi2", Number(t.selection->delta_chi2)},
                      {"penalty_chi2", Number(t.selection->penalty_chi2)},
                      {"decision", t.selection->decision}};
  }
  return j;
}

Json ToJsonValue(const AllanModelCheckReport& m) {
  Json j;
  j["tested"] = m.tested;
  j["not_tested"] = m.not_tested ? Json(*m.not_tested) : Json(nullptr);
  j["chi2"] = Number(m.chi2);
  j["dof"] = m.dof ? Json(*m.dof) : Json(nullptr);
  j["p_value"] = Number(m.p_value);
  j["alpha"] = Number(m.alpha);
  j["rejected"] = m.rejected;
  j["tau_s"] = Numbers(m.tau_s);
  j["z"] = Numbers(m.z);
  j["contradicting_taus_s"] = Numbers(m.contradicting_taus_s);
  if (m.tau_range_model_holds_s) {
    j["tau_range_model_holds_s"] =
        Json::array({(*m.tau_range_model_holds_s)[0], (*m.tau_range_model_holds_s)[1]});
  } else {
    j["tau_range_model_holds_s"] = nullptr;
  }
  j["holds_chi2"] = Number(m.holds_chi2);
  j["holds_dof"] = m.holds_dof ? Json(*m.holds_dof) : Json(nullptr);
  j["holds_p_value"] = Number(m.holds_p_value);
  j["summary"] = m.summary;
  return j;
}

AllanModelCheckReport ModelCheckFromJsonValue(const JsonCursor& c) {
  AllanModelCheckReport m;
  m.tested = c["tested"].Bool();
  m.not_tested = c["not_tested"].OptionalString();
  m.chi2 = c["chi2"].NumberOrNaN();
  m.dof = c["dof"].OptionalInteger();
  m.p_value = c["p_value"].NumberOrNaN();
  m.alpha = c["alpha"].NumberOrNaN();
  m.rejected = c["rejected"].Bool();
  m.tau_s = c["tau_s"].NumbersOrNaN();
  m.z = c["z"].NumbersOrNaN();
  m.contradicting_taus_s = c["contradicting_taus_s"].NumbersOrNaN();
  const JsonCursor range = c["tau_range_model_holds_s"];
  if (!range.IsNull()) {
    const std::vector<double> r = range.NumbersOrNaN();
    if (r.size() == 2) {
      m.tau_range_model_holds_s = std::array<double, 2>{r[0], r[1]};
    } else {
      range.Fail("[tau_min_s, tau_max_s]");
    }
  }
  m.holds_chi2 = c["holds_chi2"].NumberOrNaN();
  m.holds_dof = c["holds_dof"].OptionalInteger();
  m.holds_p_value = c["holds_p_value"].NumberOrNaN();
  m.summary = c["summary"].String();
  return m;
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
  if (c.Has("model_rejected")) t.model_rejected = c["model_rejected"].Bool();
  if (c.Has("u_model")) t.u_model = c["u_model"].NumberOrNaN();
  if (c.Has("selection")) {
    const JsonCursor sel = c["selection"];
    t.selection =
        AllanTermSelectionReport{sel["delta_chi2"].NumberOrNaN(), sel["penalty_chi2"].NumberOrNaN(),
                                 sel["decision"].String()};
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
  for (NoiseTerm t : kAllNoiseTerms) {
    Json term = ToJsonValue(a.term(t));
    // Derived from value, u and unit (written, never read): the field's names (issue #40).
    if (const std::optional<StandardNoiseName> n = StandardNoiseNameOf(t, a.term(t))) {
      Json standard = {{"name", n->name},
                       {"kalibr_key", n->kalibr_key},
                       {"value", Number(n->value)},
                       {"u", Number(n->u)},
                       {"unit", n->unit}};
      if (t == NoiseTerm::kRandomWalk) {
        standard["density_one_sided"] = Number(n->density_one_sided);
        standard["u_density_one_sided"] = Number(n->u_density_one_sided);
      }
      term["standard"] = standard;
    }
    noise[NoiseTermKey(t)] = term;
  }
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
  if (a.model_check) j["model_check"] = ToJsonValue(*a.model_check);
  if (a.b_k) {
    j["b_k"] = {{"joint", a.b_k->joint}, {"correlation", Number(a.b_k->correlation)},
                {"b", Number(a.b_k->b)}, {"u_b", Number(a.b_k->u_b)},
                {"k", Number(a.b_k->k)}, {"u_k", Number(a.b_k->u_k)}};
  }
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
  if (c.Has("model_check")) a.model_check = ModelCheckFromJsonValue(c["model_check"]);
  if (c.Has("b_k")) {
    const JsonCursor bk = c["b_k"];
    a.b_k = AllanBkReport{bk["joint"].Bool(),    bk["correlation"].NumberOrNaN(),
                          bk["b"].NumberOrNaN(), bk["u_b"].NumberOrNaN(),
                          bk["k"].NumberOrNaN(), bk["u_k"].NumberOrNaN()};
  }
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
  if (link.noise_model) j["noise_model"] = *link.noise_model;
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
  link.noise_model = c["noise_model"].OptionalString();
  return link;
}

std::string ToJson(const AllanReport& allan) { return JsonText(ToJsonValue(allan), 2); }

}  // namespace metro
