#include "metro/accuracy/accuracy_report.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "accuracy/accuracy_report_json.hpp"
#include "core/json_reader.hpp"
#include "core/json_text.hpp"
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

constexpr const char* kNoiseMethod =
    "one AR(1) process over all plateaus, each plateau's mean removed, fitted by the "
    "method of moments (exact expectations of the lag-0 and lag-1 sums); u of a "
    "plateau mean = sigma sqrt(F(n, phi))";
constexpr const char* kFitEquation =
    "e(theta) = c0 + s theta + a1 cos(theta) + b1 sin(theta) + a2 cos(2 theta) + b2 "
    "sin(2 theta) (+ h d / 2, d = +1 up, -1 down, 0 first), theta in deg";
constexpr const char* kFitWeights = "1/u_i^2, u_i the plateau Type A u";

// ---- Reading (JsonCursor records the first error; every read gives a default after it). ----

template <typename T>
T ReadCount(const JsonCursor& c) {
  const int64_t v = c.Integer();
  if (v < 0 && c.ok()) c.Fail("an integer >= 0");
  return static_cast<T>(std::max<int64_t>(v, 0));
}

// A [first, last] pair of numbers.
void ReadPair(const JsonCursor& c, double* first, double* last) {
  const std::vector<double> v = c.NumbersOrNaN();
  if (c.ok() && v.size() != 2) c.Fail("an array of 2 numbers [first, last]");
  if (v.size() == 2) {
    *first = v[0];
    *last = v[1];
  }
}

int ReadDirection(const JsonCursor& c) {
  const std::string name = c.String();
  for (int d : {1, -1, 0}) {
    if (name == DirectionName(d)) return d;
  }
  if (c.ok()) c.Fail("one of \"up\", \"down\", \"first\"");
  return 0;
}

ErrorModel ReadErrorModel(const JsonCursor& c) {
  const std::string name = c.String();
  Result<ErrorModel> model = ParseErrorModel(name);
  if (model.ok()) return model.value();
  if (c.ok()) c.Fail("one of \"auto\", \"linear\", \"harmonic1\", \"harmonic2\"");
  return ErrorModel::kAuto;
}

HarmonicFit ReadFit(const JsonCursor& j) {
  HarmonicFit fit;
  const JsonCursor params = j["params"];
  if (!params.IsArray()) params.Fail("an array of parameters {name, value, u, unit}");
  for (size_t i = 0; i < params.Size(); ++i) {
    const JsonCursor p = params[i];
    const JsonCursor name = p["name"];
    const std::string text = name.String();
    bool known = false;
    for (ErrorTerm t : {ErrorTerm::kOffset, ErrorTerm::kScale, ErrorTerm::kCos1, ErrorTerm::kSin1,
                        ErrorTerm::kCos2, ErrorTerm::kSin2, ErrorTerm::kHysteresis}) {
      if (text == ErrorTermName(t)) {
        fit.terms.push_back(t);
        known = true;
      }
    }
    if (!known && name.ok()) {
      name.Fail("a parameter name (c0_deg, scale, a1_deg, b1_deg, a2_deg, b2_deg, h_deg)");
    }
    fit.params.push_back(p["value"].NumberOrNaN());
    fit.u.push_back(p["u"].NumberOrNaN());
    const std::string unit = p["unit"].String();
    const char* expected =
        !fit.terms.empty() && fit.terms.back() == ErrorTerm::kScale ? "deg/deg" : "deg";
    if (known && unit != expected && p["unit"].ok()) {
      p["unit"].Fail(fmt::format("\"{}\"", expected));
    }
  }
  const JsonCursor covariance = j["covariance"];
  if (!covariance.IsArray()) covariance.Fail("an array of rows of numbers");
  for (size_t i = 0; i < covariance.Size(); ++i) {
    fit.covariance.push_back(covariance[i].NumbersOrNaN());
  }
  fit.chi2 = j["chi2"].NumberOrNaN();
  fit.dof = static_cast<int>(j["dof"].Integer());
  fit.reduced_chi2 = j["reduced_chi2"].NumberOrNaN();
  fit.covariance_scaled = j["covariance_scaled_by_reduced_chi2"].Bool();
  fit.residual_rms_deg = j["residual_rms_deg"].NumberOrNaN();
  fit.residuals_deg = j["residuals_deg"].NumbersOrNaN();
  return fit;
}

ReadingBudget ReadBudget(const JsonCursor& j, const std::string& name) {
  ReadingBudget b;
  b.name = name;
  GumResult& g = b.gum;
  g.u = j["u_deg"].NumberOrNaN();
  g.dof_eff = j["dof_eff"].NumberOrInfinity();
  g.k = j["k"].NumberOrNaN();
  g.expanded = j["U_deg"].NumberOrNaN();
  g.coverage = j["coverage"].NumberOrNaN();
  g.dof_note = j["dof_note"].String();
  const JsonCursor inputs = j["inputs"];
  if (!inputs.IsArray()) inputs.Fail("an array of budget inputs");
  for (size_t i = 0; i < inputs.Size(); ++i) {
    const JsonCursor in = inputs[i];
    BudgetLine line;
    line.name = in["name"].String();
    line.u = in["u_deg"].NumberOrNaN();
    line.distribution = in["distribution"].String();
    line.sensitivity = in["sensitivity"].NumberOrNaN();
    line.contribution = in["contribution_deg"].NumberOrNaN();
    line.dof = in["dof"].NumberOrInfinity();
    line.percent = in["percent"].NumberOrNaN();
    b.input_names.push_back(line.name);
    b.notes.push_back(in["note"].String());
    g.budget.push_back(line);
  }
  return b;
}

}  // namespace

AccuracyReport MakeAccuracyReport(const AccuracyResult& r, const Session& session,
                                  const Session* reference, const TagRegistry& tags) {
  AccuracyReport m;
  AccuracyReportInput& in = m.input;
  in.session = session.path;
  in.sha256 = session.sha256;
  in.format = SessionFormatName(session.format);
  in.sensor = r.sensor;
  in.table_axis = r.axis;
  in.quantity = r.quantity;
  const TagEntry* entry = tags.Find(r.sensor);
  AccuracyReportTag tag;
  const Tag* source = session.FindTag(r.sensor);
  tag.name = tags.Name(r.sensor, session.format, source != nullptr ? source->source_name : "");
  if (entry != nullptr && entry->device_id) tag.device_id = FormatDeviceIdText(*entry->device_id);
  in.tag = tag;
  if (reference != nullptr && r.alignment) {
    in.reference_log = AccuracyReferenceLog{reference->path, reference->sha256, *r.alignment};
    in.reference_log->alignment.reference_deg.clear();
  }
  const WindowOptions& w = r.options.window;
  m.window.skip_samples = w.skip_samples;
  m.window.skip_seconds = w.skip_seconds;
  m.window.from_s = w.from_s;
  m.window.to_s = w.to_s;
  m.window.n_total = static_cast<int64_t>(r.window.n_total);
  m.window.n = static_cast<int64_t>(r.window.n());
  m.window.t_first_s = r.window.t_first_s;
  m.window.t_last_s = r.window.t_last_s;
  m.options = r.options;
  const Segmentation& s = r.segmentation;
  AccuracyReportSegmentation& seg = m.segmentation;
  seg.plateaus = static_cast<int64_t>(s.plateaus.size());
  seg.excluded_samples = static_cast<int64_t>(s.motion_samples);
  seg.excluded_s = s.motion_s;
  seg.settle_samples = static_cast<int64_t>(s.settle_samples);
  for (const ExcludedSpan& e : s.excluded) {
    seg.excluded.push_back(
        {e.t_start_s, e.t_end_s, static_cast<int64_t>(e.end - e.begin), e.reason});
  }
  seg.lag_tau_s = r.lag_tau_s;
  seg.lag_method = r.lag_method;
  seg.lag_settled_plateaus = r.lag_settled_plateaus;
  seg.max_settle_s = r.max_settle_s;
  seg.reference_unwrapped = r.reference_unwrapped;
  seg.departure_trimmed_plateaus = s.departure_trimmed_plateaus;
  seg.departure_trimmed_samples = static_cast<int64_t>(s.departure_trimmed_samples);
  seg.max_end_trimmed_s = s.max_end_trimmed_s;
  seg.departure_kept_plateaus = s.departure_kept_plateaus;
  m.points = r.points;
  if (!r.cross_axis_available) {
    for (AccuracyPoint& p : m.points) {
      for (int k = 0; k < 2; ++k) {
        p.other_mean_deg[k] = std::numeric_limits<double>::quiet_NaN();
        p.other_u_deg[k] = std::numeric_limits<double>::quiet_NaN();
      }
    }
  }
  m.noise = r.noise;
  m.noise_method = kNoiseMethod;
  m.systematic = r.systematic;
  m.fit.model = r.model;
  m.fit.equation = kFitEquation;
  m.fit.hysteresis_term = r.fit_hysteresis_term;
  m.fit.order_rule = kErrorModelOrderRule;
  m.fit.weights = kFitWeights;
  m.fit.fit = r.fit;
  m.fit.max_prediction_u_deg = r.max_prediction_u_deg;
  m.linearity = r.linearity;
  m.hysteresis = r.hysteresis;
  m.repeatability = r.repeatability;
  m.cross_axis_available = r.cross_axis_available;
  m.cross_axis_note = r.cross_axis_note;
  for (int k = 0; k < 2; ++k) m.cross_axis[k] = r.cross_axis[k];
  m.corrected = r.corrected;
  m.uncorrected = r.uncorrected;
  AccuracyReportResult& result = m.result;
  result.U_random_deg = r.random_expanded_deg;
  result.U_uncorrected_max_abs_deg = r.uncorrected_max_abs_expanded_deg;
  result.U_uncorrected_gum_deg = r.uncorrected_gum_expanded_deg;
  result.which_u = r.which_u;
  result.statement_corrected =
      "a single " + r.quantity + " reading corrected by the fitted curve: error within " +
      Statement(r.corrected.gum.expanded, r.corrected.gum.k, r.corrected.gum.coverage);
  result.statement_uncorrected =
      "a single uncorrected " + r.quantity + " reading: error within " +
      Statement(r.uncorrected.gum.expanded, r.uncorrected.gum.k, r.uncorrected.gum.coverage) +
      fmt::format("; bound U(random) + max|e| = {} deg", U2(r.uncorrected_max_abs_expanded_deg));
  m.warnings = r.warnings;
  return m;
}

Json AccuracyOptionsToJsonValue(const AccuracyOptions& o) {
  return {{"plateau_tolerance_deg", o.plateaus.tolerance_deg},
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
}

Json ToJsonValue(const AccuracyReport& m) {
  Json j;
  j["schema"] = kAccuracyReportSchema;
  const AccuracyReportInput& in = m.input;
  Json input = {{"session", in.session},
                {"sha256", in.sha256},
                {"format", in.format},
                {"sensor", in.sensor},
                {"table_axis", TableAxisName(in.table_axis)},
                {"quantity", in.quantity}};
  if (in.tag) {
    input["tag"] = {{"name", in.tag->name},
                    {"device_id", in.tag->device_id ? Json(*in.tag->device_id) : Json(nullptr)}};
  }
  if (in.reference_log) {
    const Alignment& a = in.reference_log->alignment;
    input["reference"] = {{"file", in.reference_log->file},
                          {"sha256", in.reference_log->sha256},
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
  const AccuracyOptions& o = m.options;
  const AccuracyReportWindow& w = m.window;
  j["window"] = {{"skip_samples", w.skip_samples},
                 {"skip_seconds", w.skip_seconds},
                 {"from_s", w.from_s ? Json(*w.from_s) : Json()},
                 {"to_s", w.to_s ? Json(*w.to_s) : Json()},
                 {"n_total", w.n_total},
                 {"n", w.n},
                 {"t_first_s", w.t_first_s},
                 {"t_last_s", w.t_last_s}};
  j["options"] = AccuracyOptionsToJsonValue(o);
  const AccuracyReportSegmentation& s = m.segmentation;
  Json excluded = Json::array();
  for (const AccuracyExcludedSpan& e : s.excluded) {
    excluded.push_back({{"t_start_s", e.t_start_s},
                        {"t_end_s", e.t_end_s},
                        {"samples", e.samples},
                        {"reason", e.reason}});
  }
  j["segmentation"] = {{"plateaus", s.plateaus},
                       {"excluded_samples", s.excluded_samples},
                       {"excluded_s", s.excluded_s},
                       {"settle_samples", s.settle_samples},
                       {"excluded", excluded},
                       {"lag_tau_s", s.lag_tau_s},
                       {"lag_method", s.lag_method},
                       {"lag_settled_plateaus", s.lag_settled_plateaus},
                       {"max_settle_s", s.max_settle_s},
                       {"reference_unwrapped", s.reference_unwrapped},
                       {"departure_trimmed_plateaus", s.departure_trimmed_plateaus},
                       {"departure_trimmed_samples", s.departure_trimmed_samples},
                       {"max_end_trimmed_s", s.max_end_trimmed_s},
                       {"departure_kept_plateaus", s.departure_kept_plateaus}};
  Json points = Json::array();
  for (const AccuracyPoint& p : m.points) {
    Json other, other_u;
    for (int k = 0; k < 2; ++k) {
      other[m.cross_axis[k].quantity] =
          m.cross_axis_available ? Json(p.other_mean_deg[k]) : Json(nullptr);
      other_u[m.cross_axis[k].quantity] =
          m.cross_axis_available ? Json(p.other_u_deg[k]) : Json(nullptr);
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
  j["noise"] = {{"sigma_deg", m.noise.sigma_deg},
                {"phi_per_observation", m.noise.phi},
                {"dof", m.noise.dof},
                {"plateaus", m.noise.plateaus},
                {"method", m.noise_method}};
  const SystematicError& se = m.systematic;
  j["systematic"] = {{"mean_error_deg", se.mean_deg},
                     {"std_error_deg", se.std_deg},
                     {"rms_error_deg", se.rms_deg},
                     {"max_abs_error_deg", se.max_abs_deg},
                     {"at_reference_deg", se.at_reference_deg}};
  Json fit = {{"model", ErrorModelName(m.fit.model)},
              {"equation", m.fit.equation},
              {"hysteresis_term", m.fit.hysteresis_term},
              {"order_rule", m.fit.order_rule},
              {"weights", m.fit.weights}};
  fit.update(FitJson(m.fit.fit));
  fit["max_prediction_u_deg"] = m.fit.max_prediction_u_deg;
  j["fit"] = fit;
  const Linearity& l = m.linearity;
  j["linearity"] = {{"max_abs_deviation_deg", l.max_abs_deviation_deg},
                    {"at_reference_deg", l.at_reference_deg},
                    {"rms_deviation_deg", l.rms_deviation_deg},
                    {"percent_of_span", l.percent_of_span},
                    {"line_offset_deg", l.line_offset_deg},
                    {"line_slope", l.line_slope},
                    {"angles", l.angles},
                    {"u_max_abs_deviation_deg", l.u_max_abs_deviation_deg}};
  const Hysteresis& h = m.hysteresis;
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
  const Repeatability& rp = m.repeatability;
  j["repeatability"] = {{"available", rp.available},
                        {"s_r_deg", rp.available ? Json(rp.s_r_deg) : Json(nullptr)},
                        {"dof", rp.dof},
                        {"u_s_r_deg", rp.available ? Json(rp.u_s_r_deg) : Json(nullptr)},
                        {"groups", rp.groups},
                        {"sweeps", rp.sweeps},
                        {"note", rp.note}};
  Json cross;
  for (const CrossAxis& x : m.cross_axis) {
    if (!m.cross_axis_available) {
      cross[x.quantity] = {{"evaluated", false},
                           {"mean_deg", nullptr},
                           {"span_deg", nullptr},
                           {"fitted", false},
                           {"note", m.cross_axis_note}};
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
  j["budget"] = {{"corrected", BudgetJson(m.corrected)},
                 {"uncorrected", BudgetJson(m.uncorrected)}};
  const AccuracyReportResult& r = m.result;
  j["result"] = {{"ok", true},
                 {"U_corrected_deg", m.corrected.gum.expanded},
                 {"k_corrected", m.corrected.gum.k},
                 {"U_uncorrected_deg", m.uncorrected.gum.expanded},
                 {"k_uncorrected", m.uncorrected.gum.k},
                 {"U_random_deg", r.U_random_deg},
                 {"U_uncorrected_max_abs_deg", r.U_uncorrected_max_abs_deg},
                 {"U_uncorrected_gum_deg", r.U_uncorrected_gum_deg},
                 {"which_U_to_quote", r.which_u},
                 {"coverage", m.corrected.gum.coverage},
                 {"statement_corrected", r.statement_corrected},
                 {"statement_uncorrected", r.statement_uncorrected}};
  j["warnings"] = m.warnings;
  return j;
}

AccuracyReport AccuracyReportFromJsonValue(const JsonCursor& j) {
  AccuracyReport m;
  if (!j.IsObject()) {
    j.Fail(fmt::format("a {} object", kAccuracyReportSchema));
    return m;
  }
  if (j["schema"].String() != kAccuracyReportSchema && j.ok()) {
    j["schema"].Fail(fmt::format("\"{}\"", kAccuracyReportSchema));
  }
  const JsonCursor input = j["input"];
  AccuracyReportInput& in = m.input;
  in.session = input["session"].String();
  in.sha256 = input["sha256"].String();
  in.format = input["format"].String();
  in.sensor = input["sensor"].Integer();
  const JsonCursor axis = input["table_axis"];
  Result<TableAxis> table_axis = ParseTableAxis(axis.String());
  if (table_axis.ok()) {
    in.table_axis = table_axis.value();
  } else if (axis.ok()) {
    axis.Fail("one of \"yaw\", \"pitch\", \"roll\"");
  }
  in.quantity = input["quantity"].String();
  if (input.Has("tag")) {
    AccuracyReportTag tag;
    tag.name = input["tag"]["name"].String();
    tag.device_id = input["tag"]["device_id"].OptionalString();
    in.tag = tag;
  }
  const JsonCursor reference = input["reference"];
  if (!reference["file"].IsNull()) {
    AccuracyReferenceLog log;
    log.file = reference["file"].String();
    log.sha256 = reference["sha256"].String();
    const JsonCursor a = reference["alignment"];
    Alignment& al = log.alignment;
    al.method = a["method"].String();
    al.estimated = a["estimated"].Bool();
    al.offset_s = a["offset_s"].NumberOrNaN();
    al.residual_std_deg = a["residual_std_deg"].NumberOrNaN();
    al.residual_std_at_zero_deg = a["residual_std_at_zero_offset_deg"].NumberOrNaN();
    al.overlap_samples = ReadCount<size_t>(a["overlap_samples"]);
    al.outside_samples = ReadCount<size_t>(a["outside_samples"]);
    ReadPair(a["tag_t_s"], &al.tag_t_first_s, &al.tag_t_last_s);
    ReadPair(a["reference_t_s"], &al.reference_t_first_s, &al.reference_t_last_s);
    al.delay_s = a["delay_s"].NumberOrNaN();
    al.lag_modelled = a["lag_modelled"].Bool();
    if (al.lag_modelled) al.lag_tau_s = a["lag_tau_s"].NumberOrNaN();
    in.reference_log = std::move(log);
  } else if (reference["column"].String() != "table_angle_deg" && reference.ok()) {
    reference["column"].Fail("\"table_angle_deg\"");
  }
  const JsonCursor window = j["window"];
  AccuracyReportWindow& w = m.window;
  w.skip_samples = window["skip_samples"].Integer();
  w.skip_seconds = window["skip_seconds"].Number();
  w.from_s = window["from_s"].OptionalNumber();
  w.to_s = window["to_s"].OptionalNumber();
  w.n_total = window["n_total"].Integer();
  w.n = window["n"].Integer();
  w.t_first_s = window["t_first_s"].NumberOrNaN();
  w.t_last_s = window["t_last_s"].NumberOrNaN();
  const JsonCursor options = j["options"];
  AccuracyOptions& o = m.options;
  o.axis = in.table_axis;
  o.sensor = static_cast<int>(in.sensor);
  o.window.skip_samples = w.skip_samples;
  o.window.skip_seconds = w.skip_seconds;
  o.window.from_s = w.from_s;
  o.window.to_s = w.to_s;
  o.plateaus.tolerance_deg = options["plateau_tolerance_deg"].Number();
  o.plateaus.min_dwell_s = options["min_dwell_s"].Number();
  o.plateaus.min_samples = ReadCount<size_t>(options["min_samples"]);
  o.plateaus.settle_s = options["settle_s"].Number();
  const JsonCursor settle = options["settle"];
  const std::string settle_name = settle.String();
  if (settle_name != "auto" && settle_name != "none" && settle.ok()) {
    settle.Fail("\"auto\" or \"none\"");
  }
  o.plateaus.settle_auto = settle_name == "auto";
  o.angle_match_deg = options["angle_match_deg"].Number();
  o.model = ReadErrorModel(options["model"]);
  o.resolution_deg = options["resolution_deg"].Number();
  o.reference.u_deg = options["reference_u_deg"].Number();
  o.reference.dof = options["reference_dof"].NumberOrInfinity();
  o.reference.source = options["reference_u_source"].String();
  o.coverage = options["coverage"].Number();
  o.assumed_hysteresis_deg = options["assumed_hysteresis_deg"].Number();
  o.model_lag = options["model_lag"].Bool();
  o.lag_tau_s = options["lag_tau_s"].OptionalNumber();
  o.plateaus.settle_lag_residual_deg = options["settle_lag_residual_deg"].Number();
  o.plateaus.trim_departures = options["trim_departures"].Bool();
  o.plateaus.departure_sigmas = options["departure_sigmas"].Number();
  const JsonCursor segmentation = j["segmentation"];
  AccuracyReportSegmentation& seg = m.segmentation;
  seg.plateaus = segmentation["plateaus"].Integer();
  seg.excluded_samples = segmentation["excluded_samples"].Integer();
  seg.excluded_s = segmentation["excluded_s"].NumberOrNaN();
  seg.settle_samples = segmentation["settle_samples"].Integer();
  const JsonCursor excluded = segmentation["excluded"];
  if (!excluded.IsArray()) excluded.Fail("an array of excluded spans");
  for (size_t i = 0; i < excluded.Size(); ++i) {
    const JsonCursor e = excluded[i];
    seg.excluded.push_back({e["t_start_s"].NumberOrNaN(), e["t_end_s"].NumberOrNaN(),
                            e["samples"].Integer(), e["reason"].String()});
  }
  seg.lag_tau_s = segmentation["lag_tau_s"].NumberOrNaN();
  seg.lag_method = segmentation["lag_method"].String();
  seg.lag_settled_plateaus = segmentation["lag_settled_plateaus"].Integer();
  seg.max_settle_s = segmentation["max_settle_s"].NumberOrNaN();
  seg.reference_unwrapped = segmentation["reference_unwrapped"].Bool();
  seg.departure_trimmed_plateaus = segmentation["departure_trimmed_plateaus"].Integer();
  seg.departure_trimmed_samples = segmentation["departure_trimmed_samples"].Integer();
  seg.max_end_trimmed_s = segmentation["max_end_trimmed_s"].NumberOrNaN();
  seg.departure_kept_plateaus = segmentation["departure_kept_plateaus"].Integer();
  // The cross-axis quantities name the points' other-axis members, in this order.
  const JsonCursor cross = j["cross_axis"];
  const std::vector<std::string> cross_names = cross.Keys();
  if (cross.ok() && cross_names.size() != 2) {
    cross.Fail("an object with the 2 axes not turned (e.g. pitch_deg, roll_deg)");
  }
  for (size_t k = 0; k < 2 && k < cross_names.size(); ++k) {
    m.cross_axis[k].quantity = cross_names[k];
  }
  m.cross_axis_available = cross_names.empty() || cross[cross_names[0]]["evaluated"].Bool();
  const JsonCursor points = j["points"];
  if (!points.IsArray()) points.Fail("an array of plateau points");
  for (size_t i = 0; i < points.Size(); ++i) {
    const JsonCursor p = points[i];
    AccuracyPoint pt;
    pt.index = i;
    pt.reference_deg = p["reference_deg"].NumberOrNaN();
    pt.mean_deg = p["mean_deg"].NumberOrNaN();
    pt.error_deg = p["error_deg"].NumberOrNaN();
    const JsonCursor ta = p["type_a"];
    pt.type_a.n = ta["n"].Integer();
    pt.type_a.std_deg = ta["std_deg"].NumberOrNaN();
    pt.type_a.u_deg = ta["u_deg"].NumberOrNaN();
    pt.type_a.n_eff = ta["n_eff"].NumberOrNaN();
    pt.type_a.dof = ta["dof"].NumberOrInfinity();
    pt.direction = ReadDirection(p["direction"]);
    pt.sweep = static_cast<int>(p["sweep"].Integer());
    pt.t_start_s = p["t_start_s"].NumberOrNaN();
    pt.t_end_s = p["t_end_s"].NumberOrNaN();
    pt.settle_samples = ReadCount<size_t>(p["settle_samples"]);
    for (size_t k = 0; k < 2 && k < cross_names.size(); ++k) {
      pt.other_mean_deg[k] = p["other_axes_mean_deg"][cross_names[k]].NumberOrNaN();
      pt.other_u_deg[k] = p["other_axes_u_deg"][cross_names[k]].NumberOrNaN();
    }
    m.points.push_back(pt);
  }
  const JsonCursor noise = j["noise"];
  m.noise.sigma_deg = noise["sigma_deg"].NumberOrNaN();
  m.noise.phi = noise["phi_per_observation"].NumberOrNaN();
  m.noise.dof = noise["dof"].NumberOrNaN();
  m.noise.plateaus = ReadCount<size_t>(noise["plateaus"]);
  m.noise_method = noise["method"].String();
  const JsonCursor systematic = j["systematic"];
  m.systematic.mean_deg = systematic["mean_error_deg"].NumberOrNaN();
  m.systematic.std_deg = systematic["std_error_deg"].NumberOrNaN();
  m.systematic.rms_deg = systematic["rms_error_deg"].NumberOrNaN();
  m.systematic.max_abs_deg = systematic["max_abs_error_deg"].NumberOrNaN();
  m.systematic.at_reference_deg = systematic["at_reference_deg"].NumberOrNaN();
  const JsonCursor fit = j["fit"];
  m.fit.model = ReadErrorModel(fit["model"]);
  m.fit.equation = fit["equation"].String();
  m.fit.hysteresis_term = fit["hysteresis_term"].Bool();
  m.fit.order_rule = fit["order_rule"].String();
  m.fit.weights = fit["weights"].String();
  m.fit.fit = ReadFit(fit);
  m.fit.max_prediction_u_deg = fit["max_prediction_u_deg"].NumberOrNaN();
  const JsonCursor linearity = j["linearity"];
  Linearity& l = m.linearity;
  l.max_abs_deviation_deg = linearity["max_abs_deviation_deg"].NumberOrNaN();
  l.at_reference_deg = linearity["at_reference_deg"].NumberOrNaN();
  l.rms_deviation_deg = linearity["rms_deviation_deg"].NumberOrNaN();
  l.percent_of_span = linearity["percent_of_span"].NumberOrNaN();
  l.line_offset_deg = linearity["line_offset_deg"].NumberOrNaN();
  l.line_slope = linearity["line_slope"].NumberOrNaN();
  l.angles = ReadCount<size_t>(linearity["angles"]);
  l.u_max_abs_deviation_deg = linearity["u_max_abs_deviation_deg"].NumberOrNaN();
  const JsonCursor hysteresis = j["hysteresis"];
  Hysteresis& h = m.hysteresis;
  h.available = hysteresis["available"].Bool();
  h.mean_deg = hysteresis["mean_deg"].NumberOrNaN();
  h.u_mean_deg = hysteresis["u_mean_deg"].NumberOrNaN();
  h.max_abs_deg = hysteresis["max_abs_deg"].NumberOrNaN();
  h.u_max_abs_deg = hysteresis["u_max_abs_deg"].NumberOrNaN();
  h.at_reference_deg = hysteresis["at_reference_deg"].NumberOrNaN();
  const JsonCursor pairs = hysteresis["pairs"];
  if (!pairs.IsArray()) pairs.Fail("an array of up/down pairs");
  for (size_t i = 0; i < pairs.Size(); ++i) {
    const JsonCursor p = pairs[i];
    HysteresisPair pair;
    pair.reference_deg = p["reference_deg"].NumberOrNaN();
    pair.up_error_deg = p["up_error_deg"].NumberOrNaN();
    pair.down_error_deg = p["down_error_deg"].NumberOrNaN();
    pair.hysteresis_deg = p["hysteresis_deg"].NumberOrNaN();
    pair.u_deg = p["u_deg"].NumberOrNaN();
    pair.dof = p["dof"].NumberOrInfinity();
    pair.up_count = static_cast<int>(p["up_plateaus"].Integer());
    pair.down_count = static_cast<int>(p["down_plateaus"].Integer());
    h.pairs.push_back(pair);
  }
  h.note = hysteresis["note"].String();
  const JsonCursor repeatability = j["repeatability"];
  Repeatability& rp = m.repeatability;
  rp.available = repeatability["available"].Bool();
  rp.s_r_deg = repeatability["s_r_deg"].NumberOrNaN();
  rp.dof = repeatability["dof"].NumberOrNaN();
  rp.u_s_r_deg = repeatability["u_s_r_deg"].NumberOrNaN();
  rp.groups = static_cast<int>(repeatability["groups"].Integer());
  rp.sweeps = static_cast<int>(repeatability["sweeps"].Integer());
  rp.note = repeatability["note"].String();
  for (size_t k = 0; k < 2 && k < cross_names.size(); ++k) {
    const JsonCursor c = cross[cross_names[k]];
    CrossAxis& x = m.cross_axis[k];
    if (!m.cross_axis_available) {
      m.cross_axis_note = c["note"].String();
      continue;
    }
    x.mean_deg = c["mean_deg"].NumberOrNaN();
    x.span_deg = c["span_deg"].NumberOrNaN();
    x.fitted = c["fitted"].Bool();
    if (x.fitted) {
      x.amplitude_deg = c["amplitude_deg"].NumberOrNaN();
      x.u_amplitude_deg = c["u_amplitude_deg"].NumberOrNaN();
      x.fit = ReadFit(c["fit"]);
    }
  }
  if (!j["budget"].IsObject()) j["budget"].Fail("an object {corrected, uncorrected}");
  m.corrected = ReadBudget(j["budget"]["corrected"], "corrected");
  m.uncorrected = ReadBudget(j["budget"]["uncorrected"], "uncorrected");
  const JsonCursor result = j["result"];
  AccuracyReportResult& r = m.result;
  r.U_random_deg = result["U_random_deg"].NumberOrNaN();
  r.U_uncorrected_max_abs_deg = result["U_uncorrected_max_abs_deg"].NumberOrNaN();
  r.U_uncorrected_gum_deg = result["U_uncorrected_gum_deg"].NumberOrNaN();
  r.which_u = result["which_U_to_quote"].String();
  r.statement_corrected = result["statement_corrected"].String();
  r.statement_uncorrected = result["statement_uncorrected"].String();
  m.warnings = j["warnings"].Strings();
  return m;
}

std::string ToJson(const AccuracyReport& report) { return JsonText(ToJsonValue(report), 2); }

Result<AccuracyReport> AccuracyReportFromJson(std::string_view text, const std::string& file) {
  return ReadJsonText<AccuracyReport>(text, file, AccuracyReportFromJsonValue);
}

std::string AccuracyReportTable(const AccuracyReport& m) {
  std::string out;
  auto it = std::back_inserter(out);
  fmt::format_to(it, "Accuracy of tag {} {} against the table ({} axis), {} plateaus\n",
                 m.input.sensor, m.input.quantity, TableAxisName(m.input.table_axis),
                 m.points.size());
  if (m.input.reference_log) {
    fmt::format_to(it, "reference log aligned: offset {:.4f} s ({}), residual std {:.4g} deg\n",
                   m.input.reference_log->alignment.offset_s,
                   m.input.reference_log->alignment.estimated ? "estimated" : "given",
                   m.input.reference_log->alignment.residual_std_deg);
  }
  fmt::format_to(it, "{:>4} {:>12} {:>12} {:>10} {:>9} {:>8} {:>6}\n", "#", "reference_deg",
                 "mean_deg", "error_deg", "u_deg", "n_eff", "dir");
  for (const AccuracyPoint& p : m.points) {
    fmt::format_to(it, "{:>4} {:>12.4f} {:>12.4f} {:>10.4f} {:>9.5f} {:>8.1f} {:>6}\n", p.index,
                   p.reference_deg, p.mean_deg, p.error_deg, p.type_a.u_deg, p.type_a.n_eff,
                   DirectionName(p.direction));
  }
  fmt::format_to(it,
                 "systematic: mean {:.4f} deg, RMS {:.4f} deg, max |e| {:.4f} deg at {:.6g} deg\n",
                 m.systematic.mean_deg, m.systematic.rms_deg, m.systematic.max_abs_deg,
                 m.systematic.at_reference_deg);
  fmt::format_to(it, "fit ({}, chi2/nu {:.3g}{}):", ErrorModelName(m.fit.model),
                 m.fit.fit.reduced_chi2, m.fit.fit.covariance_scaled ? ", covariance scaled" : "");
  for (size_t i = 0; i < m.fit.fit.terms.size(); ++i) {
    fmt::format_to(it, " {} = {:.5g} +- {:.2g}", ErrorTermName(m.fit.fit.terms[i]),
                   m.fit.fit.params[i], m.fit.fit.u[i]);
  }
  out += '\n';
  fmt::format_to(it,
                 "linearity: max deviation {:.4f} +- {:.4f} deg at {:.6g} deg ({:.3g} % of span)\n",
                 m.linearity.max_abs_deviation_deg, m.linearity.u_max_abs_deviation_deg,
                 m.linearity.at_reference_deg, m.linearity.percent_of_span);
  if (m.hysteresis.available) {
    fmt::format_to(it, "hysteresis (up - down): mean {:.4f} +- {:.4f} deg, max |h| {:.4f} deg\n",
                   m.hysteresis.mean_deg, m.hysteresis.u_mean_deg, m.hysteresis.max_abs_deg);
  } else {
    fmt::format_to(it, "hysteresis: {}\n", m.hysteresis.note);
  }
  if (m.repeatability.available) {
    fmt::format_to(it, "repeatability: s_r {:.4f} deg (dof {:.0f})\n", m.repeatability.s_r_deg,
                   m.repeatability.dof);
  } else {
    fmt::format_to(it, "repeatability: {}\n", m.repeatability.note);
  }
  if (!m.cross_axis_available) out += "cross-axis: " + m.cross_axis_note + "\n";
  for (const CrossAxis& x : m.cross_axis) {
    if (!m.cross_axis_available) break;
    fmt::format_to(it, "cross-axis {}: span {:.4f} deg", x.quantity, x.span_deg);
    if (x.fitted) {
      fmt::format_to(it, ", first harmonic {:.4f} +- {:.4f} deg", x.amplitude_deg,
                     x.u_amplitude_deg);
    }
    out += '\n';
  }
  fmt::format_to(it, "single reading, corrected:   U = {} deg (k = {:.3g}, nu_eff = {:.3g})\n",
                 U2(m.corrected.gum.expanded), m.corrected.gum.k, m.corrected.gum.dof_eff);
  fmt::format_to(
      it, "single reading, uncorrected: U = {} deg (k = {:.3g}); U(random) + max|e| = {} deg\n",
      U2(m.uncorrected.gum.expanded), m.uncorrected.gum.k, U2(m.result.U_uncorrected_max_abs_deg));
  for (const std::string& w : m.warnings) out += "warning: " + w + "\n";
  return out;
}

}  // namespace metro
