#include "metro/accuracy/accuracy_report.hpp"

#include <fmt/format.h>

#include <cmath>

#include "metro/core/device_id.hpp"
#include "metro/core/rounding.hpp"

namespace metro {
namespace {

using Json = nlohmann::ordered_json;

// Infinite or NaN numbers are written as null (JSON has neither).
Json Num(double v) { return std::isfinite(v) ? Json(v) : Json(nullptr); }

// U to two significant digits (JCGM 100 7.2.6).
std::string U2(double u) { return RoundForStatement(0.0, u).uncertainty; }

const char* DirectionName(int d) { return d > 0 ? "up" : d < 0 ? "down" : "first"; }

Json FitJson(const HarmonicFit& fit) {
  Json j;
  Json params = Json::array();
  for (size_t i = 0; i < fit.terms.size(); ++i) {
    params.push_back({{"name", ErrorTermName(fit.terms[i])},
                      {"value", fit.params[i]},
                      {"u", fit.u[i]},
                      {"unit", fit.terms[i] == ErrorTerm::kScale ? "deg/deg" : "deg"}});
  }
  j["params"] = params;
  j["covariance"] = fit.covariance;
  j["chi2"] = fit.chi2;
  j["dof"] = fit.dof;
  j["reduced_chi2"] = fit.reduced_chi2;
  j["covariance_scaled_by_reduced_chi2"] = fit.covariance_scaled;
  j["residual_rms_deg"] = fit.residual_rms_deg;
  j["residuals_deg"] = fit.residuals_deg;
  return j;
}

Json BudgetJson(const ReadingBudget& b) {
  const GumResult& g = b.gum;
  Json inputs = Json::array();
  for (const BudgetLine& line : g.budget) {
    std::string note;
    for (size_t i = 0; i < b.input_names.size() && i < b.notes.size(); ++i) {
      if (b.input_names[i] == line.name) note = b.notes[i];
    }
    inputs.push_back({{"name", line.name},
                      {"u_deg", line.u},
                      {"distribution", line.distribution},
                      {"sensitivity", line.sensitivity},
                      {"contribution_deg", line.contribution},
                      {"dof", Num(line.dof)},
                      {"percent", line.percent},
                      {"note", note}});
  }
  return {{"u_deg", g.u},        {"dof_eff", Num(g.dof_eff)}, {"k", g.k},
          {"U_deg", g.expanded}, {"coverage", g.coverage},    {"dof_note", g.dof_note},
          {"inputs", inputs}};
}

std::string Statement(double u_expanded, double k, double coverage) {
  return fmt::format("+-{} deg (k = {:.3g}, p = {:.3g})", U2(u_expanded), k, coverage);
}

}  // namespace

Json AccuracyReportJson(const AccuracyResult& r, const Session& session, const Session* reference,
                        const TagRegistry& tags) {
  Json j;
  j["schema"] = "metro.accuracy-report/1";
  Json input = {{"session", session.path},
                {"sha256", session.sha256},
                {"format", SessionFormatName(session.format)},
                {"sensor", r.sensor},
                {"table_axis", TableAxisName(r.axis)},
                {"quantity", r.quantity}};
  const TagEntry* entry = tags.Find(r.sensor);
  input["tag"] = {{"name", tags.Name(r.sensor)},
                  {"device_id", entry != nullptr && entry->device_id
                                    ? Json(FormatDeviceIdText(*entry->device_id))
                                    : Json(nullptr)}};
  if (reference != nullptr && r.alignment) {
    const Alignment& a = *r.alignment;
    input["reference"] = {{"file", reference->path},
                          {"sha256", reference->sha256},
                          {"alignment",
                           {{"method", a.method},
                            {"estimated", a.estimated},
                            {"offset_s", a.offset_s},
                            {"residual_std_deg", Num(a.residual_std_deg)},
                            {"residual_std_at_zero_offset_deg", Num(a.residual_std_at_zero_deg)},
                            {"overlap_samples", a.overlap_samples},
                            {"outside_samples", a.outside_samples},
                            {"tag_t_s", {a.tag_t_first_s, a.tag_t_last_s}},
                            {"reference_t_s", {a.reference_t_first_s, a.reference_t_last_s}},
                            {"delay_s", a.delay_s},
                            {"lag_modelled", a.lag_modelled},
                            {"lag_tau_s", a.lag_modelled ? Json(a.lag_tau_s) : Json(nullptr)}}}};
  } else {
    input["reference"] = {{"file", nullptr}, {"column", "table_angle_deg"}};
  }
  j["input"] = input;
  const AccuracyOptions& o = r.options;
  const WindowOptions& w = o.window;
  j["window"] = {{"skip_samples", w.skip_samples},
                 {"skip_seconds", w.skip_seconds},
                 {"from_s", w.from_s ? Json(*w.from_s) : Json()},
                 {"to_s", w.to_s ? Json(*w.to_s) : Json()},
                 {"n_total", r.window.n_total},
                 {"n", r.window.n()},
                 {"t_first_s", r.window.t_first_s},
                 {"t_last_s", r.window.t_last_s}};
  j["options"] = {{"plateau_tolerance_deg", o.plateaus.tolerance_deg},
                  {"min_dwell_s", o.plateaus.min_dwell_s},
                  {"min_samples", o.plateaus.min_samples},
                  {"settle_s", o.plateaus.settle_s},
                  {"settle", o.plateaus.settle_auto ? "auto" : "none"},
                  {"angle_match_deg", o.angle_match_deg},
                  {"model", ErrorModelName(o.model)},
                  {"resolution_deg", o.resolution_deg},
                  {"reference_u_deg", o.reference.u_deg},
                  {"reference_dof", Num(o.reference.dof)},
                  {"reference_u_source", o.reference.source},
                  {"coverage", o.coverage},
                  {"assumed_hysteresis_deg", o.assumed_hysteresis_deg},
                  {"model_lag", o.model_lag},
                  {"lag_tau_s", o.lag_tau_s ? Json(*o.lag_tau_s) : Json(nullptr)},
                  {"settle_lag_residual_deg", o.plateaus.settle_lag_residual_deg},
                  {"trim_departures", o.plateaus.trim_departures},
                  {"departure_sigmas", o.plateaus.departure_sigmas}};
  const Segmentation& s = r.segmentation;
  Json excluded = Json::array();
  for (const ExcludedSpan& e : s.excluded) {
    excluded.push_back({{"t_start_s", e.t_start_s},
                        {"t_end_s", e.t_end_s},
                        {"samples", e.end - e.begin},
                        {"reason", e.reason}});
  }
  j["segmentation"] = {{"plateaus", s.plateaus.size()},
                       {"excluded_samples", s.motion_samples},
                       {"excluded_s", s.motion_s},
                       {"settle_samples", s.settle_samples},
                       {"excluded", excluded},
                       {"lag_tau_s", r.lag_tau_s},
                       {"lag_method", r.lag_method},
                       {"lag_settled_plateaus", r.lag_settled_plateaus},
                       {"max_settle_s", r.max_settle_s},
                       {"reference_unwrapped", r.reference_unwrapped},
                       {"departure_trimmed_plateaus", s.departure_trimmed_plateaus},
                       {"departure_trimmed_samples", s.departure_trimmed_samples},
                       {"max_end_trimmed_s", s.max_end_trimmed_s},
                       {"departure_kept_plateaus", s.departure_kept_plateaus}};
  Json points = Json::array();
  for (const AccuracyPoint& p : r.points) {
    Json other, other_u;
    for (int k = 0; k < 2; ++k) {
      other[r.cross_axis[k].quantity] =
          r.cross_axis_available ? Json(p.other_mean_deg[k]) : Json(nullptr);
      other_u[r.cross_axis[k].quantity] =
          r.cross_axis_available ? Json(p.other_u_deg[k]) : Json(nullptr);
    }
    points.push_back({{"reference_deg", p.reference_deg},
                      {"mean_deg", p.mean_deg},
                      {"error_deg", p.error_deg},
                      {"type_a",
                       {{"n", p.type_a.n},
                        {"std_deg", p.type_a.std_deg},
                        {"u_deg", p.type_a.u_deg},
                        {"n_eff", p.type_a.n_eff},
                        {"dof", p.type_a.dof}}},
                      {"direction", DirectionName(p.direction)},
                      {"sweep", p.sweep},
                      {"t_start_s", p.t_start_s},
                      {"t_end_s", p.t_end_s},
                      {"settle_samples", p.settle_samples},
                      {"other_axes_mean_deg", other},
                      {"other_axes_u_deg", other_u}});
  }
  j["points"] = points;
  j["noise"] = {{"sigma_deg", r.noise.sigma_deg},
                {"phi_per_observation", r.noise.phi},
                {"dof", r.noise.dof},
                {"plateaus", r.noise.plateaus},
                {"method",
                 "one AR(1) process over all plateaus, each plateau's mean removed, fitted by the "
                 "method of moments (exact expectations of the lag-0 and lag-1 sums); u of a "
                 "plateau mean = sigma sqrt(F(n, phi))"}};
  const SystematicError& se = r.systematic;
  j["systematic"] = {{"mean_error_deg", se.mean_deg},
                     {"std_error_deg", se.std_deg},
                     {"rms_error_deg", se.rms_deg},
                     {"max_abs_error_deg", se.max_abs_deg},
                     {"at_reference_deg", se.at_reference_deg}};
  Json fit = {{"model", ErrorModelName(r.model)},
              {"equation",
               "e(theta) = c0 + s theta + a1 cos(theta) + b1 sin(theta) + a2 cos(2 theta) + b2 "
               "sin(2 theta) (+ h d / 2, d = +1 up, -1 down, 0 first), theta in deg"},
              {"hysteresis_term", r.fit_hysteresis_term},
              {"order_rule", kErrorModelOrderRule},
              {"weights", "1/u_i^2, u_i the plateau Type A u"}};
  fit.update(FitJson(r.fit));
  fit["max_prediction_u_deg"] = r.max_prediction_u_deg;
  j["fit"] = fit;
  const Linearity& l = r.linearity;
  j["linearity"] = {{"max_abs_deviation_deg", l.max_abs_deviation_deg},
                    {"at_reference_deg", l.at_reference_deg},
                    {"rms_deviation_deg", l.rms_deviation_deg},
                    {"percent_of_span", l.percent_of_span},
                    {"line_offset_deg", l.line_offset_deg},
                    {"line_slope", l.line_slope},
                    {"angles", l.angles},
                    {"u_max_abs_deviation_deg", l.u_max_abs_deviation_deg}};
  const Hysteresis& h = r.hysteresis;
  Json pairs = Json::array();
  for (const HysteresisPair& p : h.pairs) {
    pairs.push_back({{"reference_deg", p.reference_deg},
                     {"up_error_deg", p.up_error_deg},
                     {"down_error_deg", p.down_error_deg},
                     {"hysteresis_deg", p.hysteresis_deg},
                     {"u_deg", p.u_deg},
                     {"dof", Num(p.dof)},
                     {"up_plateaus", p.up_count},
                     {"down_plateaus", p.down_count}});
  }
  j["hysteresis"] = {{"available", h.available},
                     {"mean_deg", h.available ? Json(h.mean_deg) : Json(nullptr)},
                     {"u_mean_deg", h.available ? Json(h.u_mean_deg) : Json(nullptr)},
                     {"max_abs_deg", h.available ? Json(h.max_abs_deg) : Json(nullptr)},
                     {"u_max_abs_deg", h.available ? Json(h.u_max_abs_deg) : Json(nullptr)},
                     {"at_reference_deg", h.available ? Json(h.at_reference_deg) : Json(nullptr)},
                     {"pairs", pairs},
                     {"note", h.note}};
  const Repeatability& rp = r.repeatability;
  j["repeatability"] = {{"available", rp.available},
                        {"s_r_deg", rp.available ? Json(rp.s_r_deg) : Json(nullptr)},
                        {"dof", rp.dof},
                        {"u_s_r_deg", rp.available ? Json(rp.u_s_r_deg) : Json(nullptr)},
                        {"groups", rp.groups},
                        {"sweeps", rp.sweeps},
                        {"note", rp.note}};
  Json cross;
  for (const CrossAxis& x : r.cross_axis) {
    if (!r.cross_axis_available) {
      cross[x.quantity] = {{"evaluated", false},
                           {"mean_deg", nullptr},
                           {"span_deg", nullptr},
                           {"fitted", false},
                           {"note", r.cross_axis_note}};
      continue;
    }
    Json c = {{"evaluated", true},
              {"mean_deg", x.mean_deg},
              {"span_deg", x.span_deg},
              {"fitted", x.fitted}};
    if (x.fitted) {
      c["amplitude_deg"] = x.amplitude_deg;
      c["u_amplitude_deg"] = x.u_amplitude_deg;
      c["fit"] = FitJson(x.fit);
    }
    cross[x.quantity] = c;
  }
  j["cross_axis"] = cross;
  j["budget"] = {{"corrected", BudgetJson(r.corrected)},
                 {"uncorrected", BudgetJson(r.uncorrected)}};
  j["result"] = {
      {"ok", true},
      {"U_corrected_deg", r.corrected.gum.expanded},
      {"k_corrected", r.corrected.gum.k},
      {"U_uncorrected_deg", r.uncorrected.gum.expanded},
      {"k_uncorrected", r.uncorrected.gum.k},
      {"U_random_deg", r.random_expanded_deg},
      {"U_uncorrected_max_abs_deg", r.uncorrected_max_abs_expanded_deg},
      {"U_uncorrected_gum_deg", r.uncorrected_gum_expanded_deg},
      {"which_U_to_quote", r.which_u},
      {"coverage", r.corrected.gum.coverage},
      {"statement_corrected",
       "a single " + r.quantity + " reading corrected by the fitted curve: error within " +
           Statement(r.corrected.gum.expanded, r.corrected.gum.k, r.corrected.gum.coverage)},
      {"statement_uncorrected",
       "a single uncorrected " + r.quantity + " reading: error within " +
           Statement(r.uncorrected.gum.expanded, r.uncorrected.gum.k, r.uncorrected.gum.coverage) +
           fmt::format("; bound U(random) + max|e| = {} deg",
                       U2(r.uncorrected_max_abs_expanded_deg))}};
  j["warnings"] = r.warnings;
  return j;
}

std::string AccuracyReportTable(const AccuracyResult& r) {
  std::string out;
  auto it = std::back_inserter(out);
  fmt::format_to(it, "Accuracy of tag {} {} against the table ({} axis), {} plateaus\n", r.sensor,
                 r.quantity, TableAxisName(r.axis), r.points.size());
  if (r.alignment) {
    fmt::format_to(it, "reference log aligned: offset {:.4f} s ({}), residual std {:.4g} deg\n",
                   r.alignment->offset_s, r.alignment->estimated ? "estimated" : "given",
                   r.alignment->residual_std_deg);
  }
  fmt::format_to(it, "{:>4} {:>12} {:>12} {:>10} {:>9} {:>8} {:>6}\n", "#", "reference_deg",
                 "mean_deg", "error_deg", "u_deg", "n_eff", "dir");
  for (const AccuracyPoint& p : r.points) {
    fmt::format_to(it, "{:>4} {:>12.4f} {:>12.4f} {:>10.4f} {:>9.5f} {:>8.1f} {:>6}\n", p.index,
                   p.reference_deg, p.mean_deg, p.error_deg, p.type_a.u_deg, p.type_a.n_eff,
                   DirectionName(p.direction));
  }
  fmt::format_to(it,
                 "systematic: mean {:.4f} deg, RMS {:.4f} deg, max |e| {:.4f} deg at {:.6g} deg\n",
                 r.systematic.mean_deg, r.systematic.rms_deg, r.systematic.max_abs_deg,
                 r.systematic.at_reference_deg);
  fmt::format_to(it, "fit ({}, chi2/nu {:.3g}{}):", ErrorModelName(r.model), r.fit.reduced_chi2,
                 r.fit.covariance_scaled ? ", covariance scaled" : "");
  for (size_t i = 0; i < r.fit.terms.size(); ++i) {
    fmt::format_to(it, " {} = {:.5g} +- {:.2g}", ErrorTermName(r.fit.terms[i]), r.fit.params[i],
                   r.fit.u[i]);
  }
  out += '\n';
  fmt::format_to(it,
                 "linearity: max deviation {:.4f} +- {:.4f} deg at {:.6g} deg ({:.3g} % of span)\n",
                 r.linearity.max_abs_deviation_deg, r.linearity.u_max_abs_deviation_deg,
                 r.linearity.at_reference_deg, r.linearity.percent_of_span);
  if (r.hysteresis.available) {
    fmt::format_to(it, "hysteresis (up - down): mean {:.4f} +- {:.4f} deg, max |h| {:.4f} deg\n",
                   r.hysteresis.mean_deg, r.hysteresis.u_mean_deg, r.hysteresis.max_abs_deg);
  } else {
    fmt::format_to(it, "hysteresis: {}\n", r.hysteresis.note);
  }
  if (r.repeatability.available) {
    fmt::format_to(it, "repeatability: s_r {:.4f} deg (dof {:.0f})\n", r.repeatability.s_r_deg,
                   r.repeatability.dof);
  } else {
    fmt::format_to(it, "repeatability: {}\n", r.repeatability.note);
  }
  if (!r.cross_axis_available) out += "cross-axis: " + r.cross_axis_note + "\n";
  for (const CrossAxis& x : r.cross_axis) {
    if (!r.cross_axis_available) break;
    fmt::format_to(it, "cross-axis {}: span {:.4f} deg", x.quantity, x.span_deg);
    if (x.fitted) {
      fmt::format_to(it, ", first harmonic {:.4f} +- {:.4f} deg", x.amplitude_deg,
                     x.u_amplitude_deg);
    }
    out += '\n';
  }
  fmt::format_to(it, "single reading, corrected:   U = {} deg (k = {:.3g}, nu_eff = {:.3g})\n",
                 U2(r.corrected.gum.expanded), r.corrected.gum.k, r.corrected.gum.dof_eff);
  fmt::format_to(
      it, "single reading, uncorrected: U = {} deg (k = {:.3g}); U(random) + max|e| = {} deg\n",
      U2(r.uncorrected.gum.expanded), r.uncorrected.gum.k, U2(r.uncorrected_max_abs_expanded_deg));
  for (const std::string& w : r.warnings) out += "warning: " + w + "\n";
  return out;
}

}  // namespace metro
