// The Allan evidence against the Type A u_mean (issue #21 part 2, docs/type-a.md).
//
// The Type A u_mean (stats/type_a.hpp) models the correlation of the window; a rate random
// walk or a bias instability that is slow against the window hides in it as a large but
// finite correlation. The Allan analysis (noise/allan_report.hpp) fits the IEEE Std 952
// noise terms and predicts the deviation of the mean over the window's duration,
// "allan_type_a_link".u_mean_allan. Where that is more than 2x u_mean, u_mean takes the
// Allan value with u_mean_dof = (1/2) (u / u(u))^2 (JCGM 100:2008 G.4.2), at most n - 1,
// u_mean_method "allan_noise_model", and a warning names the dominant noise term. This
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
