#include "mean_coverage.hpp"

#include <cmath>

#include "metro/uncertainty/gum.hpp"

namespace metro::report_internal {

void SetMeanCoverage(TypeAReport* type_a) {
  TypeAReport& a = *type_a;
  const double u = a.u_mean;
  const double dof = a.u_mean_dof;
  a.coverage = kMeanCoverage;
  a.k = NAN;
  a.U_mean = NAN;
  // Below one degree of freedom t has no usable quantile (t_0.975(0.04) ~ 1e66): no U, as
  // the certificate states none for a fit with dof < 1.
  if (!(std::isfinite(u) && dof >= 1.0)) return;
  // JCGM 100:2008 6.2.1 and G.3.2: U = k u_c, k = t_{(1+p)/2}(nu).
  a.k = CoverageFactor(kMeanCoverage, dof);
  a.U_mean = a.k * u;
}

}  // namespace metro::report_internal
