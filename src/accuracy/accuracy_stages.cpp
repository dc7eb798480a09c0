#include "metro/accuracy/accuracy_stages.hpp"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numeric>

#include "metro/accuracy/alignment.hpp"
#include "metro/core/angles.hpp"
#include "metro/uncertainty/budget.hpp"

namespace metro {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

std::vector<double> Slice(const std::vector<double>& v, size_t begin, size_t end) {
  std::vector<double> s(v.begin() + static_cast<std::ptrdiff_t>(begin),
                        v.begin() + static_cast<std::ptrdiff_t>(end));
  UnwrapDegInPlace(&s);
  return s;
}

double Mean(const std::vector<double>& v) {
  return std::accumulate(v.begin(), v.end(), 0.0) / static_cast<double>(v.size());
}

// Clusters of reference angles closer than match_deg (sorted by angle): cluster id per point.
std::vector<size_t> ClusterAngles(const std::vector<AccuracyPoint>& points, double match_deg,
                                  std::vector<double>* centres) {
  std::vector<size_t> order(points.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(),
            [&](size_t a, size_t b) { return points[a].reference_deg < points[b].reference_deg; });
  std::vector<size_t> id(points.size(), 0);
  centres->clear();
  std::vector<size_t> counts;
  for (size_t k = 0; k < order.size(); ++k) {
    const size_t i = order[k];
    if (k == 0 || points[i].reference_deg - points[order[k - 1]].reference_deg > match_deg) {
      centres->push_back(0.0);
      counts.push_back(0);
    }
    id[i] = centres->size() - 1;
    centres->back() += points[i].reference_deg;
    ++counts.back();
  }
  for (size_t c = 0; c < centres->size(); ++c) (*centres)[c] /= static_cast<double>(counts[c]);
  return id;
}

// Mean error of a group of plateaus and its standard uncertainty: the larger of the
// between-plateau s/sqrt(m) (dof m - 1) and the within-plateau sqrt(sum u_i^2)/m (dof: the
// smallest plateau dof).
struct GroupMean {
  double mean = 0.0, u = 0.0, dof = 0.0;
  int count = 0;
};
GroupMean MeanOfGroup(const std::vector<const AccuracyPoint*>& group, bool with_between = true) {
  GroupMean g;
  g.count = static_cast<int>(group.size());
  if (group.empty()) return g;
  const double m = static_cast<double>(group.size());
  double sum = 0.0, sum_u2 = 0.0, min_dof = kInf;
  for (const AccuracyPoint* p : group) {
    sum += p->error_deg;
    sum_u2 += p->type_a.u_deg * p->type_a.u_deg;
    min_dof = std::min(min_dof, p->type_a.dof);
  }
  g.mean = sum / m;
  const double within = sum_u2 / (m * m);
  g.u = std::sqrt(within);
  g.dof = min_dof;
  if (with_between && group.size() >= 2) {
    double ss = 0.0;
    for (const AccuracyPoint* p : group) ss += (p->error_deg - g.mean) * (p->error_deg - g.mean);
    const double between = ss / (m - 1.0) / m;
    if (between > within) {
      g.u = std::sqrt(between);
      g.dof = m - 1.0;
    }
  }
  return g;
}

BudgetInput NormalInput(const std::string& name, double u, double dof, const std::string& note) {
  BudgetInput in;
  in.name = name;
  in.distribution = Distribution::kNormal;
  in.u = u;
  in.dof = dof > 0.0 ? dof : kInf;
  in.sensitivity = 1.0;
  in.unit = "deg";
  in.note = note;
  return in;
}

BudgetInput RectangularInput(const std::string& name, double half_width, const std::string& note) {
  BudgetInput in;
  in.name = name;
  in.distribution = Distribution::kRectangular;
  in.half_width = half_width;
  in.u = half_width / std::sqrt(3.0);  // JCGM 100 4.3.7
  in.sensitivity = 1.0;
  in.unit = "deg";
  in.note = note;
  return in;
}

Result<ReadingBudget> EvaluateReadingBudget(const std::string& name,
                                            const std::vector<BudgetInput>& inputs,
                                            double coverage) {
  Budget budget;
  budget.file = name + " reading budget";
  budget.measurand = "error of a single " + name + " tag reading";
  budget.unit = "deg";
  budget.inputs = inputs;
  budget.gum.coverage = coverage;
  budget.monte_carlo.enabled = false;
  if (Status s = ValidateBudget(budget); !s.ok()) return s.error();
  auto gum = EvaluateGum(budget);
  if (!gum.ok()) return gum.error();
  ReadingBudget rb;
  rb.name = name;
  rb.gum = gum.value();
  for (const BudgetInput& in : inputs) {
    rb.notes.push_back(in.note);
    rb.input_names.push_back(in.name);
  }
  return rb;
}

double NormalCdf(double x) { return 0.5 * std::erfc(-x / std::sqrt(2.0)); }

}  // namespace

double Ar1MeanVarianceFactor(size_t n, double phi) {
  if (n == 0) return 0.0;
  const double nn = static_cast<double>(n);
  double sum = 0.0, pk = 1.0;
  for (size_t k = 1; k < n; ++k) {
    pk *= phi;
    if (pk < 1e-300) break;
    sum += (nn - static_cast<double>(k)) * pk;
  }
  return (nn + 2.0 * sum) / (nn * nn);
}

PlateauNoise PlateauNoiseOf(const std::vector<double>& series_deg,
                            const std::vector<Plateau>& plateaus) {
  PlateauNoise noise;
  // Per plateau (centred on its own mean; REML does not depend on the means): the sums the
  // restricted likelihood needs.
  struct Sums {
    double n = 0.0, xx = 0.0, ends2 = 0.0, lag = 0.0, ends = 0.0, inner = 0.0;
  };
  std::vector<Sums> sums;
  std::vector<size_t> sizes;
  double total_xx = 0.0;
  for (const Plateau& p : plateaus) {
    if (p.n() < 3) continue;
    std::vector<double> x = Slice(series_deg, p.begin, p.end);
    const double m = Mean(x);
    for (double& v : x) v -= m;
    Sums q;
    q.n = static_cast<double>(x.size());
    for (size_t k = 0; k < x.size(); ++k) {
      q.xx += x[k] * x[k];
      if (k + 1 < x.size()) q.lag += x[k] * x[k + 1];
      if (k > 0 && k + 1 < x.size()) q.inner += x[k];
    }
    q.ends = x.front() + x.back();
    q.ends2 = x.front() * x.front() + x.back() * x.back();
    total_xx += q.xx;
    sums.push_back(q);
    sizes.push_back(x.size());
  }
  noise.plateaus = sizes.size();
  if (sizes.empty() || !(total_xx > 0.0)) return noise;
  // Restricted (REML) likelihood of a stationary AR(1) with one unknown mean per plateau
  // (Patterson & Thompson, Biometrika 58 (1971) 545; Cooper & Thompson, Biometrika 64 (1977)
  // 625 for AR(1)). With innovation variance s_e^2 the inverse covariance of n observations
  // is Q / s_e^2, Q tridiagonal (diagonal 1, 1 + phi^2, ..., 1 + phi^2, 1; off-diagonal
  // -phi), |Q| = 1 - phi^2 and 1'Q1 = (1 - phi)(n - (n - 2) phi). Per plateau
  //   -2 l_i = (n_i - 1) ln s_e^2 - ln(1 - phi^2) + ln(1'Q1) + RSS_i / s_e^2,
  //   RSS_i = x'Qx - (1'Qx)^2 / 1'Q1 (the residual about the GLS mean),
  // s_e^2 profiled out as sum RSS_i / sum (n_i - 1). Unlike the moments of short plateaus
  // (whose r1 is biased by about -(1 + 4 phi)/n and whose expectations flatten near phi = 1),
  // the restricted likelihood accounts for each removed mean exactly.
  auto objective = [&](double phi, double* se2) {
    const double p2 = phi * phi;
    double rss = 0.0, dof = 0.0, logs = 0.0;
    for (const Sums& q : sums) {
      const double xqx = q.xx * (1.0 + p2) - p2 * q.ends2 - 2.0 * phi * q.lag;
      const double oqx = (1.0 - phi) * q.ends + (1.0 - phi) * (1.0 - phi) * q.inner;
      const double oqo = (1.0 - phi) * (q.n - (q.n - 2.0) * phi);
      rss += xqx - oqx * oqx / oqo;
      dof += q.n - 1.0;
      logs += -std::log(1.0 - p2) + std::log(oqo);
    }
    *se2 = rss / dof;
    return dof * std::log(*se2) + logs;
  };
  // Grid over [0, 0.999] then golden-section refinement about the best grid point.
  constexpr double kPhiMax = 0.999;
  constexpr int kGrid = 200;
  double se2 = 0.0, best = kInf, best_phi = 0.0;
  for (int g = 0; g <= kGrid; ++g) {
    const double phi = kPhiMax * g / kGrid;
    const double f = objective(phi, &se2);
    if (f < best) {
      best = f;
      best_phi = phi;
    }
  }
  double a = std::max(0.0, best_phi - kPhiMax / kGrid),
         b = std::min(kPhiMax, best_phi + kPhiMax / kGrid);
  const double r = 0.5 * (std::sqrt(5.0) - 1.0);
  double c = b - r * (b - a), d = a + r * (b - a);
  double fc = objective(c, &se2), fd = objective(d, &se2);
  for (int it = 0; it < 60; ++it) {
    if (fc < fd) {
      b = d;
      d = c;
      fd = fc;
      c = b - r * (b - a);
      fc = objective(c, &se2);
    } else {
      a = c;
      c = d;
      fc = fd;
      d = a + r * (b - a);
      fd = objective(d, &se2);
    }
  }
  double phi = 0.5 * (a + b);
  if (objective(phi, &se2) > best) phi = best_phi;
  objective(phi, &se2);
  noise.phi = phi;
  noise.sigma_deg = std::sqrt(se2 / (1.0 - phi * phi));
  // The dof of a plateau's u^2 = sigma^2 F(n, phi) (JCGM 100 G.4.2: nu = 2 / var(ln u^2) for
  // a variance estimate), at the median plateau length: the innovation variance carries
  // sum (n_i - 1) dof given phi, and phi's own uncertainty (from the curvature of the profile
  // likelihood, var(phi) = 2 / f'' for f = -2 l) moves u^2 along the profile. Short plateaus
  // of strongly correlated output leave phi poorly known, and u with few dof.
  std::vector<size_t> sorted = sizes;
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<ptrdiff_t>(sorted.size() / 2),
                   sorted.end());
  const size_t n_mid = sorted[sorted.size() / 2];
  double n_resid = 0.0;
  for (size_t n : sizes) n_resid += static_cast<double>(n) - 1.0;
  double var_log_u2 = 2.0 / n_resid;
  const double h = 1e-3;
  if (phi - h > 0.0 && phi + h < kPhiMax) {
    double se2_lo = 0.0, se2_hi = 0.0;
    const double f0 = objective(phi, &se2);
    const double f_lo = objective(phi - h, &se2_lo), f_hi = objective(phi + h, &se2_hi);
    const double curvature = (f_hi - 2.0 * f0 + f_lo) / (h * h);
    auto log_u2 = [&](double p, double e2) {
      return std::log(e2 / (1.0 - p * p) * Ar1MeanVarianceFactor(n_mid, p));
    };
    const double slope = (log_u2(phi + h, se2_hi) - log_u2(phi - h, se2_lo)) / (2.0 * h);
    if (curvature > 0.0) var_log_u2 += slope * slope * 2.0 / curvature;
    objective(phi, &se2);
  }
  noise.dof = std::clamp(2.0 / var_log_u2, 1.0, n_resid);
  return noise;
}

std::vector<double> ResponseTransient(const std::vector<double>& t_s,
                                      const std::vector<double>& reference_deg, double tau_s) {
  std::vector<double> lagged;
  FirstOrderLag(t_s, reference_deg, tau_s, &lagged);
  std::vector<double> d(reference_deg.size());
  for (size_t k = 0; k < d.size(); ++k) {
    d[k] = std::isnan(lagged[k]) || std::isnan(reference_deg[k])
               ? std::numeric_limits<double>::quiet_NaN()
               : WrapDeg180(lagged[k] - reference_deg[k]);
  }
  return d;
}

std::vector<AccuracyPoint> PlateauErrors(const std::vector<double>& error_deg,
                                         const Segmentation& segmentation,
                                         const PlateauNoise& noise, double resolution_deg) {
  std::vector<AccuracyPoint> points;
  int sweep = 1;
  for (size_t i = 0; i < segmentation.plateaus.size(); ++i) {
    const Plateau& p = segmentation.plateaus[i];
    const std::vector<double> e = Slice(error_deg, p.begin, p.end);
    AccuracyPoint pt;
    pt.index = i;
    pt.reference_deg = p.reference_deg;
    const double n = static_cast<double>(e.size());
    pt.error_deg = WrapDeg180(Mean(e));  // JCGM 100 4.2.1
    pt.mean_deg = WrapDeg180(p.reference_deg + pt.error_deg);
    double ss = 0.0;
    for (double v : e) ss += (v - pt.error_deg) * (v - pt.error_deg);
    pt.type_a.n = static_cast<int64_t>(e.size());
    pt.type_a.std_deg = e.size() > 1 ? std::sqrt(ss / (n - 1.0)) : 0.0;  // 4.2.2
    // u of the mean from the pooled AR(1) noise (4.2.3 with the autocorrelation counted);
    // floored by the packets' quantisation, q / sqrt(12 n) (F.2.2.1).
    const double f = Ar1MeanVarianceFactor(e.size(), noise.phi);
    pt.type_a.u_deg =
        std::max(noise.sigma_deg * std::sqrt(f), resolution_deg / std::sqrt(12.0 * n));
    pt.type_a.n_eff = f > 0.0 ? 1.0 / f : n;
    pt.type_a.dof = std::max(noise.dof, 1.0);
    pt.t_start_s = p.t_start_s;
    pt.t_end_s = p.t_end_s;
    pt.settle_samples = p.settle_samples;
    if (i > 0) {
      const double move = p.reference_deg - points.back().reference_deg;
      pt.direction = move > 0.0 ? 1 : -1;
      if (pt.direction > 0 && points.back().direction < 0) ++sweep;
    }
    pt.sweep = sweep;
    points.push_back(pt);
  }
  return points;
}

SystematicError SystematicErrorOf(const std::vector<AccuracyPoint>& points) {
  SystematicError s;
  if (points.empty()) return s;
  const double m = static_cast<double>(points.size());
  double sum = 0.0, sum2 = 0.0;
  for (const AccuracyPoint& p : points) {
    sum += p.error_deg;
    sum2 += p.error_deg * p.error_deg;
    if (std::fabs(p.error_deg) > s.max_abs_deg) {
      s.max_abs_deg = std::fabs(p.error_deg);
      s.at_reference_deg = p.reference_deg;
    }
  }
  s.mean_deg = sum / m;
  s.rms_deg = std::sqrt(sum2 / m);
  double ss = 0.0;
  for (const AccuracyPoint& p : points)
    ss += (p.error_deg - s.mean_deg) * (p.error_deg - s.mean_deg);
  s.std_deg = points.size() > 1 ? std::sqrt(ss / (m - 1.0)) : 0.0;
  return s;
}

Result<ErrorCurve> FitErrorCurve(const std::vector<AccuracyPoint>& points, ErrorModel model,
                                 double angle_match_deg) {
  std::vector<FitPoint> fit_points;
  for (const AccuracyPoint& p : points) {
    fit_points.push_back({p.reference_deg, p.error_deg, p.type_a.u_deg, p.direction});
  }
  auto chosen = ChooseErrorModel(fit_points, model, angle_match_deg);
  if (!chosen.ok()) return chosen.error();
  ErrorCurve curve;
  curve.model = chosen.value();
  std::vector<ErrorTerm> terms = ErrorModelTerms(curve.model);
  curve.hysteresis_term = HysteresisOf(points, angle_match_deg).available;
  if (curve.hysteresis_term) terms.push_back(ErrorTerm::kHysteresis);
  auto fit = FitHarmonicModel(fit_points, terms);
  if (!fit.ok()) return fit.error();
  curve.fit = std::move(fit).value();
  for (const AccuracyPoint& p : points) {
    curve.max_prediction_u_deg =
        std::max(curve.max_prediction_u_deg, curve.fit.PredictionU(p.reference_deg));
  }
  return curve;
}

Linearity LinearityOf(const std::vector<AccuracyPoint>& points, double angle_match_deg) {
  Linearity lin;
  if (points.empty()) return lin;
  std::vector<double> centres;
  const std::vector<size_t> cluster = ClusterAngles(points, angle_match_deg, &centres);
  const size_t angles = centres.size();
  std::vector<std::vector<const AccuracyPoint*>> groups(angles);
  for (size_t i = 0; i < points.size(); ++i) groups[cluster[i]].push_back(&points[i]);
  Eigen::VectorXd mean(static_cast<Eigen::Index>(angles)), u2(static_cast<Eigen::Index>(angles));
  for (size_t c = 0; c < angles; ++c) {
    // The angle's mean error and its u from the plateaus' own u (up and down plateaus differ
    // by the hysteresis, a systematic effect that is part of the mean, not its uncertainty).
    const GroupMean g = MeanOfGroup(groups[c]);
    double sum_u2 = 0.0;
    for (const AccuracyPoint* p : groups[c]) sum_u2 += p->type_a.u_deg * p->type_a.u_deg;
    const double m = static_cast<double>(groups[c].size());
    mean(static_cast<Eigen::Index>(c)) = g.mean;
    u2(static_cast<Eigen::Index>(c)) = sum_u2 / (m * m);
  }
  lin.angles = angles;
  // Least-squares straight line through the angle means: d = (I - H) m, H = X (X^T X)^-1 X^T.
  const auto na = static_cast<Eigen::Index>(angles);
  Eigen::MatrixXd x(na, 2);
  for (Eigen::Index c = 0; c < na; ++c) {
    x(c, 0) = 1.0;
    x(c, 1) = centres[static_cast<size_t>(c)];
  }
  Eigen::MatrixXd residual_map = Eigen::MatrixXd::Identity(na, na);
  if (angles >= 2) {
    const Eigen::MatrixXd xtx = x.transpose() * x;
    const Eigen::Vector2d line = xtx.ldlt().solve(x.transpose() * mean);
    lin.line_offset_deg = line(0);
    lin.line_slope = line(1);
    residual_map -= x * xtx.ldlt().solve(x.transpose());
  } else {
    lin.line_offset_deg = mean(0);
  }
  const Eigen::VectorXd d = residual_map * mean;
  // JCGM 100 5.1.2 for the linear map: Cov(d) = (I - H) diag(u^2) (I - H)^T.
  const Eigen::MatrixXd cov = residual_map * u2.asDiagonal() * residual_map.transpose();
  double ss = 0.0;
  for (Eigen::Index c = 0; c < na; ++c) {
    ss += d(c) * d(c);
    if (std::fabs(d(c)) >= lin.max_abs_deviation_deg) {
      lin.max_abs_deviation_deg = std::fabs(d(c));
      lin.at_reference_deg = centres[static_cast<size_t>(c)];
      lin.u_max_abs_deviation_deg = std::sqrt(std::max(cov(c, c), 0.0));
    }
  }
  lin.rms_deviation_deg = std::sqrt(ss / static_cast<double>(angles));
  const double span = centres.back() - centres.front();
  lin.percent_of_span = span > 0.0 ? 100.0 * lin.max_abs_deviation_deg / span : 0.0;
  return lin;
}

Hysteresis HysteresisOf(const std::vector<AccuracyPoint>& points, double angle_match_deg) {
  Hysteresis h;
  std::vector<double> centres;
  const std::vector<size_t> cluster = ClusterAngles(points, angle_match_deg, &centres);
  for (size_t c = 0; c < centres.size(); ++c) {
    std::vector<const AccuracyPoint*> up, down;
    for (size_t i = 0; i < points.size(); ++i) {
      if (cluster[i] != c) continue;
      if (points[i].direction > 0) up.push_back(&points[i]);
      if (points[i].direction < 0) down.push_back(&points[i]);
    }
    if (up.empty() || down.empty()) continue;
    // Each side's u from its plateaus' own u: a between-plateau s of 2 or 3 plateaus is too
    // noisy to be taken as the larger (it made u(h) conservative, 40 of 40 covering); scatter
    // beyond the plateaus' u across angles enlarges the mean's u by the Birge ratio below.
    const GroupMean gu = MeanOfGroup(up, false), gd = MeanOfGroup(down, false);
    HysteresisPair pair;
    pair.reference_deg = centres[c];
    pair.up_error_deg = gu.mean;
    pair.down_error_deg = gd.mean;
    pair.hysteresis_deg = gu.mean - gd.mean;
    pair.u_deg = std::hypot(gu.u, gd.u);
    // JCGM 100 G.4.1 for the difference of two independent means.
    pair.dof = std::pow(pair.u_deg, 4) / (std::pow(gu.u, 4) / gu.dof + std::pow(gd.u, 4) / gd.dof);
    pair.up_count = gu.count;
    pair.down_count = gd.count;
    h.pairs.push_back(pair);
  }
  if (h.pairs.empty()) {
    h.note =
        "no table angle was visited both turning up and turning down: sweep up and back down "
        "through the same angles to measure hysteresis";
    return h;
  }
  h.available = true;
  double sw = 0.0, swh = 0.0, chi2 = 0.0;
  for (const HysteresisPair& p : h.pairs) {
    const double w = 1.0 / (p.u_deg * p.u_deg);
    sw += w;
    swh += w * p.hysteresis_deg;
    if (std::fabs(p.hysteresis_deg) >= h.max_abs_deg) {
      h.max_abs_deg = std::fabs(p.hysteresis_deg);
      h.u_max_abs_deg = p.u_deg;
      h.at_reference_deg = p.reference_deg;
    }
  }
  h.mean_deg = swh / sw;
  for (const HysteresisPair& p : h.pairs) {
    chi2 += std::pow((p.hysteresis_deg - h.mean_deg) / p.u_deg, 2);
  }
  // Inverse-variance weighted mean; u enlarged by the Birge ratio sqrt(chi2/(k-1)) when the
  // pairs scatter more than their u's allow (hysteresis that varies with angle).
  const double k = static_cast<double>(h.pairs.size());
  const double birge = h.pairs.size() > 1 ? std::sqrt(chi2 / (k - 1.0)) : 1.0;
  h.u_mean_deg = std::sqrt(1.0 / sw) * std::max(1.0, birge);
  h.note =
      fmt::format("{} angle(s) visited both ways; mean weighted by 1/u^2, its u {}", h.pairs.size(),
                  birge > 1.0 ? "enlarged by the Birge ratio" : "from the pairs' u");
  return h;
}

Repeatability RepeatabilityOf(const std::vector<AccuracyPoint>& points, double angle_match_deg) {
  // ISO 5725-2: pooled s of plateau errors at the same angle and direction.
  Repeatability r;
  r.sweeps = points.empty() ? 0 : points.back().sweep;
  std::vector<double> centres;
  const std::vector<size_t> cluster = ClusterAngles(points, angle_match_deg, &centres);
  double ss = 0.0, df = 0.0;
  for (size_t c = 0; c < centres.size(); ++c) {
    for (int d : {-1, 0, 1}) {
      std::vector<double> e;
      for (size_t i = 0; i < points.size(); ++i) {
        if (cluster[i] == c && points[i].direction == d) e.push_back(points[i].error_deg);
      }
      if (e.size() < 2) continue;
      const double mean = Mean(e);
      for (double v : e) ss += (v - mean) * (v - mean);
      df += static_cast<double>(e.size()) - 1.0;
      ++r.groups;
    }
  }
  if (df > 0.0) {
    r.available = true;
    r.s_r_deg = std::sqrt(ss / df);
    r.dof = df;
    r.u_s_r_deg = r.s_r_deg / std::sqrt(2.0 * df);  // JCGM 100 E.4.3
    r.note = fmt::format("pooled over {} (angle, direction) group(s) with >= 2 plateaus", r.groups);
  } else {
    r.note =
        "no table angle was visited twice in the same direction: repeat the sweep at least "
        "twice to measure repeatability";
  }
  return r;
}

CrossAxis CrossAxisOf(const std::string& quantity, const std::vector<AccuracyPoint>& points,
                      const std::vector<double>& mean_deg, const std::vector<double>& u_deg,
                      double angle_match_deg) {
  CrossAxis x;
  x.quantity = quantity;
  std::vector<double> v = mean_deg;
  UnwrapDegInPlace(&v);
  const auto [lo, hi] = std::minmax_element(v.begin(), v.end());
  x.span_deg = *hi - *lo;
  x.mean_deg = WrapDeg180(Mean(v));
  std::vector<FitPoint> pts;
  for (size_t i = 0; i < v.size(); ++i) pts.push_back({points[i].reference_deg, v[i], u_deg[i]});
  const AngleCoverage cov = CoverageOf(pts, angle_match_deg);
  if (cov.distinct >= 5 && cov.span_deg >= 180.0) {
    auto f = FitHarmonicModel(pts, {ErrorTerm::kOffset, ErrorTerm::kCos1, ErrorTerm::kSin1});
    if (f.ok()) {
      x.fitted = true;
      x.fit = std::move(f).value();
      const double a = x.fit.params[1], b = x.fit.params[2];
      x.amplitude_deg = std::hypot(a, b);
      if (x.amplitude_deg > 0.0) {
        // JCGM 100 5.2.2: g = (a, b) / A on the (a1, b1) block of the covariance.
        const double ga = a / x.amplitude_deg, gb = b / x.amplitude_deg;
        const auto& c = x.fit.covariance;
        x.u_amplitude_deg = std::sqrt(
            std::max(0.0, ga * ga * c[1][1] + 2.0 * ga * gb * c[1][2] + gb * gb * c[2][2]));
      }
    }
  }
  return x;
}

double UncorrectedMixtureU(const std::vector<AccuracyPoint>& points, double u_random_deg,
                           double coverage) {
  if (points.empty()) return 0.0;
  auto covered = [&](double u_expanded) {
    double sum = 0.0;
    for (const AccuracyPoint& p : points) {
      const double s = std::hypot(u_random_deg, p.type_a.u_deg);
      if (s <= 0.0) {
        sum += std::fabs(p.error_deg) <= u_expanded ? 1.0 : 0.0;
        continue;
      }
      sum += NormalCdf((u_expanded - p.error_deg) / s) - NormalCdf((-u_expanded - p.error_deg) / s);
    }
    return sum / static_cast<double>(points.size());
  };
  double lo = 0.0, hi = 1.0;
  while (covered(hi) < coverage && hi < 1e6) hi *= 2.0;
  for (int it = 0; it < 100; ++it) {
    const double mid = 0.5 * (lo + hi);
    (covered(mid) < coverage ? lo : hi) = mid;
  }
  return hi;
}

Status ReadingBudgets(const AccuracyOptions& options, AccuracyResult* r) {
  // JCGM 100 5.1.2, G.4.1, 6.2 via EvaluateGum; every sensitivity 1.
  const std::string ref_note =
      options.reference.u_deg > 0.0
          ? "table certificate (" + options.reference.source + "), standard uncertainty"
          : "table certificate not given: the table is treated as exact (give --reference-u)";
  const BudgetInput reading =
      NormalInput("reading_noise", r->reading_std_deg, r->reading_dof,
                  "Type A: the standard deviation of one reading, the plateaus' pooled AR(1) "
                  "noise (dof from its effective number of observations)");
  const BudgetInput table =
      NormalInput("reference", options.reference.u_deg, options.reference.dof, ref_note);
  BudgetInput resolution;
  resolution.name = "resolution";
  resolution.distribution = Distribution::kRectangular;
  resolution.half_width = options.resolution_deg / 2.0;
  resolution.u = options.resolution_deg / std::sqrt(12.0);  // JCGM 100 F.2.2.1
  resolution.sensitivity = 1.0;
  resolution.unit = "deg";
  resolution.note = fmt::format("{} deg packet resolution, rectangular, q/sqrt(12) (F.2.2.1)",
                                options.resolution_deg);
  const double fit_dof = r->fit.dof > 0 ? r->fit.dof : kInf;
  const BudgetInput prediction =
      NormalInput("fit_prediction", r->max_prediction_u_deg, fit_dof,
                  "u of the fitted correction, max over the plateaus of sqrt(g^T C g) (dof m - p)");
  // The plateau errors' scatter about the curve beyond their own noise (a fresh reading has
  // its own noise, counted by reading_noise): sqrt(max(0, s_res^2 - mean u_i^2)).
  double mean_u2 = 0.0;
  for (const AccuracyPoint& p : r->points) mean_u2 += p.type_a.u_deg * p.type_a.u_deg;
  mean_u2 /= static_cast<double>(std::max<size_t>(r->points.size(), 1));
  const double lack_of_fit =
      std::sqrt(std::max(0.0, r->fit.residual_rms_deg * r->fit.residual_rms_deg - mean_u2));
  const BudgetInput residual = NormalInput(
      "fit_residual", lack_of_fit, fit_dof,
      fmt::format("scatter of the plateau errors about the curve beyond their own Type A u "
                  "(lack of fit, repeatability): sqrt(max(0, s_res^2 - mean u_i^2)), s_res = "
                  "sqrt(sum r_i^2 / (m - p)) = {:.3g} deg",
                  r->fit.residual_rms_deg));
  std::vector<BudgetInput> corrected = {reading, prediction, residual};
  if (r->fit_hysteresis_term) {
    // The correction is the mean of the up and down curves; a reading of unknown direction is
    // h/2 above or below it: u = |h|/2 (the standard deviation of +-h/2), with u(h)/2.
    size_t h = 0;
    while (r->fit.terms[h] != ErrorTerm::kHysteresis) ++h;
    const double hv = r->fit.params[h], uh = r->fit.u[h];
    corrected.push_back(NormalInput(
        "hysteresis", 0.5 * std::hypot(hv, uh), r->fit.dof > 0 ? r->fit.dof : kInf,
        fmt::format("a reading's direction of approach is unknown: +-h/2 about the corrected "
                    "curve, h = {:.4g} +- {:.2g} deg fitted; u = sqrt(h^2 + u(h)^2) / 2",
                    hv, uh)));
  } else {
    corrected.push_back(RectangularInput(
        "hysteresis_not_measured", options.assumed_hysteresis_deg,
        fmt::format("no angle was visited both ways: hysteresis up to {} deg assumed "
                    "(rectangular, half-width the assumed bound; --assumed-hysteresis-deg)",
                    options.assumed_hysteresis_deg)));
  }
  corrected.push_back(table);
  corrected.push_back(resolution);
  auto c = EvaluateReadingBudget("corrected", corrected, options.coverage);
  if (!c.ok()) return c.error();
  r->corrected = std::move(c).value();
  if (r->fit_hysteresis_term) {
    // The +-h/2 part is two-valued, not normal: U from the distribution of +-h/2 plus the
    // rest (normal with the other inputs' u), k = U / u_c (UncorrectedMixtureU's method).
    size_t h = 0;
    while (r->fit.terms[h] != ErrorTerm::kHysteresis) ++h;
    GumResult& g = r->corrected.gum;
    const double half = 0.5 * r->fit.params[h];
    const double rest = std::sqrt(std::max(0.0, g.u * g.u - half * half));
    AccuracyPoint up, down;
    up.error_deg = half;
    down.error_deg = -half;
    const double expanded = UncorrectedMixtureU({up, down}, rest, options.coverage);
    g.expanded = expanded;
    g.k = g.u > 0.0 ? expanded / g.u : g.k;
    g.dof_note =
        "U from the distribution of +-h/2 (the reading's unknown direction of approach) plus "
        "the other inputs as a normal; k = U / u_c";
  }

  const BudgetInput systematic =
      NormalInput("systematic_error", r->systematic.rms_deg, static_cast<double>(r->points.size()),
                  "uncorrected error over the range: RMS of the plateau errors about zero, "
                  "sqrt(mean^2 + variance over the range) (JCGM 100 F.2.4.5; dof m)");
  std::vector<BudgetInput> random_inputs = {reading, table, resolution};
  if (!r->fit_hysteresis_term) random_inputs.push_back(corrected[3]);
  std::vector<BudgetInput> uncorrected = {systematic};
  uncorrected.insert(uncorrected.end(), random_inputs.begin(), random_inputs.end());
  auto u = EvaluateReadingBudget("uncorrected", uncorrected, options.coverage);
  if (!u.ok()) return u.error();
  r->uncorrected = std::move(u).value();
  auto random = EvaluateReadingBudget("random", random_inputs, options.coverage);
  if (!random.ok()) return random.error();
  r->random_expanded_deg = random.value().gum.expanded;
  r->uncorrected_max_abs_expanded_deg = r->random_expanded_deg + r->systematic.max_abs_deg;
  // The uncorrected error is the plateau errors' spread over the range plus the random part:
  // far from normal (a bounded, often bimodal systematic part), so its U is taken from that
  // distribution (UncorrectedMixtureU) and k = U / u_c is reported.
  GumResult& g = r->uncorrected.gum;
  r->uncorrected_gum_expanded_deg = g.expanded;
  const double mixture = UncorrectedMixtureU(r->points, random.value().gum.u, options.coverage);
  g.expanded = mixture;
  g.k = g.u > 0.0 ? mixture / g.u : g.k;
  g.dof_note =
      "U from the distribution of the uncorrected error over the covered range (the plateau "
      "errors, each with the random part; UncorrectedMixtureU), k = U / u_c";
  r->which_u =
      "quote U_corrected_deg for readings corrected by the fitted curve e(theta) (the tag or "
      "the user subtracts it); quote U_uncorrected_deg for raw readings anywhere in the covered "
      "range (it covers the stated share of them, not each angle); U_uncorrected_max_abs_deg "
      "bounds a raw reading at every plateau visited";
  return Status::Ok();
}

}  // namespace metro
