#include "metro/report/u_mean_evidence.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "mean_coverage.hpp"

namespace metro {

void ApplyAllanEvidenceToUMean(SessionTypeA* type_a, SessionReport* report) {
  std::vector<SensorReport>& sensors = report->sensors;
  for (size_t k = 0; k < type_a->tags.size() && k < sensors.size(); ++k) {
    for (QuantityTypeA& q : type_a->tags[k].quantities) {
      if (!q.ok || !q.type_a.u_mean_available) continue;
      QuantityReport* jq = sensors[k].Find(q.name);
      if (jq == nullptr || !jq->allan_type_a_link || !jq->type_a) continue;
      const AllanTypeALink& link = *jq->allan_type_a_link;
      const double u_allan = link.u_mean_allan;
      if (!std::isfinite(u_allan)) continue;
      TypeAResult& ta = q.type_a;
      if (!(u_allan > 2.0 * ta.u_mean)) continue;
      // A model that failed its goodness-of-fit test, or could not be tested, never changes
      // u_mean (issue #36): it stays the value from the data alone, and a warning says why.
      if (link.noise_model && *link.noise_model != "holds") {
        std::string why = "the IEEE 952 noise model is " + *link.noise_model;
        if (jq->allan && jq->allan->model_check) {
          const AllanModelCheckReport& m = *jq->allan->model_check;
          why = m.tested ? fmt::format(
                               "the IEEE 952 noise model is rejected by the Allan curve "
                               "(chi2 = {:.4g} at {} dof, p = {:.2g}; allan.model_check)",
                               m.chi2, m.dof.value_or(0), m.p_value)
                         : "the IEEE 952 noise model could not be tested against the curve "
                           "(allan.model_check.not_tested)";
        }
        const std::string warning = fmt::format(
            "the fitted noise model would predict u of the mean {:.3g} over the window, {:.1f}x "
            "the Type A u_mean {:.3g}, but {}: u_mean stays the Type A value from the data "
            "alone ({})",
            u_allan, u_allan / ta.u_mean, ta.u_mean, why, ta.u_mean_method);
        q.warnings.push_back(warning);
        jq->warnings.push_back(warning);
        continue;
      }
      const double u_u = std::isfinite(link.u_u_mean_allan) ? link.u_u_mean_allan : 0.0;
      const double n_minus_1 = static_cast<double>(ta.n - 1);
      // JCGM 100:2008 G.4.2: nu = (1/2) (u / u(u))^2.
      const double ratio = u_u > 0.0 ? u_allan / u_u : 0.0;
      const double dof = u_u > 0.0 ? std::clamp(0.5 * ratio * ratio, 1.0, n_minus_1) : n_minus_1;
      const std::string dominant = link.dominant_term.value_or("unknown");
      const bool extrapolated = link.extrapolated.value_or(false);
      const std::string warning = fmt::format(
          "the Allan deviation shows noise the autocorrelation misses: the fitted noise model "
          "(dominant term {}{}) predicts u of the mean {:.3g} over the window, {:.1f}x the "
          "Type A u_mean {:.3g} ({}); u_mean takes the Allan value ({:.1f} dof)",
          dominant, extrapolated ? ", extrapolated to the window's duration" : "", u_allan,
          u_allan / ta.u_mean, ta.u_mean, ta.u_mean_method, dof);
      ta.u_mean = u_allan;
      ta.u_mean_dof = dof;
      ta.u_mean_method = kUMeanAllan;
      q.warnings.push_back(warning);
      TypeAReport& ja = *jq->type_a;
      ja.u_mean = u_allan;
      ja.u_mean_dof = dof;
      ja.u_mean_method = kUMeanAllan;
      ja.u_mean_ar_order.reset();
      report_internal::SetMeanCoverage(&ja);
      jq->warnings.push_back(warning);
    }
  }
}

}  // namespace metro
