#include "mean_coverage.hpp"

#include <cmath>

#include "metro/uncertainty/gum.hpp"

namespace metro::report_internal {

void SetMeanCoverage(nlohmann::ordered_json* type_a) {
  nlohmann::ordered_json& a = *type_a;
  const bool have = a.contains("u_mean") && a["u_mean"].is_number() && a.contains("u_mean_dof") &&
                    a["u_mean_dof"].is_number();
  const double u = have ? a["u_mean"].get<double>() : NAN;
  const double dof = have ? a["u_mean_dof"].get<double>() : NAN;
  a["coverage"] = kMeanCoverage;
  // Below one degree of freedom t has no usable quantile (t_0.975(0.04) ~ 1e66): no U, as
  // the certificate states none for a fit with dof < 1.
  if (!(std::isfinite(u) && dof >= 1.0)) {
    a["k"] = nullptr;
    a["U_mean"] = nullptr;
    return;
  }
  // JCGM 100:2008 6.2.1 and G.3.2: U = k u_c, k = t_{(1+p)/2}(nu).
  const double k = CoverageFactor(kMeanCoverage, dof);
  a["k"] = k;
  a["U_mean"] = k * u;
}

}  // namespace metro::report_internal
