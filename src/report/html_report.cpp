#include "metro/report/html_report.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <filesystem>
#include <utility>

#include "accuracy_view.hpp"
#include "budget_view.hpp"
#include "html_common.hpp"
#include "html_templates.hpp"
#include "metro/calibration/calibration_io.hpp"
#include "metro/core/file.hpp"
#include "metro/core/json_text.hpp"
#include "metro/io/session_io.hpp"
#include "metro/report/batch.hpp"
#include "metro/report/batch_page.hpp"
#include "metro/report/budget_page.hpp"
#include "metro/report/certificate.hpp"
#include "metro/report/type_a_report.hpp"
#include "session_plots.hpp"
#include "session_tables.hpp"

namespace metro {

using nlohmann::ordered_json;
namespace mustache = kainjow::mustache;
using report_internal::AddAllanGroupPlots;
using report_internal::AddAllanPlot;
using report_internal::AddSeriesPlots;
using report_internal::JsonNumber;
using report_internal::JsonString;
using report_internal::NoiseRows;
using report_internal::OptionRows;
using report_internal::QuantityPlots;
using report_internal::ResultRows;
using report_internal::ShortNumber;
using report_internal::TypeADetailRows;

namespace {

bool IsQuaternionComponent(const std::string& name) {
  return name == "qw" || name == "qx" || name == "qy" || name == "qz";
}

std::string SettleText(const ordered_json& window) {
  if (!window.contains("settle")) return "none";
  const ordered_json& s = window["settle"];
  // `driver`: the quantity whose cut the tag window takes (each quantity has its own).
  const std::string driver = s.contains("driver") && s["driver"].is_string()
                                 ? fmt::format(", the cut of {}", s["driver"].get<std::string>())
                                 : "";
  return fmt::format("{}: {} samples{}{}", JsonString(s, "method"),
                     ShortNumber(JsonNumber(s, "samples"), 10), driver,
                     s.value("at_limit", false) ? " (at the limit)" : "");
}

// How the file was read (the report's input.dialect, mapping and time), in words: empty for
// a receiver capture, which has none of them.
std::string DialectText(const ordered_json& input) {
  if (!input.contains("dialect") || !input["dialect"].is_object()) return "";
  const ordered_json& d = input["dialect"];
  const std::string delimiter = JsonString(d, "delimiter");
  std::string text = delimiter == "\t"  ? "tab-separated"
                     : delimiter == ";" ? "semicolon-separated"
                     : delimiter == "," ? "comma-separated"
                                        : fmt::format("separated by {}", delimiter);
  if (JsonString(d, "decimal_point") == ",") text += ", decimal comma";
  text += fmt::format(", {} line ends", JsonString(d, "line_ends"));
  if (d.value("bom", false)) text += ", UTF-8 byte-order mark";
  if (d.value("quoted", false)) text += ", quoted fields";
  if (d.value("header_in_comment", false)) text += ", header in a '#' comment";
  return text;
}

std::string MappingText(const ordered_json& input) {
  if (!input.contains("mapping") || !input["mapping"].is_array()) return "";
  std::string text;
  for (const ordered_json& m : input["mapping"]) {
    const std::string canonical = JsonString(m, "canonical");
    text += fmt::format("{}{} \u2192 {}", text.empty() ? "" : "; ", JsonString(m, "source"),
                        canonical.empty() ? "(left out)" : canonical);
  }
  return text;
}

std::string TimeText(const ordered_json& input) {
  if (!input.contains("time") || !input["time"].is_object()) return "";
  const ordered_json& t = input["time"];
  const std::string source = JsonString(t, "source");
  std::string text = t.contains("rate_hz")
                         ? fmt::format("none in the file: sample i at i / {} Hz",
                                       ShortNumber(JsonNumber(t, "rate_hz"), 10))
                         : fmt::format("column {} in {}", source, JsonString(t, "unit"));
  if (t.value("integer", false)) {
    text += fmt::format(", integer (exact), origin {} ns",
                        t.contains("origin_ns") ? JsonText(t["origin_ns"]) : "0");
  }
  if (t.contains("resolution_s")) {
    text +=
        fmt::format(", resolution {} s as written", ShortNumber(JsonNumber(t, "resolution_s"), 3));
  }
  return text;
}

mustache::data StringList(const ordered_json& j, const char* key) {
  mustache::data list{mustache::data::type::list};
  if (j.contains(key) && j[key].is_array()) {
    for (const auto& v : j[key])
      list.push_back(mustache::data(v.is_string() ? v.get<std::string>() : JsonText(v)));
  }
  return list;
}

Status ValidateReport(const ordered_json& report) {
  if (!report.is_object() || report.value("schema", "") != kReportSchema) {
    return MakeError(
        fmt::format("not a {} report (schema key missing or different)", kReportSchema));
  }
  for (const char* key : {"input", "sensors"}) {
    if (!report.contains(key)) {
      return MakeError(fmt::format("{} report: missing key '{}'", kReportSchema, key));
    }
  }
  if (!report["sensors"].is_array()) {
    return MakeError(fmt::format("{} report: 'sensors' is not an array", kReportSchema));
  }
  return Status::Ok();
}

}  // namespace

bool HtmlReportOptions::IsValid(std::string* why) const {
  if (max_plotted_quantities < 0) {
    *why = "html: max_plotted_quantities must be >= 0";
    return false;
  }
  if (max_series_points < 16) {
    *why = "html: max_series_points must be >= 16";
    return false;
  }
  if (histogram_bins < 0 || histogram_bins > 1000) {
    *why = "html: histogram_bins must be in 0..1000";
    return false;
  }
  if (max_autocorr_lag < 2) {
    *why = "html: max_autocorr_lag must be >= 2";
    return false;
  }
  return true;
}

Result<std::string> RenderSessionReportHtml(const ordered_json& report, const Session* session,
                                            const std::string& session_note,
                                            const HtmlReportOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) return MakeError(why);
  if (Status s = ValidateReport(report); !s.ok()) return s.error();
  const ordered_json& input = report["input"];
  mustache::data data;
  // The result first, then how it was obtained.
  data.set("result_rows", ResultRows(report));
  data.set("summary_rows", TypeADetailRows(report));
  mustache::data noise = NoiseRows(report);
  data.set("has_noise", !noise.is_empty_list());
  data.set("noise_rows", noise);
  data.set("input_path", JsonString(input, "path"));
  data.set("input_sha256", JsonString(input, "sha256"));
  data.set("input_format", JsonString(input, "format"));
  data.set("input_rows", ShortNumber(JsonNumber(input, "rows"), 12));
  data.set("input_rejected_rows", ShortNumber(JsonNumber(input, "rejected_rows"), 12));
  // Each row only when the report has it (a receiver capture has no dialect, a canonical
  // file no mapping): a missing value renders no section.
  for (const auto& [key, text] :
       {std::pair{"input_dialect", DialectText(input)},
        std::pair{"input_mapping", MappingText(input)}, std::pair{"input_time", TimeText(input)}}) {
    if (!text.empty()) data.set(key, text);
  }
  data.set("input_notes", StringList(input, "notes"));
  data.set("input_warnings", StringList(input, "warnings"));
  mustache::data option_rows =
      report.contains("options") ? OptionRows(report["options"]) : mustache::data::type::list;
  data.set("has_options", !option_rows.is_empty_list());
  data.set("option_rows", option_rows);
  data.set("session_ok", session != nullptr);
  data.set("session_note", session_note);

  mustache::data sensors{mustache::data::type::list};
  int plotted = 0;
  int not_plotted = 0;
  for (const ordered_json& s : report["sensors"]) {
    const int sensor = static_cast<int>(JsonNumber(s, "sensor"));
    const std::string tag_name = JsonString(s, "name");
    const Tag* tag = session != nullptr ? session->FindTag(sensor) : nullptr;
    mustache::data sd;
    sd.set("sensor", std::to_string(sensor));
    sd.set("tag", tag_name);
    sd.set("frames", ShortNumber(JsonNumber(s, "frames"), 12));
    sd.set("fresh", ShortNumber(JsonNumber(s, "fresh"), 12));
    sd.set("stale", ShortNumber(JsonNumber(s, "stale"), 12));
    sd.set("loss", fmt::format("{:.2f} %", 100.0 * JsonNumber(s, "packet_loss_ratio")));
    const ordered_json empty = ordered_json::object();
    const ordered_json& window = s.contains("window") ? s["window"] : empty;
    sd.set("n", ShortNumber(JsonNumber(window, "n"), 12));
    sd.set("n_total", ShortNumber(JsonNumber(window, "n_total"), 12));
    sd.set("t_first_s", ShortNumber(JsonNumber(window, "t_first_s"), 6));
    sd.set("t_last_s", ShortNumber(JsonNumber(window, "t_last_s"), 6));
    sd.set("settle", SettleText(window));
    sd.set("warnings", StringList(s, "warnings"));
    QuantityPlots groups;
    AddAllanGroupPlots(s, &groups);
    sd.set("has_allan_groups",
           !groups.plots.is_empty_list() || !groups.unavailable.is_empty_list());
    sd.set("allan_group_plots", groups.plots);
    sd.set("allan_group_unavailable", groups.unavailable);
    mustache::data quantities{mustache::data::type::list};
    if (s.contains("quantities") && s["quantities"].is_object()) {
      for (const auto& [qname, q] : s["quantities"].items()) {
        const bool evaluated = q.contains("type_a") && q["type_a"].is_object();
        const bool wanted =
            options.plot_quantities.empty()
                ? !IsQuaternionComponent(qname)
                : std::find(options.plot_quantities.begin(), options.plot_quantities.end(),
                            qname) != options.plot_quantities.end();
        if (!evaluated || !wanted) continue;
        if (plotted >= options.max_plotted_quantities) {
          ++not_plotted;
          continue;
        }
        ++plotted;
        mustache::data qd;
        qd.set("sensor", std::to_string(sensor));
        qd.set("quantity", qname);
        qd.set("unit", JsonString(q, "unit"));
        qd.set("warnings", StringList(q, "warnings"));
        QuantityPlots plots;
        const Quantity* column = tag != nullptr ? tag->Find(qname) : nullptr;
        if (column != nullptr) {
          AddSeriesPlots(s, qname, q, *tag, *column, options, &plots);
        } else {
          plots.unavailable.push_back(mustache::data(fmt::format(
              "time series, histogram and autocorrelation of {}: unavailable ({})", qname,
              session == nullptr ? session_note : "the session has no such tag or column")));
        }
        mustache::data terms{mustache::data::type::list};
        if (q.contains("allan")) AddAllanPlot(qname, q, &plots, &terms);
        qd.set("has_allan_terms", !terms.is_empty_list());
        qd.set("allan_terms", terms);
        qd.set("plots", plots.plots);
        qd.set("unavailable", plots.unavailable);
        quantities.push_back(qd);
      }
    }
    sd.set("quantities", quantities);
    sensors.push_back(sd);
  }
  data.set("sensors", sensors);
  data.set("has_more_quantities", not_plotted > 0);
  data.set("more_quantities",
           fmt::format("{} more quantities are in the tables but not plotted (at most {} are "
                       "plotted).",
                       not_plotted, options.max_plotted_quantities));
  if (report.contains("budget")) {
    Result<mustache::data> budget = report_internal::BudgetViewData(report["budget"]);
    if (!budget.ok()) return budget.error();
    data.set("budget", budget.value());
  } else {
    data.set("budget", false);
  }
  Result<std::string> body = report_internal::RenderTemplate("session", std::move(data));
  if (!body.ok()) return body;
  const std::string file = std::filesystem::path(JsonString(input, "path")).filename().string();
  return report_internal::RenderPage(
      fmt::format("Session report: {}", file),
      fmt::format("{} (GUM Type A{}{}) - sha256 {}", kReportSchema,
                  report_internal::AnyAllan(report) ? ", Allan deviation" : "",
                  report.contains("budget") ? ", uncertainty budget" : "",
                  JsonString(input, "sha256").substr(0, 16)),
      body.value());
}

Result<std::string> RenderSessionAnalysisHtml(const SessionAnalysis& analysis,
                                              const HtmlReportOptions& options) {
  if (!analysis.ok) return MakeError("no HTML report of a failed analysis");
  return RenderSessionReportHtml(
      analysis.report, &analysis.session,
      fmt::format("Plots drawn from the session as analysed ({}).", analysis.session.path),
      options);
}

namespace {

// Reloads the report's session: `explicit_path`, or input.path as given and relative to the
// report's directory. Sets *note to what happened.
std::optional<Session> ReloadReportSession(const ordered_json& report, const std::string& json_path,
                                           const std::string& explicit_path, std::string* note) {
  const ordered_json& input = report["input"];
  const std::string path = JsonString(input, "path");
  const std::string sha256 = JsonString(input, "sha256");
  std::vector<std::string> candidates;
  if (!explicit_path.empty()) {
    candidates.push_back(explicit_path);
  } else if (!path.empty()) {
    candidates.push_back(path);
    const std::filesystem::path dir = std::filesystem::path(json_path).parent_path();
    if (std::filesystem::path(path).is_relative() && !dir.empty()) {
      candidates.push_back((dir / path).string());
    }
  }
  std::vector<std::string> reasons;
  for (const std::string& candidate : candidates) {
    Result<std::string> hash = Sha256File(candidate);
    if (!hash.ok()) {
      reasons.push_back(fmt::format("{}: cannot be read", candidate));
      continue;
    }
    if (hash.value() != sha256) {
      reasons.push_back(
          fmt::format("{}: its SHA-256 {} differs from the report's", candidate, hash.value()));
      continue;
    }
    LoadOptions load;
    if (!ParseSessionFormat(JsonString(input, "format"), &load.format)) {
      load.format = SessionFormat::kAuto;
    }
    // The same columns, time and scales as the report's load (type_a_report's "input").
    if (input.contains("mapping") && input["mapping"].is_array()) {
      for (const auto& m : input["mapping"]) {
        if (m.is_object() && m.value("source", ordered_json()).is_string() &&
            m.value("canonical", ordered_json()).is_string()) {
          load.column_map.push_back(
              {m["source"].get<std::string>(), m["canonical"].get<std::string>()});
        }
      }
    }
    if (input.contains("time") && input["time"].is_object()) {
      const double rate_hz = JsonNumber(input["time"], "rate_hz");
      if (std::isfinite(rate_hz) && rate_hz > 0.0) load.rate_hz = rate_hz;
    }
    if (input.contains("raw_full_scale") && input["raw_full_scale"].is_object()) {
      const double accel = JsonNumber(input["raw_full_scale"], "accel_fs_g");
      const double gyro = JsonNumber(input["raw_full_scale"], "gyro_fs_dps");
      if (std::isfinite(accel) && accel > 0.0) load.accel_fs_g = accel;
      if (std::isfinite(gyro) && gyro > 0.0) load.gyro_fs_dps = gyro;
    }
    load.lenient = JsonNumber(input, "rejected_rows") > 0;
    const double period = JsonNumber(input, "frame_period_s");
    if (std::isfinite(period) && period > 0.0) load.frame_period_s = period;
    load.threads = 1;
    Result<Session> session = LoadSession(candidate, load);
    if (!session.ok()) {
      reasons.push_back(session.error().ToString());
      continue;
    }
    *note = fmt::format(
        "Plots drawn from the session reloaded from {} (SHA-256 matches the "
        "report).",
        candidate);
    return std::move(session).value();
  }
  if (candidates.empty()) reasons.push_back("the report names no input file");
  std::string joined;
  for (const std::string& r : reasons) joined += (joined.empty() ? "" : "; ") + r;
  *note = fmt::format(
      "The session's raw data are not available ({}): the time series, histogram and "
      "autocorrelation plots need them and are omitted; tables, Allan curves and budget bars "
      "come from the JSON alone.",
      joined);
  return std::nullopt;
}

}  // namespace

Result<std::string> RenderJsonHtml(const ordered_json& document, const std::string& json_path,
                                   const std::string& session_path,
                                   const HtmlReportOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) return MakeError(why);
  const std::string schema =
      document.is_object() && document.contains("schema") && document["schema"].is_string()
          ? document["schema"].get<std::string>()
          : "";
  if (schema == kReportSchema) {
    if (Status s = ValidateReport(document); !s.ok()) {
      Error e = s.error();
      e.file = json_path;
      return e;
    }
    std::string note;
    std::optional<Session> session = ReloadReportSession(document, json_path, session_path, &note);
    return RenderSessionReportHtml(document, session ? &*session : nullptr, note, options);
  }
  if (schema == kCalibrationSchema) {
    // The document's text as metro writes it (indent 2), so positions match a file it wrote.
    Result<Calibration> cal = CalibrationFromJson(JsonText(document, 2), json_path);
    if (!cal.ok()) return cal.error();
    // The id of the file's own bytes: what `fit` printed and the registry recorded.
    CertificateOptions certificate;
    Result<std::string> sha = Sha256File(json_path);
    if (sha.ok()) certificate.certificate_id = sha.value().substr(0, 16);
    return RenderCalibrationCertificate(cal.value(), certificate);
  }
  if (schema == report_internal::kAccuracyReportSchema) {
    Result<std::string> html = report_internal::RenderAccuracyHtml(document, json_path);
    if (!html.ok() && html.error().file.empty()) {
      Error e = html.error();
      e.file = json_path;
      return e;
    }
    return html;
  }
  if (schema == kBudgetReportSchema) {
    Result<std::string> html = RenderBudgetReportHtml(document);
    if (!html.ok() && html.error().file.empty()) {
      Error e = html.error();
      e.file = json_path;
      return e;
    }
    return html;
  }
  if (schema == kBatchSummarySchema) {
    // The links are relative to the summary's folder, where batch wrote the session pages.
    Result<std::string> html = RenderBatchSummaryHtml(document);
    if (!html.ok() && html.error().file.empty()) {
      Error e = html.error();
      e.file = json_path;
      return e;
    }
    return html;
  }
  if (IsBudgetDefinition(document)) {
    return MakeError(json_path, 0,
                     "this is a budget definition (docs/budget-format.md), not a report: run "
                     "`characterize budget " +
                         json_path + " --html PAGE.html` to evaluate it and write its page");
  }
  return report_internal::RenderGenericHtml(document, json_path, schema);
}

Result<std::string> RenderJsonFileHtml(const std::string& json_path,
                                       const std::string& session_path,
                                       const HtmlReportOptions& options) {
  Result<std::string> text = ReadFile(json_path);
  if (!text.ok()) return text.error();
  Result<ordered_json> document = ParseOrderedJsonText(text.value(), json_path);
  if (!document.ok()) return document.error();
  return RenderJsonHtml(document.value(), json_path, session_path, options);
}

}  // namespace metro
