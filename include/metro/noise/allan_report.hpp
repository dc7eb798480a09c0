// JSON and CSV forms of an Allan curve and its noise terms.
//
// AllanToJson produces the "allan" object of a characterize report (one per quantity):
//   {"estimator": "oadev", "tau_s": [...], "adev": [...], "ci_low": [...], "ci_high": [...],
//    "edf": [...], "n_terms": [...], "n_terms_gap_free": [...], "missing_fraction": [...],
//    "confidence": 0.683, "alpha": [...], "alpha_source": ["lag1_acf", ...],
//    "noise": {"quantization": T, "random_walk": T, "bias_instability": T,
//              "rate_random_walk": T, "rate_ramp": T}}
// "adev" holds the chosen estimator's deviation in the quantity's unit. Each T is
//   {"value", "u", "unit", "value_conventional", "unit_conventional", "supported",
//    "tau_min_s", "tau_max_s", "readoff": {"value", "u", "tau_s"} | null}
// with value/u null when the fit does not support the term; random_walk also carries
// "density_one_sided", "u_density_one_sided", "unit_density" (sqrt(2) N, the figure a
// datasheet quotes) and their conventional forms. NaN (no EDF) is written as null.
//
// AllanTypeALinkToJson gives what sits beside the n_eff Type A result:
//   {"allan_min_tau_s", "allan_min_dev", "allan_min_at_end", "duration_s",
//    "u_mean_allan", "u_u_mean_allan", "dominant_term", "extrapolated"}
//
// AllanCurveCsv: header "tau_s,m,n_terms,alpha,alpha_source,edf,adev_<tok>,ci_low_<tok>,
// ci_high_<tok>,missing_fraction" (tok from NoiseUnits::column_token, e.g. adev_dps), one row
// per tau, numbers with 10 significant digits, empty fields for NaN. missing_fraction is the
// fraction of the tau's terms left out for missing samples (0 without gaps).
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "metro/noise/allan.hpp"
#include "metro/noise/noise_fit.hpp"

namespace metro {

nlohmann::ordered_json AllanToJson(const AllanCurve& curve, const NoiseFit& fit,
                                   const std::string& quantity_unit);

nlohmann::ordered_json AllanTypeALinkToJson(const AllanCurve& curve, const NoiseFit& fit,
                                            double duration_s);

std::string AllanCurveCsv(const AllanCurve& curve, const std::string& quantity_unit);

// 1 - n_terms / n_terms_gap_free at each tau (0 where nothing is missing).
std::vector<double> MissingFractions(const AllanCurve& curve);

}  // namespace metro
