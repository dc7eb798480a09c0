#include "metro/report/session_analysis.hpp"

#include "metro/core/terminal_text.hpp"
#include "metro/io/columns.hpp"
#include "metro/report/batch.hpp"
#include "metro/report/plot_data.hpp"
#include "metro/report/settle_report.hpp"
#include "metro/report/type_a_report.hpp"
#include "metro/report/u_mean_evidence.hpp"
#include "metro/uncertainty/budget.hpp"
#include "metro/uncertainty/budget_report.hpp"
#include "metro/uncertainty/session_resolver.hpp"

namespace metro {

bool SessionAnalysisOptions::IsValid(std::string* why) const {
  return load.IsValid(why) && type_a.IsValid(why) && plot.IsValid(why);
}

SessionAnalysis AnalyzeSession(const std::string& path, const SessionAnalysisOptions& options) {
  SessionAnalysis out;  // Its defaults read as an input error.
  std::string why;
  if (!options.IsValid(&why)) {
    out.error = MakeError(why);
    return out;
  }
  ProgressSink* progress = options.progress;
  LoadOptions load = options.load;
  if (progress != nullptr) {
    BeginLoadPhase(progress, path);
    load.on_bytes_parsed = [progress](int64_t n) { progress->Advance(n); };
  }
  auto session = LoadSession(path, load);
  if (!session.ok()) {
    out.error = session.error();
    return out;
  }
  return AnalyzeLoadedSession(std::move(session).value(), options);
}

SessionAnalysis AnalyzeLoadedSession(Session session, const SessionAnalysisOptions& options) {
  SessionAnalysis out;
  auto fail = [&out](Error error, bool input_error) {
    out.ok = false;
    out.error = std::move(error);
    out.input_error = input_error;
    return std::move(out);
  };
  std::string why;
  if (!options.IsValid(&why)) return fail(MakeError(why), true);
  ProgressSink* progress = options.progress;
  out.session = std::move(session);
  if (progress != nullptr) progress->BeginPhase("Type A", kUncountedWork);
  auto type_a = EvaluateSessionTypeA(out.session, options.type_a);
  if (!type_a.ok()) return fail(type_a.error(), true);
  out.type_a = std::move(type_a).value();
  out.report = MakeSessionReport(out.session, out.type_a, options.type_a, options.registry);
  AddSettleToReport(out.session, out.type_a, options.type_a.window, &out.report);
  bool run_allan = options.allan;
  if (run_allan && options.allan_skip_without_rates && options.allan_options.quantities.empty()) {
    bool any_rate = false;
    for (const TagTypeA& tag : out.type_a.tags) {
      for (const QuantityTypeA& q : tag.quantities) any_rate = any_rate || IsRateQuantity(q.name);
    }
    if (!any_rate) {
      run_allan = false;
      out.report.allan_skipped =
          "no rate quantity (gyroscope or accelerometer column) in the window: no Allan "
          "deviation for this session";
    }
  }
  if (run_allan) {
    if (progress != nullptr) progress->BeginPhase("Allan deviation", kUncountedWork);
    Result<AllanSectionSummary> allan =
        AddAllanToReport(out.session, out.type_a, options.allan_options, &out.report,
                         options.allan_csv ? &out.allan_csv : nullptr);
    if (!allan.ok()) return fail(allan.error(), true);
    for (const std::string& f : allan.value().failures) out.failures.push_back("--allan: " + f);
    out.nothing_produced = out.nothing_produced || allan.value().NothingProduced();
    ApplyAllanEvidenceToUMean(&out.type_a, &out.report);
  }
  // The figures of the session page, from the record as analysed (the window, the settle
  // cuts and the Allan u_mean are final here).
  Result<int> plots = AddPlotData(out.session, out.type_a, options.plot, &out.report);
  if (!plots.ok()) return fail(plots.error(), false);
  out.table.clear();
  for (const std::string& w : NoFreshPacketWarnings(out.report)) {
    out.table += EscapeControlChars(w) + "\n";  // One line: it names the tag.
  }
  out.table += TypeAReportTable(out.report);
  if (!options.budget_path.empty()) {
    auto budget =
        LoadBudget(options.budget_path,
                   MakeSessionQuantityResolver(out.session, out.type_a, options.type_a.window));
    if (!budget.ok()) return fail(budget.error(), true);
    auto evaluation = EvaluateBudget(budget.value(), progress);
    if (!evaluation.ok()) return fail(evaluation.error(), false);
    for (const std::string& w : evaluation.value().gum.warnings) {
      out.warnings.push_back("--budget: " + w);
    }
    out.report.budget = MakeBudgetReport(evaluation.value());
    out.table += BudgetReportTable(evaluation.value());
  }
  if (progress != nullptr) progress->Finish();
  out.ok = true;
  return out;
}

}  // namespace metro
