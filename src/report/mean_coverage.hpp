// The expanded uncertainty of a quantity's mean in the report (docs/report-schema.md):
// U_mean = k u_mean with k = t_{(1+p)/2}(u_mean_dof), Student's t at the mean's degrees of
// freedom for the coverage probability p (JCGM 100:2008 6.2.1, G.3.2). Set whenever u_mean
// is set, so the session page and any reader take the same U from the report.
#pragma once

#include "metro/report/session_report.hpp"

namespace metro::report_internal {

// The coverage probability p of a session report's U_mean.
inline constexpr double kMeanCoverage = 0.95;

// Sets `type_a`'s coverage (p), k and U_mean from its u_mean and u_mean_dof; k and U_mean
// are NaN (null) when u_mean or its dof is NaN (a constant series) or the dof is below 1 (a
// mean dominated by a slow drift: t has no usable quantile there).
void SetMeanCoverage(TypeAReport* type_a);

}  // namespace metro::report_internal
