#include "metro/report/settle_report.hpp"

#include <cmath>

namespace metro {

void AddSettleToReport(const Session& session, const SessionTypeA& result,
                       const WindowOptions& options, SessionReport* report) {
  const char* scope = options.settle_tag_wide ? "tag" : "quantity";
  report->options.settle_scope = scope;
  if (!options.settle_auto) return;
  std::vector<SensorReport>& sensors = report->sensors;
  for (size_t k = 0; k < result.tags.size() && k < sensors.size(); ++k) {
    const TagTypeA& t = result.tags[k];
    SensorReport& s = sensors[k];
    const Tag* tag = session.FindTag(t.sensor);
    if (tag == nullptr) continue;
    // Sample period of the window, to state tau in seconds too.
    double period_s = std::nan("");
    const size_t explicit_begin = t.window.begin - t.window.settle_samples;
    const size_t n_window = t.window.end - explicit_begin;
    if (n_window > 1) {
      period_s = (tag->t_s[t.window.end - 1] - tag->t_s[explicit_begin]) /
                 static_cast<double>(n_window - 1);
    }
    if (!s.window.settle) s.window.settle = ReportWindowSettle{};
    ReportWindowSettle& settle = *s.window.settle;
    settle.method = kSettleMethod;
    settle.scope = scope;
    settle.driver = t.window.settle_driver.empty()
                        ? std::nullopt
                        : std::optional<std::string>(t.window.settle_driver);
    for (const QuantityTypeA& q : t.quantities) {
      QuantityReport* jq = s.Find(q.name);
      if (jq == nullptr) continue;
      jq->window_first_index = static_cast<int64_t>(q.window_begin);
      jq->t_first_s = q.window_begin < t.window.end ? tag->t_s[q.window_begin] : std::nan("");
      const SettleResult& r = q.settle;
      QuantitySettle js;
      js.method = kSettleMethod;
      js.samples = static_cast<int64_t>(r.samples);
      js.at_limit = r.at_limit;
      js.fitted = r.fitted;
      if (r.fitted) {
        js.significant = r.significant;
        js.tau_samples = r.tau_samples;
        js.tau_s = r.tau_samples * period_s;  // NaN (null) without a period.
        js.amplitude = r.amplitude;
        js.amplitude_over_u = r.t_ratio;
        js.u_mean_residual = r.u_mean_residual;
        js.bias_over_u_uncut = r.bias_over_u_uncut;
        js.bias_over_u_kept = r.bias_over_u_kept;
      } else {
        js.note = r.note;
      }
      jq->settle = js;
    }
  }
}

}  // namespace metro
