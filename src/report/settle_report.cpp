#include "metro/report/settle_report.hpp"

#include <cmath>

namespace metro {

using nlohmann::ordered_json;

namespace {

ordered_json FiniteOrNull(double v) { return std::isfinite(v) ? ordered_json(v) : ordered_json(); }

}  // namespace

void AddSettleToReport(const Session& session, const SessionTypeA& result,
                       const WindowOptions& options, ordered_json* report) {
  ordered_json& opts = (*report)["options"];
  opts["settle_scope"] = options.settle_tag_wide ? "tag" : "quantity";
  if (!options.settle_auto || !report->contains("sensors")) return;
  ordered_json& sensors = (*report)["sensors"];
  for (size_t k = 0; k < result.tags.size() && k < sensors.size(); ++k) {
    const TagTypeA& t = result.tags[k];
    ordered_json& s = sensors[k];
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
    ordered_json& settle = s["window"]["settle"];
    settle["method"] = kSettleMethod;
    settle["scope"] = options.settle_tag_wide ? "tag" : "quantity";
    settle["driver"] =
        t.window.settle_driver.empty() ? ordered_json() : ordered_json(t.window.settle_driver);
    ordered_json& quantities = s["quantities"];
    for (const QuantityTypeA& q : t.quantities) {
      if (!quantities.contains(q.name)) continue;
      ordered_json& jq = quantities[q.name];
      jq["window_first_index"] = q.window_begin;
      jq["t_first_s"] =
          q.window_begin < t.window.end ? ordered_json(tag->t_s[q.window_begin]) : ordered_json();
      const SettleResult& r = q.settle;
      ordered_json js = {{"method", kSettleMethod},
                         {"samples", r.samples},
                         {"at_limit", r.at_limit},
                         {"fitted", r.fitted}};
      if (r.fitted) {
        js["significant"] = r.significant;
        js["tau_samples"] = r.tau_samples;
        js["tau_s"] = FiniteOrNull(r.tau_samples * period_s);
        js["amplitude"] = r.amplitude;
        js["amplitude_over_u"] = r.t_ratio;
        js["u_mean_residual"] = r.u_mean_residual;
        js["bias_over_u_uncut"] = r.bias_over_u_uncut;
        js["bias_over_u_kept"] = r.bias_over_u_kept;
      } else {
        js["note"] = r.note;
      }
      jq["settle"] = js;
    }
  }
}

}  // namespace metro
