#include "metro/report/type_a_report.hpp"

#include <fmt/format.h>

#include <cmath>
#include <iterator>
#include <utility>
#include <vector>

#include "mean_coverage.hpp"
#include "metro/core/rounding.hpp"
#include "metro/core/terminal_text.hpp"
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

// What the loader applied to a text file (docs/report-schema.md, "input"): enough to see
// that nothing was guessed.
void AddInputDialect(const InputDialect& d, ReportInput* input) {
  input->dialect = ReportDialect{
      std::string(1, d.delimiter), std::string(1, d.decimal_point), d.line_ends, d.bom, d.quoted,
      d.header_in_comment};
  std::vector<ReportColumnMapping> mapping;
  for (const ColumnMapping& m : d.mapping) mapping.push_back({m.source, m.canonical});
  input->mapping = std::move(mapping);
  ReportTime time;
  time.source = d.time_source;
  time.unit = d.time_unit;
  time.integer = d.time_integer;
  if (d.time_integer) time.origin_ns = d.time_origin_ns;
  if (d.rate_hz > 0.0) time.rate_hz = d.rate_hz;
  if (d.time_resolution_s > 0.0) time.resolution_s = d.time_resolution_s;
  input->time = time;
  if (d.accel_fs_g > 0.0 || d.gyro_fs_dps > 0.0) {
    input->raw_full_scale = ReportRawFullScale{d.accel_fs_g, d.gyro_fs_dps};
  }
}

ReportInput MakeInput(const Session& session) {
  ReportInput input;
  input.path = session.path;
  input.sha256 = session.sha256;
  input.format = SessionFormatName(session.format);
  input.rows = session.rows;
  input.rejected_rows = session.rejected_rows;
  for (size_t i = 0; i < session.rejected_lines.size(); ++i) {
    input.rejected.push_back({session.rejected_lines[i], session.rejected_reasons[i]});
  }
  input.columns = session.columns;
  input.unknown_columns = session.unknown_columns;
  if (session.format == SessionFormat::kReceiver) {
    input.frame_period_s = session.frame_period_s;
  } else {
    AddInputDialect(session.input, &input);
  }
  if (IsBinaryLogFormat(session.format)) {
    // A binary log: no delimiter, line ends or header to report, only its time.
    input.dialect.reset();
    input.mapping.reset();
  }
  input.notes = session.input.notes;
  input.warnings = session.input.warnings;
  return input;
}

TypeAReport MakeTypeA(const TypeAResult& r) {
  TypeAReport a;
  a.n = r.n;
  a.mean = r.mean;
  a.variance = r.variance;
  a.std = r.std;
  a.variance_of_mean = r.variance_of_mean;
  a.std_of_mean = r.std_of_mean;
  a.dof = r.dof;
  // Terms that were not computed are null, with the reason (autocorr_note).
  if (r.autocorr_computed) {
    a.n_eff = r.n_eff;
    a.std_of_mean_autocorr = r.std_of_mean_autocorr;
    a.autocorr_cutoff_lag = r.cutoff_lag;
    a.rho1 = r.rho1;
  } else {
    a.autocorr_note = r.autocorr_note;
  }
  if (r.u_mean_available) {
    a.u_mean = r.u_mean;
    a.u_mean_dof = r.u_mean_dof;
    a.u_mean_method = r.u_mean_method;
  }
  if (r.u_mean_method == kUMeanArSpectral) a.u_mean_ar_order = r.ar_order;
  report_internal::SetMeanCoverage(&a);
  return a;
}

}  // namespace

SessionReport MakeSessionReport(const Session& session, const SessionTypeA& result,
                                const SessionTypeAOptions& options, const TagRegistry& registry) {
  SessionReport report;
  report.tool = ReportTool{kToolName, kVersion};
  report.input = MakeInput(session);

  const WindowOptions& w = options.window;
  SessionReportOptions& o = report.options;
  o.skip_samples = w.skip_samples;
  o.skip_seconds = w.skip_seconds;
  o.from_s = w.from_s ? *w.from_s : std::nan("");
  o.to_s = w.to_s ? *w.to_s : std::nan("");
  o.settle = w.settle_auto ? "auto" : "none";
  o.sensors.assign(options.sensors.begin(), options.sensors.end());
  o.quantities = options.quantities;
  o.autocorrelation = {"Zhang 2006, Bartlett band, first lag inside the band ends the sum",
                       options.type_a.band_confidence, options.type_a.max_lag_fraction};

  for (const TagTypeA& t : result.tags) {
    SensorReport s;
    s.sensor = t.sensor;
    const Tag* tag = session.FindTag(t.sensor);
    s.name = registry.Name(t.sensor, session.format, tag != nullptr ? tag->source_name : "");
    s.frames = t.counts.frames;
    s.fresh = t.counts.fresh;
    s.stale = t.counts.stale;
    s.never = t.counts.never;
    s.packet_loss_ratio = t.counts.PacketLossRatio();
    const AppliedWindow& a = t.window;
    s.window.n_total = static_cast<int64_t>(a.n_total);
    s.window.n = static_cast<int64_t>(a.n());
    s.window.first_index = static_cast<int64_t>(a.begin);
    s.window.end_index = static_cast<int64_t>(a.end);
    if (a.n() > 0) {
      s.window.t_first_s = a.t_first_s;
      s.window.t_last_s = a.t_last_s;
      s.window.first_line = a.first_line;
      s.window.last_line = a.last_line;
    }
    if (w.settle_auto) {
      s.window.settle = ReportWindowSettle{
          "MSER-5", static_cast<int64_t>(a.settle_samples), a.settle_at_limit, {}, {}};
    }
    for (const QuantityTypeA& q : t.quantities) {
      QuantityReport jq;
      jq.name = q.name;
      jq.unit = q.unit;
      jq.origin = OriginName(q.origin);
      jq.angle_handling = q.angle_handling;
      if (q.angle_handling == "unwrapped") jq.unwrap_jumps = q.unwrap_jumps;
      if (q.ok) {
        jq.type_a = MakeTypeA(q.type_a);
      } else {
        jq.error = q.error;
      }
      if (w.settle_auto) jq.settle_samples = static_cast<int64_t>(q.settle_samples);
      jq.warnings = q.warnings;
      s.quantities.push_back(std::move(jq));
    }
    s.warnings = t.warnings;
    report.sensors.push_back(std::move(s));
  }
  return report;
}

std::string TypeAReportTable(const SessionReport& report) {
  std::string out;
  auto it = std::back_inserter(out);
  // One record per line: names, units, paths and notes are data, their control characters
  // escaped (a tag named "Chest\nsensor 3 ..." must not print a row of its own).
  const auto text = [](const std::string& data) { return EscapeControlChars(data); };
  fmt::format_to(it, "{} ({}, {} rows, {} rejected)\n", text(report.input.path),
                 report.input.format, report.input.rows, report.input.rejected_rows);
  for (const std::string& note : report.input.notes) {
    fmt::format_to(it, "  note: {}\n", text(note));
  }
  fmt::format_to(it, "{:>6} {:<16} {:<18} {:<6} {:>8} {:>14} {:>10} {:>10} {:>10} {:>10}\n",
                 "sensor", "name", "quantity", "unit", "n", "mean", "s", "s(mean)", "n_eff",
                 "u(mean)");
  for (const SensorReport& s : report.sensors) {
    if (s.quantities.empty()) {
      fmt::format_to(it, "{:>6} {:<16} (no observations: frames {}, stale {}, never {})\n",
                     s.sensor, text(s.name), s.frames, s.stale, s.never);
    }
    const std::string name = text(s.name);
    for (const QuantityReport& q : s.quantities) {
      // The unit as the report states it ("1" for the quaternion's dimensionless components).
      const std::string unit = text(q.unit.empty() ? "1" : q.unit);
      const std::string quantity = text(q.name);
      if (!q.type_a) {
        fmt::format_to(it, "{:>6} {:<16} {:<18} {:<6} {}\n", s.sensor, name, quantity, unit,
                       text(q.error));
        continue;
      }
      const TypeAReport& a = *q.type_a;
      // GUM 7.2.6: mean rounded to u_mean, metro's recommended u(mean) (2 significant
      // digits); a report written before u_mean existed has std_of_mean_autocorr.
      const double u = a.has_u_mean ? a.u_mean : a.std_of_mean_autocorr;
      const std::string n_eff = std::isfinite(a.n_eff) ? fmt::format("{:.1f}", a.n_eff) : "-";
      std::string value, uncertainty = "-";
      if (std::isfinite(u)) {
        const RoundedResult r = RoundForTable(a.mean, u);
        value = r.value;
        uncertainty = r.uncertainty;
      } else {
        value = fmt::format("{:.6g}", a.mean);
      }
      fmt::format_to(
          it, "{:>6} {:<16} {:<18} {:<6} {:>8} {:>14} {:>10.3g} {:>10.2g} {:>10} {:>10}\n",
          s.sensor, name, quantity, unit, a.n, value, a.std, a.std_of_mean, n_eff, uncertainty);
    }
  }
  out += AllanSummaryTable(report);
  out += TypeAReportWarnings(report);
  return out;
}

std::string TypeAReportWarnings(const SessionReport& report) {
  std::vector<WarningLine> lines;
  for (const std::string& w : report.input.warnings) lines.push_back({"input", w});
  for (const SensorReport& s : report.sensors) {
    const std::string sensor = fmt::format("sensor {}", s.sensor);
    for (const std::string& w : s.warnings) lines.push_back({sensor, w});
    for (const QuantityReport& q : s.quantities) {
      for (const std::string& w : q.warnings) lines.push_back({sensor + " " + q.name, w});
    }
  }
  // Near-identical warnings (the same message but for its numbers) are grouped with a count.
  if (lines.empty()) return {};
  return "\nwarnings:\n" + GroupedWarnings(lines);
}

}  // namespace metro
