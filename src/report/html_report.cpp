// RenderSessionReportHtml fills the "session" template in these stages, in the page's order:
//
//   result, input  AnyPlotData, SetResultAndInput  result and Type A tables, noise, input,
//                                                  dialect, options, the plot-data note
//   tags           TagSection, QuantityData        per tag: counts, window, Allan groups;
//                                                  per quantity: figures (at most
//                                                  max_plotted_quantities on the page)
//   budget         BudgetViewData                  the session's budget, if any
#include "metro/report/html_report.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <filesystem>
#include <optional>
#include <utility>

#include "accuracy_view.hpp"
#include "budget_view.hpp"
#include "core/json_text.hpp"
#include "html_common.hpp"
#include "html_dispatch.hpp"
#include "html_templates.hpp"
#include "metro/calibration/calibration_io.hpp"
#include "metro/core/file.hpp"
#include "metro/io/columns.hpp"
#include "metro/io/session_io.hpp"
#include "metro/report/accuracy_page.hpp"
#include "metro/report/batch.hpp"
#include "metro/report/batch_page.hpp"
#include "metro/report/budget_page.hpp"
#include "metro/report/certificate.hpp"
#include "metro/report/session_report.hpp"
#include "metro/report/type_a_report.hpp"
#include "session_plots.hpp"
#include "session_report_json.hpp"
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
using report_internal::SessionOptionRows;
using report_internal::ShortNumber;
using report_internal::SpecRows;
using report_internal::TypeADetailRows;

namespace {

std::string SettleText(const ReportWindow& window) {
  if (!window.settle) return "none";
  const ReportWindowSettle& s = *window.settle;
  // `driver`: the quantity whose cut the tag window takes (each quantity has its own).
  const std::string driver = s.driver ? fmt::format(", the cut of {}", *s.driver) : "";
  return fmt::format("{}: {} samples{}{}", s.method,
                     ShortNumber(static_cast<double>(s.samples), 10), driver,
                     s.at_limit ? " (at the limit)" : "");
}

// How the file was read (the report's input.dialect, mapping and time), in words: empty for
// a receiver capture, which has none of them.
std::string DialectText(const ReportInput& input) {
  if (!input.dialect) return "";
  const ReportDialect& d = *input.dialect;
  const std::string& delimiter = d.delimiter;
  std::string text = delimiter == "\t"  ? "tab-separated"
                     : delimiter == ";" ? "semicolon-separated"
                     : delimiter == "," ? "comma-separated"
                                        : fmt::format("separated by {}", delimiter);
  if (d.decimal_point == ",") text += ", decimal comma";
  text += fmt::format(", {} line ends", d.line_ends);
  if (d.bom) text += ", UTF-8 byte-order mark";
  if (d.quoted) text += ", quoted fields";
  if (d.header_in_comment) text += ", header in a '#' comment";
  return text;
}

std::string MappingText(const ReportInput& input) {
  if (!input.mapping) return "";
  std::string text;
  for (const ReportColumnMapping& m : *input.mapping) {
    text += fmt::format("{}{} \u2192 {}", text.empty() ? "" : "; ", m.source,
                        m.canonical.empty() ? "(left out)" : m.canonical);
  }
  return text;
}

std::string TimeText(const ReportInput& input) {
  if (!input.time) return "";
  const ReportTime& t = *input.time;
  std::string text = t.rate_hz ? fmt::format("none in the file: sample i at i / {} Hz",
                                             ShortNumber(*t.rate_hz, 10))
                               : fmt::format("column {} in {}", t.source, t.unit);
  if (t.integer) text += fmt::format(", integer (exact), origin {} ns", t.origin_ns.value_or(0));
  if (t.resolution_s) {
    text += fmt::format(", resolution {} s as written", ShortNumber(*t.resolution_s, 3));
  }
  return text;
}

mustache::data StringList(const std::vector<std::string>& strings) {
  mustache::data list{mustache::data::type::list};
  for (const std::string& v : strings) list.push_back(mustache::data(v));
  return list;
}

bool AnyAllan(const SessionReport& report) {
  for (const SensorReport& s : report.sensors) {
    for (const QuantityReport& q : s.quantities) {
      if (q.allan) return true;
    }
  }
  return false;
}

// ---- RenderSessionReportHtml's stages -------------------------------------------------------

// True when some quantity kept its plot data (a report from before metro kept it has the
// tables and Allan curves only).
bool AnyPlotData(const SessionReport& report) {
  bool any_plot_data = false;
  for (const SensorReport& s : report.sensors) {
    for (const QuantityReport& q : s.quantities) any_plot_data = any_plot_data || q.plot;
  }
  return any_plot_data;
}

// The result tables, then how it was obtained: the input, its dialect, the options.
void SetResultAndInput(const SessionReport& report, bool any_plot_data, mustache::data* data) {
  const ReportInput& input = report.input;
  const std::string session_note =
      any_plot_data
          ? "Time series, histograms and autocorrelations drawn from the plot data computed "
            "when the session was analysed (the report's \"plot\" objects)."
          : "This report predates the plot data metro now keeps in a report: it has no time "
            "series, histograms or autocorrelations. Run characterize analyze on the session "
            "again for them; tables, Allan curves and budget bars come from the report.";
  // The result first, then how it was obtained.
  data->set("result_rows", ResultRows(report));
  data->set("summary_rows", TypeADetailRows(report));
  mustache::data noise = NoiseRows(report);
  data->set("has_noise", !noise.is_empty_list());
  data->set("noise_rows", noise);
  if (report.spec) {
    data->set("has_spec", true);
    data->set("spec_part", report.spec->part);
    data->set("spec_library", report.spec->library);
    data->set("spec_rows", SpecRows(report));
    data->set("spec_rules", SpecRulesText(*report.spec));
  }
  data->set("input_path", input.path);
  data->set("input_sha256", input.sha256);
  data->set("input_format", input.format);
  data->set("input_rows", ShortNumber(static_cast<double>(input.rows), 12));
  data->set("input_rejected_rows", ShortNumber(static_cast<double>(input.rejected_rows), 12));
  // Each row only when the report has it (a receiver capture has no dialect, a canonical
  // file no mapping): a missing value renders no section.
  for (const auto& [key, text] :
       {std::pair{"input_dialect", DialectText(input)},
        std::pair{"input_mapping", MappingText(input)}, std::pair{"input_time", TimeText(input)}}) {
    if (!text.empty()) data->set(key, text);
  }
  data->set("input_notes", StringList(input.notes));
  data->set("input_warnings", StringList(input.warnings));
  mustache::data option_rows = SessionOptionRows(report);
  data->set("has_options", !option_rows.is_empty_list());
  data->set("option_rows", option_rows);
  data->set("session_ok", any_plot_data);
  data->set("session_note", session_note);
}

// The plot budget across the page: at most max_plotted_quantities quantities are drawn.
struct PlotCount {
  int plotted = 0;
  int not_plotted = 0;
};

// One quantity's figures and Allan terms; nothing when it is not plotted.
std::optional<mustache::data> QuantityData(const QuantityReport& q, int sensor,
                                           const HtmlReportOptions& options, bool any_plot_data,
                                           PlotCount* count) {
  const std::string& qname = q.name;
  const bool wanted =
      options.plot_quantities.empty()
          ? !IsQuaternionComponent(qname)
          : std::find(options.plot_quantities.begin(), options.plot_quantities.end(), qname) !=
                options.plot_quantities.end();
  if (!q.type_a || !wanted) return std::nullopt;
  if (count->plotted >= options.max_plotted_quantities) {
    ++count->not_plotted;
    return std::nullopt;
  }
  ++count->plotted;
  mustache::data qd;
  qd.set("sensor", std::to_string(sensor));
  qd.set("quantity", qname);
  qd.set("unit", q.unit);
  qd.set("warnings", StringList(q.warnings));
  QuantityPlots plots;
  if (q.plot) {
    AddSeriesPlots(q, *q.plot, &plots);
  } else {
    plots.unavailable.push_back(mustache::data(fmt::format(
        "time series, histogram and autocorrelation of {}: unavailable ({})", qname,
        any_plot_data ? "no plot data was kept for it when the session was analysed"
                      : "the report predates plot data; run characterize analyze again")));
  }
  mustache::data terms{mustache::data::type::list};
  if (q.allan) AddAllanPlot(q, &plots, &terms);
  qd.set("has_allan_terms", !terms.is_empty_list());
  qd.set("allan_terms", terms);
  qd.set("plots", plots.plots);
  qd.set("unavailable", plots.unavailable);
  return qd;
}

// One tag's section: its counts, window, warnings, Allan group plots and quantities.
mustache::data TagSection(const SensorReport& s, const HtmlReportOptions& options,
                          bool any_plot_data, PlotCount* count) {
  const int sensor = static_cast<int>(s.sensor);
  mustache::data sd;
  sd.set("sensor", std::to_string(sensor));
  sd.set("tag", s.name);
  sd.set("frames", ShortNumber(static_cast<double>(s.frames), 12));
  sd.set("fresh", ShortNumber(static_cast<double>(s.fresh), 12));
  sd.set("stale", ShortNumber(static_cast<double>(s.stale), 12));
  sd.set("loss", fmt::format("{:.2f} %", 100.0 * s.packet_loss_ratio));
  sd.set("n", ShortNumber(static_cast<double>(s.window.n), 12));
  sd.set("n_total", ShortNumber(static_cast<double>(s.window.n_total), 12));
  sd.set("t_first_s", ShortNumber(s.window.t_first_s, 6));
  sd.set("t_last_s", ShortNumber(s.window.t_last_s, 6));
  sd.set("settle", SettleText(s.window));
  sd.set("warnings", StringList(s.warnings));
  QuantityPlots groups;
  AddAllanGroupPlots(s, &groups);
  sd.set("has_allan_groups", !groups.plots.is_empty_list() || !groups.unavailable.is_empty_list());
  sd.set("allan_group_plots", groups.plots);
  sd.set("allan_group_unavailable", groups.unavailable);
  mustache::data quantities{mustache::data::type::list};
  for (const QuantityReport& q : s.quantities) {
    std::optional<mustache::data> qd = QuantityData(q, sensor, options, any_plot_data, count);
    if (qd) quantities.push_back(*qd);
  }
  sd.set("quantities", quantities);
  return sd;
}

}  // namespace

bool HtmlReportOptions::IsValid(std::string* why) const {
  if (max_plotted_quantities < 0) {
    *why = "html: max_plotted_quantities must be >= 0";
    return false;
  }
  return true;
}

Result<std::string> RenderSessionReportHtml(const SessionReport& report,
                                            const HtmlReportOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) return MakeError(why);
  const ReportInput& input = report.input;
  // The figures come from the plot data kept in the report at analysis time.
  const bool any_plot_data = AnyPlotData(report);
  mustache::data data;
  SetResultAndInput(report, any_plot_data, &data);
  mustache::data sensors{mustache::data::type::list};
  PlotCount count;
  for (const SensorReport& s : report.sensors) {
    sensors.push_back(TagSection(s, options, any_plot_data, &count));
  }
  const int not_plotted = count.not_plotted;
  data.set("sensors", sensors);
  data.set("has_more_quantities", not_plotted > 0);
  data.set("more_quantities",
           fmt::format("{} more quantities are in the tables but not plotted (at most {} are "
                       "plotted).",
                       not_plotted, options.max_plotted_quantities));
  const bool has_budget = report.budget.has_value();
  if (has_budget) {
    Result<mustache::data> budget = report_internal::BudgetViewData(*report.budget);
    if (!budget.ok()) return budget.error();
    data.set("budget", budget.value());
  } else {
    data.set("budget", false);
  }
  Result<std::string> body = report_internal::RenderTemplate("session", std::move(data));
  if (!body.ok()) return body;
  const std::string file = std::filesystem::path(input.path).filename().string();
  return report_internal::RenderPage(
      fmt::format("Session report: {}", file),
      fmt::format("{} (GUM Type A{}{}) - sha256 {}", kReportSchema,
                  AnyAllan(report) ? ", Allan deviation" : "",
                  has_budget ? ", uncertainty budget" : "", input.sha256.substr(0, 16)),
      body.value());
}

Result<std::string> RenderSessionAnalysisHtml(const SessionAnalysis& analysis,
                                              const HtmlReportOptions& options) {
  if (!analysis.ok) return MakeError("no HTML report of a failed analysis");
  return RenderSessionReportHtml(analysis.report, options);
}

std::string JsonSchemaOf(std::string_view text) {
  Result<ordered_json> document = ParseOrderedJsonText(text, "");
  if (!document.ok() || !document.value().is_object()) return {};
  const ordered_json& d = document.value();
  return d.contains("schema") && d["schema"].is_string() ? d["schema"].get<std::string>() : "";
}

Result<std::string> RenderJsonTextHtml(std::string_view text, const std::string& json_path,
                                       const HtmlReportOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) return MakeError(why);
  Result<ordered_json> document = ParseOrderedJsonText(text, json_path);
  if (!document.ok()) return document.error();
  const ordered_json& d = document.value();
  const std::string schema = d.is_object() && d.contains("schema") && d["schema"].is_string()
                                 ? d["schema"].get<std::string>()
                                 : "";
  // Each typed document is read from the text itself (its FromJson), so an error names the
  // value's line and column in the file with its path.
  if (schema == kReportSchema) {
    Result<SessionReport> report = SessionReportFromJson(text, json_path);
    if (!report.ok()) return report.error();
    return RenderSessionReportHtml(report.value(), options);
  }
  if (schema == kCalibrationSchema) {
    Result<Calibration> cal = CalibrationFromJson(text, json_path);
    if (!cal.ok()) return cal.error();
    // The id of the file's own bytes: what `fit` printed and the registry recorded. A view:
    // constants marked model_rejected are shown under a banner, not refused (issue #36).
    CertificateOptions certificate;
    certificate.view = true;
    Result<std::string> sha = Sha256File(json_path);
    if (sha.ok()) certificate.certificate_id = sha.value().substr(0, 16);
    return RenderCalibrationCertificate(cal.value(), certificate);
  }
  if (schema == report_internal::kAccuracyReportSchema) {
    return RenderAccuracyReportHtml(text, json_path);
  }
  if (schema == kBudgetReportSchema) return RenderBudgetReportHtml(text, json_path);
  if (schema == kBatchSummarySchema) {
    // The links are relative to the summary's folder, where batch wrote the session pages.
    return RenderBatchSummaryHtml(text, json_path);
  }
  if (IsBudgetDefinition(d)) {
    return MakeError(json_path, 0,
                     "this is a budget definition (docs/budget-format.md), not a report: run "
                     "`characterize budget " +
                         json_path + " --html PAGE.html` to evaluate it and write its page");
  }
  return report_internal::RenderGenericHtml(d, json_path, schema);
}

Result<std::string> RenderJsonHtml(const ordered_json& document, const std::string& json_path,
                                   const HtmlReportOptions& options) {
  // As metro writes it (indent 2), so positions match a file it wrote.
  return RenderJsonTextHtml(JsonText(document, 2), json_path, options);
}

Result<std::string> RenderJsonFileHtml(const std::string& json_path,
                                       const HtmlReportOptions& options) {
  Result<std::string> text = ReadFile(json_path);
  if (!text.ok()) return text.error();
  return RenderJsonTextHtml(text.value(), json_path, options);
}

}  // namespace metro
