#include "metro/report/type_a_report.hpp"

#include <fmt/format.h>

#include "mean_coverage.hpp"
#include "metro/core/rounding.hpp"
#include "metro/core/version.hpp"
#include "metro/report/allan_section.hpp"
#include "metro/report/console_text.hpp"

namespace metro {
namespace {

const char* OriginName(QuantityOrigin origin) {
  switch (origin) {
    case QuantityOrigin::kFile:
      return "file";
    case QuantityOrigin::kDerived:
      return "derived";
    case QuantityOrigin::kUnknown:
      return "unknown_column";
  }
  return "?";
}

nlohmann::ordered_json OptionalNumber(const std::optional<double>& v) {
  return v ? nlohmann::ordered_json(*v) : nlohmann::ordered_json(nullptr);
}

// What the loader applied to a text file (docs/report-schema.md, "input"): enough to read
// the file again the same way (html_report's reload) and to see that nothing was guessed.
void AddInputDialect(const InputDialect& d, nlohmann::ordered_json* input) {
  using json = nlohmann::ordered_json;
  (*input)["dialect"] = {{"delimiter", std::string(1, d.delimiter)},
                         {"decimal_point", std::string(1, d.decimal_point)},
                         {"line_ends", d.line_ends},
                         {"bom", d.bom},
                         {"quoted", d.quoted},
                         {"header_in_comment", d.header_in_comment}};
  json mapping = json::array();
  for (const ColumnMapping& m : d.mapping) {
    mapping.push_back({{"source", m.source}, {"canonical", m.canonical}});
  }
  (*input)["mapping"] = mapping;
  json time = {{"source", d.time_source}, {"unit", d.time_unit}, {"integer", d.time_integer}};
  if (d.time_integer) time["origin_ns"] = d.time_origin_ns;
  if (d.rate_hz > 0.0) time["rate_hz"] = d.rate_hz;
  if (d.time_resolution_s > 0.0) time["resolution_s"] = d.time_resolution_s;
  (*input)["time"] = time;
  if (d.accel_fs_g > 0.0 || d.gyro_fs_dps > 0.0) {
    (*input)["raw_full_scale"] = {{"accel_fs_g", d.accel_fs_g}, {"gyro_fs_dps", d.gyro_fs_dps}};
  }
}

}  // namespace

nlohmann::ordered_json TypeAReportJson(const Session& session, const SessionTypeA& result,
                                       const SessionTypeAOptions& options,
                                       const TagRegistry& registry) {
  using json = nlohmann::ordered_json;
  json report;
  report["schema"] = kReportSchema;
  report["tool"] = {{"name", kToolName}, {"version", kVersion}};
  json input;
  input["path"] = session.path;
  input["sha256"] = session.sha256;
  input["format"] = SessionFormatName(session.format);
  input["rows"] = session.rows;
  input["rejected_rows"] = session.rejected_rows;
  json rejected = json::array();
  for (size_t i = 0; i < session.rejected_lines.size(); ++i) {
    rejected.push_back(
        {{"line", session.rejected_lines[i]}, {"reason", session.rejected_reasons[i]}});
  }
  input["rejected"] = rejected;
  input["columns"] = session.columns;
  input["unknown_columns"] = session.unknown_columns;
  if (session.format == SessionFormat::kReceiver) {
    input["frame_period_s"] = session.frame_period_s;
  } else {
    AddInputDialect(session.input, &input);
  }
  if (!session.input.notes.empty()) input["notes"] = session.input.notes;
  if (!session.input.warnings.empty()) input["warnings"] = session.input.warnings;
  report["input"] = input;

  const WindowOptions& w = options.window;
  report["options"] = {
      {"skip_samples", w.skip_samples},
      {"skip_seconds", w.skip_seconds},
      {"from_s", OptionalNumber(w.from_s)},
      {"to_s", OptionalNumber(w.to_s)},
      {"settle", w.settle_auto ? "auto" : "none"},
      {"sensors", options.sensors},
      {"quantities", options.quantities},
      {"autocorrelation",
       {{"method", "Zhang 2006, Bartlett band, first lag inside the band ends the sum"},
        {"band_confidence", options.type_a.band_confidence},
        {"max_lag_fraction", options.type_a.max_lag_fraction}}}};

  json sensors = json::array();
  for (const TagTypeA& t : result.tags) {
    json s;
    s["sensor"] = t.sensor;
    s["name"] = registry.Name(t.sensor);
    s["frames"] = t.counts.frames;
    s["fresh"] = t.counts.fresh;
    s["stale"] = t.counts.stale;
    s["never"] = t.counts.never;
    s["packet_loss_ratio"] = t.counts.PacketLossRatio();
    const AppliedWindow& a = t.window;
    json window = {{"n_total", a.n_total},
                   {"n", a.n()},
                   {"first_index", a.begin},
                   {"end_index", a.end},
                   {"t_first_s", a.n() ? json(a.t_first_s) : json(nullptr)},
                   {"t_last_s", a.n() ? json(a.t_last_s) : json(nullptr)},
                   {"first_line", a.n() ? json(a.first_line) : json(nullptr)},
                   {"last_line", a.n() ? json(a.last_line) : json(nullptr)}};
    if (w.settle_auto) {
      window["settle"] = {
          {"method", "MSER-5"}, {"samples", a.settle_samples}, {"at_limit", a.settle_at_limit}};
    }
    s["window"] = window;
    json quantities = json::object();
    for (const QuantityTypeA& q : t.quantities) {
      json jq;
      jq["unit"] = q.unit;
      jq["origin"] = OriginName(q.origin);
      jq["angle_handling"] = q.angle_handling;
      if (q.angle_handling == "unwrapped") jq["unwrap_jumps"] = q.unwrap_jumps;
      if (q.ok) {
        const TypeAResult& r = q.type_a;
        // Terms that were not computed are null, with the reason (autocorr_note).
        const bool ac = r.autocorr_computed;
        const bool um = r.u_mean_available;
        jq["type_a"] = {{"n", r.n},
                        {"mean", r.mean},
                        {"variance", r.variance},
                        {"std", r.std},
                        {"variance_of_mean", r.variance_of_mean},
                        {"std_of_mean", r.std_of_mean},
                        {"dof", r.dof},
                        {"n_eff", ac ? json(r.n_eff) : json(nullptr)},
                        {"std_of_mean_autocorr", ac ? json(r.std_of_mean_autocorr) : json(nullptr)},
                        {"autocorr_cutoff_lag", ac ? json(r.cutoff_lag) : json(nullptr)},
                        {"rho1", ac ? json(r.rho1) : json(nullptr)},
                        {"autocorr_note", ac ? json(nullptr) : json(r.autocorr_note)},
                        {"u_mean", um ? json(r.u_mean) : json(nullptr)},
                        {"u_mean_dof", um ? json(r.u_mean_dof) : json(nullptr)},
                        {"u_mean_method", um ? json(r.u_mean_method) : json(nullptr)},
                        {"u_mean_ar_order",
                         r.u_mean_method == kUMeanArSpectral ? json(r.ar_order) : json(nullptr)}};
        report_internal::SetMeanCoverage(&jq["type_a"]);
      } else {
        jq["type_a"] = nullptr;
        jq["error"] = q.error;
      }
      if (w.settle_auto) jq["settle_samples"] = q.settle_samples;
      jq["warnings"] = q.warnings;
      // Appended without a lookup (operator[] of an ordered object is a linear search): a
      // tag's quantity names are unique.
      quantities.get_ref<json::object_t&>().emplace_back(q.name, std::move(jq));
    }
    s["quantities"] = quantities;
    s["warnings"] = t.warnings;
    sensors.push_back(s);
  }
  report["sensors"] = sensors;
  return report;
}

std::string TypeAReportTable(const nlohmann::ordered_json& report) {
  std::string out;
  auto it = std::back_inserter(out);
  fmt::format_to(it, "{} ({}, {} rows, {} rejected)\n", report["input"]["path"].get<std::string>(),
                 report["input"]["format"].get<std::string>(),
                 report["input"]["rows"].get<int64_t>(),
                 report["input"]["rejected_rows"].get<int64_t>());
  if (report["input"].contains("notes")) {
    for (const auto& note : report["input"]["notes"]) {
      fmt::format_to(it, "  note: {}\n", note.get<std::string>());
    }
  }
  fmt::format_to(it, "{:>6} {:<16} {:<18} {:<6} {:>8} {:>14} {:>10} {:>10} {:>10} {:>10}\n",
                 "sensor", "name", "quantity", "unit", "n", "mean", "s", "s(mean)", "n_eff",
                 "u(mean)");
  for (const auto& s : report["sensors"]) {
    const int sensor = s["sensor"].get<int>();
    const std::string name = s["name"].get<std::string>();
    if (s["quantities"].empty()) {
      fmt::format_to(it, "{:>6} {:<16} (no observations: frames {}, stale {}, never {})\n", sensor,
                     name, s["frames"].get<int64_t>(), s["stale"].get<int64_t>(),
                     s["never"].get<int64_t>());
    }
    for (const auto& [qname, q] : s["quantities"].items()) {
      // The unit as the report states it ("1" for the quaternion's dimensionless components).
      std::string unit = q.contains("unit") && q["unit"].is_string() ? q["unit"].get<std::string>()
                                                                     : std::string();
      if (unit.empty()) unit = "1";
      if (q["type_a"].is_null()) {
        fmt::format_to(it, "{:>6} {:<16} {:<18} {:<6} {}\n", sensor, name, qname, unit,
                       q["error"].get<std::string>());
        continue;
      }
      const auto& a = q["type_a"];
      // GUM 7.2.6: mean rounded to u_mean, metro's recommended u(mean) (2 significant
      // digits); a report written before u_mean existed has std_of_mean_autocorr.
      const char* u_key = a.contains("u_mean") ? "u_mean" : "std_of_mean_autocorr";
      const std::string n_eff =
          a["n_eff"].is_number() ? fmt::format("{:.1f}", a["n_eff"].get<double>()) : "-";
      std::string value, uncertainty = "-";
      if (a[u_key].is_number()) {
        const RoundedResult r = RoundForTable(a["mean"].get<double>(), a[u_key].get<double>());
        value = r.value;
        uncertainty = r.uncertainty;
      } else {
        value = fmt::format("{:.6g}", a["mean"].get<double>());
      }
      fmt::format_to(it,
                     "{:>6} {:<16} {:<18} {:<6} {:>8} {:>14} {:>10.3g} {:>10.2g} {:>10} {:>10}\n",
                     sensor, name, qname, unit, a["n"].get<int64_t>(), value,
                     a["std"].get<double>(), a["std_of_mean"].get<double>(), n_eff, uncertainty);
    }
  }
  out += AllanSummaryTable(report);
  out += TypeAReportWarnings(report);
  return out;
}

std::string TypeAReportWarnings(const nlohmann::ordered_json& report) {
  std::vector<WarningLine> lines;
  if (report["input"].contains("warnings")) {
    for (const auto& wmsg : report["input"]["warnings"]) {
      lines.push_back({"input", wmsg.get<std::string>()});
    }
  }
  for (const auto& s : report["sensors"]) {
    const std::string sensor = fmt::format("sensor {}", s["sensor"].get<int>());
    for (const auto& wmsg : s["warnings"]) lines.push_back({sensor, wmsg.get<std::string>()});
    for (const auto& [qname, q] : s["quantities"].items()) {
      for (const auto& wmsg : q["warnings"]) {
        lines.push_back({sensor + " " + qname, wmsg.get<std::string>()});
      }
    }
  }
  // Near-identical warnings (the same message but for its numbers) are grouped with a count.
  if (lines.empty()) return {};
  return "\nwarnings:\n" + GroupedWarnings(lines);
}

}  // namespace metro
