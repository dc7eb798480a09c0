// The Allan evidence against the Type A u_mean (issue #21 part 2, docs/type-a.md).
//
// The Type A u_mean (stats/type_a.hpp) models the correlation of the window; a rate random
// walk or a bias instability that is slow against the window hides in it as a large but
// finite correlation. The Allan analysis (noise/allan_report.hpp) fits the IEEE Std 952
// noise terms and predicts the deviation of the mean over the window's duration,
// "allan_type_a_link".u_mean_allan. Where that is more than 2x u_mean, u_mean takes the
// Allan value with u_mean_dof = (1/2) (u / u(u))^2 (JCGM 100:2008 G.4.2), at most n - 1,
// u_mean_method "allan_noise_model", and a warning names the dominant noise term. Only a model
// that passed its goodness-of-fit test ("allan_type_a_link".noise_model "holds"; issue #36)
// does so: a rejected or untested model leaves u_mean the Type A value from the data alone,
// with a warning that names the evidence (allan.model_check.summary). A link without
// noise_model (a report from before issue #36) is taken as it was then. This
// lives in the report layer because it needs both the stats and the noise results.
#pragma once

#include "metro/report/session_report.hpp"
#include "metro/stats/session_type_a.hpp"

namespace metro {

// Value of u_mean_method set by ApplyAllanEvidenceToUMean.
inline constexpr const char* kUMeanAllan = "allan_noise_model";

// `report` was built from `type_a` by MakeSessionReport and AddAllanToReport (its sensors[k]
// is type_a->tags[k]). Both change: the quantity's u_mean, u_mean_dof, u_mean_method and
// warnings. Quantities without a u_mean_allan are left alone.
void ApplyAllanEvidenceToUMean(SessionTypeA* type_a, SessionReport* report);

}  // namespace metro
