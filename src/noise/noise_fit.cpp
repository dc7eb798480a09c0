#include "metro/noise/noise_fit.hpp"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <boost/math/special_functions/erf.hpp>
#include <cmath>
#include <limits>
#include <vector>

namespace metro {
namespace {

constexpr double kThinRatio = 1.9;         // Successive fitted taus at least this far apart.
constexpr double kRangeShare = 0.25;       // A term "rests on" taus where it is >= 25 %.
constexpr double kReadOffSlopeTol = 0.15;  // |local slope - term slope| for a read-off.

struct Point {
  double tau_s;
  double var;
  double edf;
};

struct SubsetFit {
  bool admissible = false;
  std::vector<int> terms;
  Eigen::VectorXd c;
  Eigen::MatrixXd cov;
  double chi2 = 0.0;
  double bic = 0.0;
};

// IRLS for one subset of terms. var(s^2) = model^2 (2/edf + (2 floor)^2).
SubsetFit FitSubset(const std::vector<Point>& pts, const std::vector<int>& terms,
                    AllanEstimator estimator, const NoiseFitOptions& options) {
  SubsetFit out;
  out.terms = terms;
  const int n = static_cast<int>(pts.size());
  const int k = static_cast<int>(terms.size());
  Eigen::MatrixXd a(n, k);
  Eigen::VectorXd y(n);
  for (int i = 0; i < n; ++i) {
    y(i) = pts[static_cast<size_t>(i)].var;
    for (int j = 0; j < k; ++j) {
      double f = 0.0;
      METRO_CHECK(NoiseBasis(estimator, static_cast<NoiseTerm>(terms[static_cast<size_t>(j)]),
                             pts[static_cast<size_t>(i)].tau_s, &f));
      a(i, j) = f;
    }
  }
  const double floor2 = 4.0 * options.relative_floor * options.relative_floor;
  Eigen::VectorXd model = y;
  Eigen::VectorXd w(n);
  Eigen::VectorXd c = Eigen::VectorXd::Zero(k);
  Eigen::MatrixXd normal_inv;
  for (int it = 0; it < options.iterations; ++it) {
    for (int i = 0; i < n; ++i) {
      const double ref = model(i) > 0.0 ? model(i) : y(i);
      w(i) = 1.0 / (ref * ref * (2.0 / pts[static_cast<size_t>(i)].edf + floor2));
    }
    // Rows scaled by sqrt(w), columns by their norms: the basis spans many decades.
    Eigen::MatrixXd as = w.cwiseSqrt().asDiagonal() * a;
    Eigen::VectorXd col = as.colwise().norm().transpose();
    for (int j = 0; j < k; ++j) {
      if (!(col(j) > 0.0)) return out;
      as.col(j) /= col(j);
    }
    const Eigen::VectorXd ys = w.cwiseSqrt().cwiseProduct(y);
    const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(as);
    if (qr.rank() < k) return out;
    const Eigen::VectorXd cs = qr.solve(ys);
    c = cs.cwiseQuotient(col);
    const Eigen::MatrixXd normal = as.transpose() * as;
    normal_inv =
        col.cwiseInverse().asDiagonal() * normal.inverse() * col.cwiseInverse().asDiagonal();
    model = a * c;
  }
  double chi2 = 0.0;
  for (int i = 0; i < n; ++i) {
    const double r = y(i) - model(i);
    chi2 += w(i) * r * r;
  }
  const int dof = n - k;
  const double scale = dof > 0 ? std::max(1.0, chi2 / dof) : 1.0;
  out.c = c;
  out.cov = normal_inv * scale;
  out.chi2 = chi2;
  out.bic = chi2 + k * std::log(static_cast<double>(n));
  out.admissible = true;
  for (int j = 0; j < k; ++j) {
    const double u = std::sqrt(std::max(out.cov(j, j), 0.0));
    if (!(c(j) > 0.0) || c(j) < options.min_significance * u) out.admissible = false;
  }
  return out;
}

// Local log-log slope at point i (central where possible).
double LocalSlope(const AllanCurve& curve, size_t i) {
  const size_t lo = i > 0 ? i - 1 : i;
  const size_t hi = i + 1 < curve.size() ? i + 1 : i;
  if (lo == hi) return std::nan("");
  return (std::log(curve.dev[hi]) - std::log(curve.dev[lo])) /
         (std::log(curve.tau_s[hi]) - std::log(curve.tau_s[lo]));
}

// Relative standard uncertainty of a deviation from its confidence interval (68 % ~ 1 sigma
// when the level is 0.683; scaled by the normal quantile otherwise).
double RelativeU(const AllanCurve& curve, size_t i) {
  if (!(std::isfinite(curve.ci_low[i]) && std::isfinite(curve.ci_high[i])) ||
      !(curve.dev[i] > 0.0) || !(curve.ci_low[i] > 0.0)) {
    return std::nan("");
  }
  const double half_log = 0.5 * (std::log(curve.ci_high[i]) - std::log(curve.ci_low[i]));
  if (!(curve.confidence > 0.0 && curve.confidence < 1.0)) return std::nan("");
  // z with two-sided normal coverage `confidence` (1.0 at 0.683).
  const double z = std::sqrt(2.0) * boost::math::erf_inv(curve.confidence);
  return half_log / z;
}

}  // namespace

bool NoiseFitOptions::IsValid(std::string* why) const {
  auto fail = [why](const std::string& message) {
    if (why != nullptr) *why = message;
    return false;
  };
  if (!(relative_floor >= 0.0 && std::isfinite(relative_floor))) {
    return fail("relative_floor must be >= 0");
  }
  if (!(min_significance >= 0.0 && std::isfinite(min_significance))) {
    return fail("min_significance must be >= 0");
  }
  if (!(tau_min_s >= 0.0) || !(tau_max_s > tau_min_s)) {
    return fail("the fit range needs 0 <= tau_min_s < tau_max_s");
  }
  if (iterations < 1) return fail("iterations must be >= 1");
  if (std::none_of(allow.begin(), allow.end(), [](bool b) { return b; })) {
    return fail("no noise term is allowed");
  }
  return true;
}

Result<NoiseFit> FitNoiseTerms(const AllanCurve& curve, const NoiseFitOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) return MakeError("noise fit options: " + why);
  double probe = 0.0;
  if (!NoiseBasis(curve.estimator, NoiseTerm::kRandomWalk, 1.0, &probe)) {
    return MakeError(fmt::format(
        "noise fit: the IEEE 952 model is defined for oadev, adev, ohdev and hdev, not {}",
        AllanEstimatorName(curve.estimator)));
  }
  std::vector<Point> pts;
  for (size_t i = 0; i < curve.size(); ++i) {
    const double tau = curve.tau_s[i];
    if (!(curve.dev[i] > 0.0) || tau < options.tau_min_s || tau > options.tau_max_s) continue;
    if (options.thin_to_octave && !pts.empty() && tau < kThinRatio * pts.back().tau_s) continue;
    const double edf = std::isfinite(curve.edf[i]) && curve.edf[i] > 0.0 ? curve.edf[i] : 1.0;
    pts.push_back({tau, curve.dev[i] * curve.dev[i], edf});
  }
  if (pts.size() < 2) {
    return MakeError(fmt::format(
        "noise fit: {} usable curve points in the fit range; at least 2 are needed", pts.size()));
  }
  std::vector<int> allowed;
  for (NoiseTerm t : kAllNoiseTerms) {
    double f = 0.0;
    if (options.allow[static_cast<size_t>(t)] && NoiseBasis(curve.estimator, t, 1.0, &f)) {
      allowed.push_back(static_cast<int>(t));
    }
  }
  SubsetFit best;
  const int n_allowed = static_cast<int>(allowed.size());
  for (int mask = 1; mask < (1 << n_allowed); ++mask) {
    std::vector<int> terms;
    for (int j = 0; j < n_allowed; ++j) {
      if (mask & (1 << j)) terms.push_back(allowed[static_cast<size_t>(j)]);
    }
    if (terms.size() > pts.size()) continue;
    SubsetFit fit = FitSubset(pts, terms, curve.estimator, options);
    if (fit.admissible && (!best.admissible || fit.bic < best.bic)) best = fit;
  }
  if (!best.admissible) {
    return MakeError(
        "noise fit: no combination of noise terms is supported by the data (every subset has a "
        "non-positive or insignificant coefficient)");
  }

  NoiseFit out;
  out.estimator = curve.estimator;
  out.chi2 = best.chi2;
  out.n_points = static_cast<int>(pts.size());
  out.dof = out.n_points - static_cast<int>(best.terms.size());
  out.birge_ratio = out.dof > 0 ? std::sqrt(best.chi2 / out.dof) : 0.0;
  out.fit_tau_min_s = pts.front().tau_s;
  out.fit_tau_max_s = pts.back().tau_s;
  for (size_t a = 0; a < best.terms.size(); ++a) {
    const int ta = best.terms[a];
    NoiseTermEstimate& est = out.terms[static_cast<size_t>(ta)];
    const double c = best.c(static_cast<Eigen::Index>(a));
    est.supported = true;
    est.value = std::sqrt(c);
    est.u = std::sqrt(std::max(best.cov(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(a)),
                               0.0)) /
            (2.0 * est.value);
    for (size_t b = 0; b < best.terms.size(); ++b) {
      out.covariance_c[static_cast<size_t>(ta)][static_cast<size_t>(best.terms[b])] =
          best.cov(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(b));
    }
  }
  out.success = true;
  out.message = "ok";
  // Tau range each term rests on.
  for (int ta : best.terms) {
    NoiseTermEstimate& est = out.terms[static_cast<size_t>(ta)];
    double best_share = -1.0, best_tau = 0.0;
    bool any = false;
    for (const Point& p : pts) {
      double f = 0.0;
      NoiseBasis(curve.estimator, static_cast<NoiseTerm>(ta), p.tau_s, &f);
      const double share = f * est.value * est.value / ModelVariance(out, p.tau_s);
      if (share > best_share) {
        best_share = share;
        best_tau = p.tau_s;
      }
      if (share >= kRangeShare) {
        est.tau_min_s = any ? std::min(est.tau_min_s, p.tau_s) : p.tau_s;
        est.tau_max_s = any ? std::max(est.tau_max_s, p.tau_s) : p.tau_s;
        any = true;
      }
    }
    if (!any) est.tau_min_s = est.tau_max_s = best_tau;
  }
  return out;
}

double ModelVariance(const NoiseFit& fit, double tau_s) {
  if (!fit.success) return 0.0;
  double sum = 0.0;
  for (NoiseTerm t : kAllNoiseTerms) {
    const NoiseTermEstimate& est = fit.term(t);
    double f = 0.0;
    if (est.supported && NoiseBasis(fit.estimator, t, tau_s, &f)) sum += f * est.value * est.value;
  }
  return sum;
}

std::array<ReadOff, kNoiseTermCount> ReadOffNoiseTerms(const AllanCurve& curve) {
  std::array<ReadOff, kNoiseTermCount> out{};
  double probe = 0.0;
  if (!NoiseBasis(curve.estimator, NoiseTerm::kRandomWalk, 1.0, &probe) || curve.size() < 2) {
    return out;
  }
  for (NoiseTerm t : kAllNoiseTerms) {
    ReadOff& ro = out[static_cast<size_t>(t)];
    double a = 0.0;  // factor at tau = 1 s: f(tau) = a tau^(2 s)
    if (!NoiseBasis(curve.estimator, t, 1.0, &a)) continue;
    const double slope = NoiseTermSlope(t);
    if (t == NoiseTerm::kBiasInstability) {
      const AllanMinimum min = FindAllanMinimum(curve);
      if (!min.found || min.at_end || min.tau_s <= curve.tau_s.front()) continue;
      size_t i = 0;
      while (curve.tau_s[i] != min.tau_s) ++i;
      ro.found = true;
      ro.value = min.dev / std::sqrt(a);  // IEEE 952 Annex C: B = sigma_min / 0.6643
      ro.u = ro.value * RelativeU(curve, i);
      ro.tau_read_s = ro.tau_min_s = ro.tau_max_s = min.tau_s;
      continue;
    }
    // Read the line sigma(tau) = sqrt(a) tau^slope * coefficient where f(tau) = 1.
    const double tau_read = std::pow(a, -1.0 / (2.0 * slope));
    double sum_w = 0.0, sum_log = 0.0, best_u = std::numeric_limits<double>::infinity();
    for (size_t i = 0; i < curve.size(); ++i) {
      if (!(curve.dev[i] > 0.0)) continue;
      const double s = LocalSlope(curve, i);
      if (!(std::fabs(s - slope) <= kReadOffSlopeTol)) continue;
      const double w = std::isfinite(curve.edf[i]) && curve.edf[i] > 0.0 ? curve.edf[i] : 1.0;
      // sigma at tau_read on the line of exact slope through point i.
      const double log_sigma =
          std::log(curve.dev[i]) + slope * (std::log(tau_read) - std::log(curve.tau_s[i]));
      sum_w += w;
      sum_log += w * log_sigma;
      const double ru = RelativeU(curve, i);
      if (std::isfinite(ru)) best_u = std::min(best_u, ru);
      ro.tau_min_s = ro.found ? std::min(ro.tau_min_s, curve.tau_s[i]) : curve.tau_s[i];
      ro.tau_max_s = ro.found ? std::max(ro.tau_max_s, curve.tau_s[i]) : curve.tau_s[i];
      ro.found = true;
    }
    if (!ro.found) continue;
    ro.tau_read_s = tau_read;
    ro.value = std::exp(sum_log / sum_w);  // sigma(tau_read) = coefficient there.
    ro.u = std::isfinite(best_u) ? ro.value * best_u : std::nan("");
  }
  return out;
}

AllanMinimum FindAllanMinimum(const AllanCurve& curve) {
  AllanMinimum out;
  size_t best = curve.size();
  for (size_t i = 0; i < curve.size(); ++i) {
    if (!(curve.dev[i] > 0.0)) continue;
    if (best == curve.size() || curve.dev[i] < curve.dev[best]) best = i;
  }
  if (best == curve.size()) return out;
  out.found = true;
  out.tau_s = curve.tau_s[best];
  out.dev = curve.dev[best];
  out.ci_low = curve.ci_low[best];
  out.ci_high = curve.ci_high[best];
  out.at_end = best + 1 == curve.size();
  return out;
}

Result<MeanUncertaintyPrediction> PredictMeanUncertainty(const NoiseFit& fit, double duration_s) {
  if (!fit.success) return MakeError("mean uncertainty: the noise fit failed: " + fit.message);
  if (!(std::isfinite(duration_s) && duration_s > 0.0)) {
    return MakeError(fmt::format("mean uncertainty: duration {} s is not positive", duration_s));
  }
  MeanUncertaintyPrediction out;
  out.duration_s = duration_s;
  const double var = ModelVariance(fit, duration_s);
  out.u = std::sqrt(var);
  std::array<double, kNoiseTermCount> grad{};
  double largest = -1.0;
  for (NoiseTerm t : kAllNoiseTerms) {
    const NoiseTermEstimate& est = fit.term(t);
    double f = 0.0;
    if (!est.supported || !NoiseBasis(fit.estimator, t, duration_s, &f)) continue;
    grad[static_cast<size_t>(t)] = out.u > 0.0 ? f / (2.0 * out.u) : 0.0;  // d sigma / d c
    if (f * est.value * est.value > largest) {
      largest = f * est.value * est.value;
      out.dominant = t;
    }
  }
  double var_u = 0.0;
  for (size_t a = 0; a < grad.size(); ++a) {
    for (size_t b = 0; b < grad.size(); ++b) var_u += grad[a] * fit.covariance_c[a][b] * grad[b];
  }
  out.u_of_u = std::sqrt(std::max(var_u, 0.0));
  out.extrapolated = duration_s < fit.fit_tau_min_s || duration_s > fit.fit_tau_max_s;
  return out;
}

}  // namespace metro
