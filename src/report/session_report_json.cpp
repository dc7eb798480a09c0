#include "session_report_json.hpp"

#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "core/json_text.hpp"
#include "noise/allan_report_json.hpp"
#include "plot_data_json.hpp"
#include "report/spec_decision_json.hpp"
#include "uncertainty/budget_report_json.hpp"

namespace metro {
namespace {

using Json = nlohmann::ordered_json;

Json Null() { return Json(nullptr); }

// NaN (and an infinity) is null in a report: in the text nlohmann writes it so anyway, and in
// the value too, so a reader of the value sees what a reader of the file sees.
void NullNonFinite(Json* j) {
  if (j->is_number_float()) {
    if (!std::isfinite(j->get<double>())) *j = nullptr;
  } else if (j->is_structured()) {
    for (Json& v : *j) NullNonFinite(&v);
  }
}

template <typename T>
Json OrNull(const std::optional<T>& v) {
  return v ? Json(*v) : Null();
}

// ---------------------------------------------------------------------------------------
// input

Json ToJsonValue(const ReportInput& in) {
  Json j;
  j["path"] = in.path;
  j["sha256"] = in.sha256;
  j["format"] = in.format;
  j["rows"] = in.rows;
  j["rejected_rows"] = in.rejected_rows;
  Json rejected = Json::array();
  for (const RejectedRow& r : in.rejected) {
    rejected.push_back({{"line", r.line}, {"reason", r.reason}});
  }
  j["rejected"] = rejected;
  j["columns"] = in.columns;
  j["unknown_columns"] = in.unknown_columns;
  if (in.frame_period_s) j["frame_period_s"] = *in.frame_period_s;
  if (in.dialect) {
    const ReportDialect& d = *in.dialect;
    j["dialect"] = {{"delimiter", d.delimiter}, {"decimal_point", d.decimal_point},
                    {"line_ends", d.line_ends}, {"bom", d.bom},
                    {"quoted", d.quoted},       {"header_in_comment", d.header_in_comment}};
  }
  if (in.mapping) {
    Json mapping = Json::array();
    for (const ReportColumnMapping& m : *in.mapping) {
      mapping.push_back({{"source", m.source}, {"canonical", m.canonical}});
    }
    j["mapping"] = mapping;
  }
  if (in.time) {
    const ReportTime& t = *in.time;
    Json time = {{"source", t.source}, {"unit", t.unit}, {"integer", t.integer}};
    if (t.origin_ns) time["origin_ns"] = *t.origin_ns;
    if (t.rate_hz) time["rate_hz"] = *t.rate_hz;
    if (t.resolution_s) time["resolution_s"] = *t.resolution_s;
    j["time"] = time;
  }
  if (in.raw_full_scale) {
    j["raw_full_scale"] = {{"accel_fs_g", in.raw_full_scale->accel_fs_g},
                           {"gyro_fs_dps", in.raw_full_scale->gyro_fs_dps}};
  }
  if (!in.notes.empty()) j["notes"] = in.notes;
  if (!in.warnings.empty()) j["warnings"] = in.warnings;
  return j;
}

ReportInput InputFromJsonValue(const JsonCursor& c) {
  ReportInput in;
  in.path = c["path"].String();
  in.sha256 = c["sha256"].String();
  in.format = c["format"].String();
  in.rows = c["rows"].Integer();
  in.rejected_rows = c["rejected_rows"].Integer();
  const JsonCursor rejected = c["rejected"];
  if (!rejected.IsArray()) rejected.Fail("an array");
  for (size_t i = 0; i < rejected.Size(); ++i) {
    in.rejected.push_back({rejected[i]["line"].Integer(), rejected[i]["reason"].String()});
  }
  in.columns = c["columns"].Strings();
  in.unknown_columns = c["unknown_columns"].Strings();
  in.frame_period_s = c["frame_period_s"].OptionalNumber();
  if (c.Has("dialect")) {
    const JsonCursor d = c["dialect"];
    ReportDialect dialect;
    dialect.delimiter = d["delimiter"].String();
    dialect.decimal_point = d["decimal_point"].String();
    dialect.line_ends = d["line_ends"].String();
    dialect.bom = d["bom"].Bool();
    dialect.quoted = d["quoted"].Bool();
    dialect.header_in_comment = d["header_in_comment"].Bool();
    in.dialect = dialect;
  }
  if (c.Has("mapping")) {
    const JsonCursor m = c["mapping"];
    if (!m.IsArray()) m.Fail("an array");
    std::vector<ReportColumnMapping> mapping;
    for (size_t i = 0; i < m.Size(); ++i) {
      mapping.push_back({m[i]["source"].String(), m[i]["canonical"].String()});
    }
    in.mapping = std::move(mapping);
  }
  if (c.Has("time")) {
    const JsonCursor t = c["time"];
    ReportTime time;
    time.source = t["source"].String();
    time.unit = t["unit"].String();
    time.integer = t["integer"].Bool();
    time.origin_ns = t["origin_ns"].OptionalInteger();
    time.rate_hz = t["rate_hz"].OptionalNumber();
    time.resolution_s = t["resolution_s"].OptionalNumber();
    in.time = time;
  }
  if (c.Has("raw_full_scale")) {
    const JsonCursor f = c["raw_full_scale"];
    in.raw_full_scale = ReportRawFullScale{f["accel_fs_g"].Number(), f["gyro_fs_dps"].Number()};
  }
  if (c.Has("notes")) in.notes = c["notes"].Strings();
  if (c.Has("warnings")) in.warnings = c["warnings"].Strings();
  return in;
}

// ---------------------------------------------------------------------------------------
// options

Json ToJsonValue(const SessionReportOptions& o) {
  Json j = {{"skip_samples", o.skip_samples},
            {"skip_seconds", o.skip_seconds},
            {"from_s", o.from_s},
            {"to_s", o.to_s},
            {"settle", o.settle},
            {"sensors", o.sensors},
            {"quantities", o.quantities},
            {"autocorrelation",
             {{"method", o.autocorrelation.method},
              {"band_confidence", o.autocorrelation.band_confidence},
              {"max_lag_fraction", o.autocorrelation.max_lag_fraction}}}};
  if (o.settle_scope) j["settle_scope"] = *o.settle_scope;
  return j;
}

SessionReportOptions OptionsFromJsonValue(const JsonCursor& c) {
  SessionReportOptions o;
  o.skip_samples = c["skip_samples"].Integer();
  o.skip_seconds = c["skip_seconds"].Number();
  o.from_s = c["from_s"].NumberOrNaN();
  o.to_s = c["to_s"].NumberOrNaN();
  o.settle = c["settle"].String();
  o.sensors = c["sensors"].Integers();
  o.quantities = c["quantities"].Strings();
  const JsonCursor a = c["autocorrelation"];
  o.autocorrelation.method = a["method"].String();
  o.autocorrelation.band_confidence = a["band_confidence"].Number();
  o.autocorrelation.max_lag_fraction = a["max_lag_fraction"].Number();
  o.settle_scope = c["settle_scope"].OptionalString();
  return o;
}

// ---------------------------------------------------------------------------------------
// sensors

Json ToJsonValue(const ReportWindow& w) {
  Json j = {{"n_total", w.n_total},
            {"n", w.n},
            {"first_index", w.first_index},
            {"end_index", w.end_index},
            {"t_first_s", w.t_first_s},
            {"t_last_s", w.t_last_s},
            {"first_line", OrNull(w.first_line)},
            {"last_line", OrNull(w.last_line)}};
  if (w.settle) {
    const ReportWindowSettle& s = *w.settle;
    Json settle = {{"method", s.method}, {"samples", s.samples}, {"at_limit", s.at_limit}};
    if (s.scope) {
      settle["scope"] = *s.scope;
      settle["driver"] = OrNull(s.driver);
    }
    j["settle"] = settle;
  }
  return j;
}

ReportWindow WindowFromJsonValue(const JsonCursor& c) {
  ReportWindow w;
  w.n_total = c["n_total"].Integer();
  w.n = c["n"].Integer();
  w.first_index = c["first_index"].Integer();
  w.end_index = c["end_index"].Integer();
  w.t_first_s = c["t_first_s"].NumberOrNaN();
  w.t_last_s = c["t_last_s"].NumberOrNaN();
  w.first_line = c["first_line"].OptionalInteger();
  w.last_line = c["last_line"].OptionalInteger();
  if (c.Has("settle")) {
    const JsonCursor s = c["settle"];
    ReportWindowSettle settle;
    settle.method = s["method"].String();
    settle.samples = s["samples"].Integer();
    settle.at_limit = s["at_limit"].Bool();
    settle.scope = s["scope"].OptionalString();
    settle.driver = s["driver"].OptionalString();
    w.settle = settle;
  }
  return w;
}

Json ToJsonValue(const TypeAReport& a) {
  Json j = {{"n", a.n},
            {"mean", a.mean},
            {"variance", a.variance},
            {"std", a.std},
            {"variance_of_mean", a.variance_of_mean},
            {"std_of_mean", a.std_of_mean},
            {"dof", a.dof},
            {"n_eff", a.n_eff},
            {"std_of_mean_autocorr", a.std_of_mean_autocorr},
            {"autocorr_cutoff_lag", OrNull(a.autocorr_cutoff_lag)},
            {"rho1", a.rho1}};
  if (a.has_autocorr_note) j["autocorr_note"] = OrNull(a.autocorr_note);
  if (a.has_u_mean) {
    j["u_mean"] = a.u_mean;
    j["u_mean_dof"] = a.u_mean_dof;
    j["u_mean_method"] = OrNull(a.u_mean_method);
    j["u_mean_ar_order"] = OrNull(a.u_mean_ar_order);
  }
  if (a.coverage) {
    j["coverage"] = *a.coverage;
    j["k"] = a.k;
    j["U_mean"] = a.U_mean;
  }
  return j;
}

TypeAReport TypeAFromJsonValue(const JsonCursor& c) {
  TypeAReport a;
  a.n = c["n"].Integer();
  a.mean = c["mean"].NumberOrNaN();
  a.variance = c["variance"].NumberOrNaN();
  a.std = c["std"].NumberOrNaN();
  a.variance_of_mean = c["variance_of_mean"].NumberOrNaN();
  a.std_of_mean = c["std_of_mean"].NumberOrNaN();
  a.dof = c["dof"].Integer();
  a.n_eff = c["n_eff"].NumberOrNaN();
  a.std_of_mean_autocorr = c["std_of_mean_autocorr"].NumberOrNaN();
  a.autocorr_cutoff_lag = c["autocorr_cutoff_lag"].OptionalInteger();
  a.rho1 = c["rho1"].NumberOrNaN();
  a.has_autocorr_note = c.Has("autocorr_note");
  a.autocorr_note = c["autocorr_note"].OptionalString();
  // Reports written before metro stated u_mean (and then coverage, k, U_mean) lack the keys.
  a.has_u_mean = c.Has("u_mean");
  if (a.has_u_mean) {
    a.u_mean = c["u_mean"].NumberOrNaN();
    a.u_mean_dof = c["u_mean_dof"].NumberOrNaN();
    a.u_mean_method = c["u_mean_method"].OptionalString();
    a.u_mean_ar_order = c["u_mean_ar_order"].OptionalInteger();
  }
  if (c.Has("coverage")) {
    a.coverage = c["coverage"].Number();
    a.k = c["k"].NumberOrNaN();
    a.U_mean = c["U_mean"].NumberOrNaN();
  }
  return a;
}

Json ToJsonValue(const QuantitySettle& s) {
  Json j = {
      {"method", s.method}, {"samples", s.samples}, {"at_limit", s.at_limit}, {"fitted", s.fitted}};
  if (s.fitted) {
    j["significant"] = s.significant;
    j["tau_samples"] = s.tau_samples;
    j["tau_s"] = s.tau_s;
    j["amplitude"] = s.amplitude;
    j["amplitude_over_u"] = s.amplitude_over_u;
    j["u_mean_residual"] = s.u_mean_residual;
    j["bias_over_u_uncut"] = s.bias_over_u_uncut;
    j["bias_over_u_kept"] = s.bias_over_u_kept;
  } else {
    j["note"] = s.note;
  }
  return j;
}

QuantitySettle SettleFromJsonValue(const JsonCursor& c) {
  QuantitySettle s;
  s.method = c["method"].String();
  s.samples = c["samples"].Integer();
  s.at_limit = c["at_limit"].Bool();
  s.fitted = c["fitted"].Bool();
  if (s.fitted) {
    s.significant = c["significant"].Bool();
    s.tau_samples = c["tau_samples"].NumberOrNaN();
    s.tau_s = c["tau_s"].NumberOrNaN();
    s.amplitude = c["amplitude"].NumberOrNaN();
    s.amplitude_over_u = c["amplitude_over_u"].NumberOrNaN();
    s.u_mean_residual = c["u_mean_residual"].NumberOrNaN();
    s.bias_over_u_uncut = c["bias_over_u_uncut"].NumberOrNaN();
    s.bias_over_u_kept = c["bias_over_u_kept"].NumberOrNaN();
  } else {
    s.note = c["note"].String();
  }
  return s;
}

Json ToJsonValue(const QuantityReport& q) {
  Json j;
  j["unit"] = q.unit;
  j["origin"] = q.origin;
  j["angle_handling"] = q.angle_handling;
  if (q.unwrap_jumps) j["unwrap_jumps"] = *q.unwrap_jumps;
  if (q.type_a) {
    j["type_a"] = ToJsonValue(*q.type_a);
  } else {
    j["type_a"] = nullptr;
    j["error"] = q.error;
  }
  if (q.settle_samples) j["settle_samples"] = *q.settle_samples;
  j["warnings"] = q.warnings;
  if (q.window_first_index) {
    j["window_first_index"] = *q.window_first_index;
    j["t_first_s"] = q.t_first_s;
  }
  if (q.settle) j["settle"] = ToJsonValue(*q.settle);
  if (q.allan) j["allan"] = ToJsonValue(*q.allan);
  if (q.allan_type_a_link) j["allan_type_a_link"] = ToJsonValue(*q.allan_type_a_link);
  if (q.plot) j["plot"] = PlotDataToJsonValue(*q.plot);
  return j;
}

QuantityReport QuantityFromJsonValue(const std::string& name, const JsonCursor& c) {
  QuantityReport q;
  q.name = name;
  q.unit = c["unit"].String();
  q.origin = c["origin"].String();
  q.angle_handling = c["angle_handling"].String();
  q.unwrap_jumps = c["unwrap_jumps"].OptionalInteger();
  const JsonCursor type_a = c["type_a"];
  if (type_a.IsNull()) {
    q.error = c["error"].String();
  } else {
    q.type_a = TypeAFromJsonValue(type_a);
  }
  q.settle_samples = c["settle_samples"].OptionalInteger();
  q.warnings = c["warnings"].Strings();
  q.window_first_index = c["window_first_index"].OptionalInteger();
  if (q.window_first_index) q.t_first_s = c["t_first_s"].NumberOrNaN();
  if (c.Has("settle")) q.settle = SettleFromJsonValue(c["settle"]);
  if (c.Has("allan")) q.allan = AllanReportFromJsonValue(c["allan"]);
  if (c.Has("allan_type_a_link")) {
    q.allan_type_a_link = AllanTypeALinkFromJsonValue(c["allan_type_a_link"]);
  }
  // Reports written before metro kept plot data have none.
  if (c.Has("plot")) q.plot = PlotDataFromJsonValue(c["plot"]);
  return q;
}

Json ToJsonValue(const SensorReport& s) {
  Json j;
  j["sensor"] = s.sensor;
  j["name"] = s.name;
  j["frames"] = s.frames;
  j["fresh"] = s.fresh;
  j["stale"] = s.stale;
  j["never"] = s.never;
  j["packet_loss_ratio"] = s.packet_loss_ratio;
  j["window"] = ToJsonValue(s.window);
  Json quantities = Json::object();
  // Appended without a lookup (operator[] of an ordered object is a linear search): a tag's
  // quantity names are unique.
  for (const QuantityReport& q : s.quantities) {
    quantities.get_ref<Json::object_t&>().emplace_back(q.name, ToJsonValue(q));
  }
  j["quantities"] = std::move(quantities);
  j["warnings"] = s.warnings;
  return j;
}

SensorReport SensorFromJsonValue(const JsonCursor& c) {
  SensorReport s;
  s.sensor = c["sensor"].Integer();
  s.name = c["name"].String();
  s.frames = c["frames"].Integer();
  s.fresh = c["fresh"].Integer();
  s.stale = c["stale"].Integer();
  s.never = c["never"].Integer();
  s.packet_loss_ratio = c["packet_loss_ratio"].NumberOrNaN();
  s.window = WindowFromJsonValue(c["window"]);
  const JsonCursor quantities = c["quantities"];
  for (const std::string& name : quantities.Keys()) {
    s.quantities.push_back(QuantityFromJsonValue(name, quantities[name]));
  }
  s.warnings = c["warnings"].Strings();
  return s;
}

}  // namespace

Json ToJsonValue(const SessionReport& report) {
  Json j;
  j["schema"] = report.schema;
  j["tool"] = {{"name", report.tool.name}, {"version", report.tool.version}};
  j["input"] = ToJsonValue(report.input);
  j["options"] = ToJsonValue(report.options);
  Json sensors = Json::array();
  for (const SensorReport& s : report.sensors) sensors.push_back(ToJsonValue(s));
  j["sensors"] = std::move(sensors);
  if (report.allan_skipped) j["allan_skipped"] = *report.allan_skipped;
  if (report.budget) j["budget"] = ToJsonValue(*report.budget);
  if (report.spec) j["spec"] = SpecDecisionsJson(*report.spec);
  NullNonFinite(&j);
  return j;
}

SessionReport SessionReportFromJsonValue(const JsonCursor& c) {
  SessionReport r;
  if (!c.IsObject()) {
    c.Fail("a metro.report/1 object");
    return r;
  }
  const JsonCursor schema = c["schema"];
  r.schema = schema.String();
  if (schema.IsString() && r.schema != kReportSchema) {
    schema.Fail(std::string("\"") + kReportSchema + "\"");
    return r;
  }
  const JsonCursor tool = c["tool"];
  r.tool.name = tool["name"].String();
  r.tool.version = tool["version"].String();
  r.input = InputFromJsonValue(c["input"]);
  r.options = OptionsFromJsonValue(c["options"]);
  const JsonCursor sensors = c["sensors"];
  if (!sensors.IsArray()) sensors.Fail("an array");
  for (size_t i = 0; i < sensors.Size(); ++i) r.sensors.push_back(SensorFromJsonValue(sensors[i]));
  r.allan_skipped = c["allan_skipped"].OptionalString();
  if (c.Has("budget")) r.budget = BudgetReportFromJsonValue(c["budget"]);
  return r;
}

std::string ToJson(const SessionReport& report) { return JsonText(ToJsonValue(report), 2); }

Result<SessionReport> SessionReportFromJson(std::string_view text, const std::string& file) {
  return ReadJsonText<SessionReport>(text, file, SessionReportFromJsonValue);
}

}  // namespace metro
