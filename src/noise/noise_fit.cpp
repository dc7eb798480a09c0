#include "metro/noise/noise_fit.hpp"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <boost/math/distributions/chi_squared.hpp>
#include <boost/math/special_functions/erf.hpp>
#include <cmath>
#include <limits>
#include <memory>
#include <mutex>
#include <vector>

namespace metro {
namespace {

constexpr double kThinRatio = 1.9;         // Successive fitted taus at least this far apart.
constexpr double kRangeShare = 0.25;       // A term "rests on" taus where it is >= 25 %.
constexpr double kReadOffSlopeTol = 0.15;  // |local slope - term slope| for a read-off.
constexpr double kReadOffNear = 2.5;       // Points within this factor of the read-off tau.

struct Point {
  double tau_s;
  double var;
  double edf;
  size_t index;  // In the curve.
  // Model error of the sampling per unit B^2 and K^2 (NoiseFitOptions::discretization_error).
  double excess_b = 0.0;
  double excess_k = 0.0;
};

// ---- Model error of the sampling (issue #36) -----------------------------------------------
//
// The IEEE 952 factors hold at every tau = m tau0 for an integrating sampler (each sample the
// average of the rate over its interval). Point-sampled noise reads higher at short taus:
//   flicker (Kasdin 1992: y = (1 - z^-1)^(-1/2) of white noise of variance B^2, two-sided PSD
//   B^2 / (2 sin(pi nu)), nu in cycles per sample): the estimator's variance is
//     B^2 int_0^1/2 sin^2(pi m nu) g(pi m nu) / (m^2 sin^3(pi nu)) dnu
//   with g(x) = 2 sin^2 x (Allan) or (8/3) sin^4 x (Hadamard): 1/ln2 = 1.443 times the IEEE 952
//   factor at m = 1 (Allan, exact), 1.154 at 2, 1.050 at 4, 1.015 at 8, 1.005 at 16;
//   random walk b_k+1 = b_k + K sqrt(tau0) w_k: AVAR = K^2 tau / 3 + K^2 tau0^2 / (6 tau)
//   (taken for the Hadamard variance too, as an approximation).
// Both are 0 for white phase, white rate and a ramp.

// Variance per unit B^2 of point-sampled (Kasdin) flicker at m, NaN beyond m = 512 (where it is
// within 1e-4 of the IEEE 952 factor).
double PointSampledFlickerFactor(bool hadamard, int64_t m) {
  static std::mutex mutex;
  static std::vector<std::pair<int64_t, double>> cache[2];
  if (m < 1 || m > 512) return std::nan("");
  std::vector<std::pair<int64_t, double>>& c = cache[hadamard ? 1 : 0];
  {
    std::lock_guard<std::mutex> lock(mutex);
    for (const auto& e : c) {
      if (e.first == m) return e.second;
    }
  }
  const double kPi = 3.14159265358979323846;
  const int64_t nodes = 400 * m + 2000;  // ~ 400 per oscillation of sin(pi m nu)
  const double h = 0.5 / static_cast<double>(nodes);
  const double md = static_cast<double>(m);
  double sum = 0.0;
  for (int64_t i = 0; i < nodes; ++i) {  // midpoint rule
    const double nu = (static_cast<double>(i) + 0.5) * h;
    const double s = std::sin(kPi * nu), sm = std::sin(kPi * md * nu);
    const double g = hadamard ? 8.0 / 3.0 * sm * sm * sm * sm : 2.0 * sm * sm;
    sum += sm * sm * g / (md * md * s * s * s);
  }
  const double value = sum * h;
  std::lock_guard<std::mutex> lock(mutex);
  c.emplace_back(m, value);
  return value;
}
// The sampling's excess per unit coefficient of a term (B^2 or K^2) at a point; 0 for the
// others.
double ExcessFactor(const Point& p, NoiseTerm term) {
  if (term == NoiseTerm::kBiasInstability) return p.excess_b;
  if (term == NoiseTerm::kRateRandomWalk) return p.excess_k;
  return 0.0;
}

// ---- Covariance of overlapping variance estimates ------------------------------------------
//
// For Gaussian noise an overlapping estimate is s_a^2 = sum_i d_a(i)^2 / norm_a with
// d_a(i) = sum_p w_p x_{i + p m_a} (Allan: w = 1, -2, 1, norm = 2 tau^2 M; Hadamard:
// w = -1, 3, -3, 1, norm = 6 tau^2 M; M terms). Then (Isserlis)
//   Cov(s_a^2, s_b^2) = sum_{i,j} [2 C(j - i)^2 + 4 mu_a mu_b C(j - i)] / (norm_a norm_b)
// with C(k) = Cov(d_a(i), d_b(i + k)) = sum_{p,q} w_p w_q G(p m_a - q m_b - k), where G is the
// generalized autocovariance of the phase (defined up to a quadratic, which the stencils
// annihilate; Greenhall 1983) and mu = R tau^2 the second difference of a rate ramp. Per unit
// squared coefficient, h in samples:
//   Q (white phase):   G(0) = 1, else 0
//   N (white rate):    G(h) = -tau0 |h| / 2
//   B (flicker rate):  G(h) = tau0^2 h^2 ln|h| / (2 pi)      (two-sided S_y = B^2 / (2 pi f))
//   K (random walk):   G(h) = tau0^3 |h|^3 / 12
// C is linear in the coefficients, so Cov is a quadratic form in c, assembled from sums
// S_tu = sum_k n(k) C_t(k) C_u(k) and S_t = sum_k n(k) C_t(k) (n(k): pairs i, j with
// j - i = k) computed once per curve. C_N and C_K vanish outside the stencils' overlap; C_B
// decays as k^-2 and is summed to 32 stencil spans (the rest is below 1e-4 of the sum).
// Long smooth stretches are integrated (Gauss-Legendre plus the Euler-Maclaurin end
// correction); stretches next to a kink are summed exactly.

constexpr int kTypes = 4;  // Q, N, B, K: the noise terms (the ramp enters through mu).

struct PairSums {
  std::array<std::array<double, kTypes>, kTypes> s2{};
  std::array<double, kTypes> s1{};
};

struct CovarianceBasis {
  bool overlapping = true;  // false: adev, hdev (no sums are computed)
  bool hadamard = false;
  std::vector<double> tau_s;
  std::vector<double> norm;       // norm_factor tau^2 M
  std::vector<double> gap_scale;  // (gap-free terms / terms), >= 1
  std::vector<PairSums> sums;     // n x n, row-major
};

class PairSummer {
 public:
  PairSummer(const std::vector<double>& w, int64_t m_a, int64_t m_b, int64_t n_a, int64_t n_b,
             double tau0)
      : w_(w), m_a_(m_a), m_b_(m_b), n_a_(n_a), n_b_(n_b), tau0_(tau0) {
    for (size_t p = 0; p < w_.size(); ++p) {
      for (size_t q = 0; q < w_.size(); ++q) {
        const int64_t k = static_cast<int64_t>(p) * m_a_ - static_cast<int64_t>(q) * m_b_;
        breaks_.push_back(k);
      }
    }
    bp_min_ = *std::min_element(breaks_.begin(), breaks_.end());
    bp_max_ = *std::max_element(breaks_.begin(), breaks_.end());
  }

  PairSums Run() {
    const int64_t span = static_cast<int64_t>(w_.size() - 1) * (m_a_ + m_b_);
    const int64_t lo = std::max(-(n_a_ - 1), bp_min_ - 32 * span);
    const int64_t hi = std::min(n_b_ - 1, bp_max_ + 32 * span);
    if (lo > hi) return out_;
    std::vector<int64_t> nodes = {lo, hi + 1, 0, n_b_ - n_a_};
    nodes.insert(nodes.end(), breaks_.begin(), breaks_.end());
    std::sort(nodes.begin(), nodes.end());
    nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
    for (size_t j = 0; j + 1 < nodes.size(); ++j) {
      const int64_t u = std::max(nodes[j], lo), v = std::min(nodes[j + 1], hi + 1);
      if (u < v) Segment(u, v);
    }
    // White phase noise: C_Q is non-zero only at the break lags.
    std::vector<int64_t> lags = breaks_;
    std::sort(lags.begin(), lags.end());
    lags.erase(std::unique(lags.begin(), lags.end()), lags.end());
    for (int64_t k : lags) {
      const double cnt = Count(static_cast<double>(k));
      if (!(cnt > 0.0)) continue;
      double cq = 0.0;
      for (size_t p = 0; p < w_.size(); ++p) {
        for (size_t q = 0; q < w_.size(); ++q) {
          if (static_cast<int64_t>(p) * m_a_ - static_cast<int64_t>(q) * m_b_ == k) {
            cq += w_[p] * w_[q];
          }
        }
      }
      std::array<double, kTypes> c{};
      Smooth(static_cast<double>(k), &c);
      c[0] = cq;
      for (int t = 0; t < kTypes; ++t) {
        out_.s2[0][static_cast<size_t>(t)] += cnt * cq * c[static_cast<size_t>(t)];
        if (t > 0) out_.s2[static_cast<size_t>(t)][0] += cnt * cq * c[static_cast<size_t>(t)];
      }
      out_.s1[0] += cnt * cq;
    }
    return out_;
  }

 private:
  double Count(double k) const {
    return std::min(static_cast<double>(n_a_), static_cast<double>(n_b_) - k) - std::max(0.0, -k);
  }

  // C_N, C_B, C_K at lag k (c[0], white phase, is left 0).
  void Smooth(double k, std::array<double, kTypes>* c) const {
    const double kPi = 3.14159265358979323846;
    const bool inside = k > static_cast<double>(bp_min_) && k < static_cast<double>(bp_max_);
    const double ref = std::max(1.0, std::fabs(k));  // G_B up to a quadratic: fewer digits lost
    double cn = 0.0, cb = 0.0, ck = 0.0;
    for (size_t p = 0; p < w_.size(); ++p) {
      for (size_t q = 0; q < w_.size(); ++q) {
        const double h = static_cast<double>(p) * static_cast<double>(m_a_) -
                         static_cast<double>(q) * static_cast<double>(m_b_) - k;
        const double ww = w_[p] * w_[q];
        const double ah = std::fabs(h);
        if (inside) {
          cn += ww * ah;
          ck += ww * ah * ah * ah;
        }
        if (ah > 0.0) cb += ww * h * h * std::log(ah / ref);
      }
    }
    (*c)[0] = 0.0;
    (*c)[1] = -0.5 * tau0_ * cn;
    (*c)[2] = tau0_ * tau0_ / (2.0 * kPi) * cb;
    (*c)[3] = tau0_ * tau0_ * tau0_ / 12.0 * ck;
  }

  void Add(double k, double weight) {
    const double cnt = Count(k);
    if (!(cnt > 0.0)) return;
    std::array<double, kTypes> c{};
    Smooth(k, &c);
    for (size_t t = 1; t < kTypes; ++t) {
      for (size_t u = 1; u < kTypes; ++u) out_.s2[t][u] += weight * cnt * c[t] * c[u];
      out_.s1[t] += weight * cnt * c[t];
    }
  }

  void GaussLegendre(double a, double b) {
    // 8-point Gauss-Legendre nodes and weights on [-1, 1].
    static const double x[4] = {0.1834346424956498, 0.5255324099163290, 0.7966664774136267,
                                0.9602898564975363};
    static const double w[4] = {0.3626837833783620, 0.3137066458778873, 0.2223810344533745,
                                0.1012285362903763};
    const double mid = 0.5 * (a + b), half = 0.5 * (b - a);
    for (int i = 0; i < 4; ++i) {
      Add(mid - half * x[i], half * w[i]);
      Add(mid + half * x[i], half * w[i]);
    }
  }

  // sum_{k=u}^{v-1} f(k), f smooth between the kinks at u and v.
  void Segment(int64_t u, int64_t v) {
    constexpr int64_t kExact = 16;
    if (v - u <= 4 * kExact) {
      for (int64_t k = u; k < v; ++k) Add(static_cast<double>(k), 1.0);
      return;
    }
    for (int64_t k = u; k < u + kExact; ++k) Add(static_cast<double>(k), 1.0);
    for (int64_t k = v - kExact; k < v; ++k) Add(static_cast<double>(k), 1.0);
    const int64_t a = u + kExact, b = v - kExact;  // sum over [a, b)
    // Midpoint rule with its Euler-Maclaurin correction: sum = int_{a-1/2}^{b-1/2} f
    //   - (f'(b - 1/2) - f'(a - 1/2)) / 24, f' from the neighbouring integers.
    Add(static_cast<double>(b), -1.0 / 24.0);
    Add(static_cast<double>(b - 1), 1.0 / 24.0);
    Add(static_cast<double>(a), 1.0 / 24.0);
    Add(static_cast<double>(a - 1), -1.0 / 24.0);
    double left = static_cast<double>(a) - 0.5, right = static_cast<double>(b) - 0.5;
    double len = static_cast<double>(kExact);
    while (right - left > 2.0 * len) {  // pieces growing geometrically away from the kinks
      GaussLegendre(left, left + len);
      GaussLegendre(right - len, right);
      left += len;
      right -= len;
      len *= 2.0;
    }
    GaussLegendre(left, right);
  }

  const std::vector<double>& w_;
  int64_t m_a_, m_b_, n_a_, n_b_;
  double tau0_;
  std::vector<int64_t> breaks_;
  int64_t bp_min_ = 0, bp_max_ = 0;
  PairSums out_;
};

struct BasisKey {
  AllanEstimator estimator;
  double tau0_s;
  std::vector<int64_t> m, n_terms, n_gap_free;
  bool operator==(const BasisKey& o) const {
    return estimator == o.estimator && tau0_s == o.tau0_s && m == o.m && n_terms == o.n_terms &&
           n_gap_free == o.n_gap_free;
  }
};

// The sums for the fitted points; a few recent curves are remembered (many records of one
// length and rate, e.g. a batch or the coverage simulations, share them).
std::shared_ptr<const CovarianceBasis> GetCovarianceBasis(const BasisKey& key) {
  static std::mutex mutex;
  static std::vector<std::pair<BasisKey, std::shared_ptr<const CovarianceBasis>>> cache;
  {
    std::lock_guard<std::mutex> lock(mutex);
    for (const auto& entry : cache) {
      if (entry.first == key) return entry.second;
    }
  }
  auto basis = std::make_shared<CovarianceBasis>();
  const EstimatorShape shape = ShapeOf(key.estimator);
  basis->hadamard = shape.d == 3;
  basis->overlapping = shape.overlapping;
  const std::vector<double> w = basis->hadamard ? std::vector<double>{-1.0, 3.0, -3.0, 1.0}
                                                : std::vector<double>{1.0, -2.0, 1.0};
  const double norm_factor = basis->hadamard ? 6.0 : 2.0;
  const size_t n = key.m.size();
  for (size_t i = 0; i < n; ++i) {
    const double tau = key.tau0_s * static_cast<double>(key.m[i]);
    basis->tau_s.push_back(tau);
    basis->norm.push_back(norm_factor * tau * tau * static_cast<double>(key.n_gap_free[i]));
    basis->gap_scale.push_back(static_cast<double>(key.n_gap_free[i]) /
                               static_cast<double>(std::max<int64_t>(1, key.n_terms[i])));
  }
  basis->sums.resize(n * n);
  for (size_t a = 0; a < n && basis->overlapping; ++a) {
    for (size_t b = a; b < n; ++b) {
      PairSummer summer(w, key.m[a], key.m[b], key.n_gap_free[a], key.n_gap_free[b], key.tau0_s);
      const PairSums s = summer.Run();
      basis->sums[a * n + b] = s;
      PairSums t;  // the transpose pair: C_ba(k) = C_ab(-k), same sums with t, u swapped
      for (size_t x = 0; x < kTypes; ++x) {
        for (size_t y = 0; y < kTypes; ++y) t.s2[x][y] = s.s2[y][x];
      }
      t.s1 = s.s1;
      basis->sums[b * n + a] = t;
    }
  }
  std::lock_guard<std::mutex> lock(mutex);
  cache.emplace_back(key, basis);
  if (cache.size() > 8) cache.erase(cache.begin());
  return basis;
}

// Cov(s_a^2, s_b^2) for squared coefficients c = [Q^2, N^2, B^2, K^2, R^2].
Eigen::MatrixXd VarianceCovariance(const CovarianceBasis& basis,
                                   const std::array<double, kNoiseTermCount>& c) {
  const size_t n = basis.tau_s.size();
  Eigen::MatrixXd cov(n, n);
  const double ramp = basis.hadamard ? 0.0 : c[4];
  for (size_t a = 0; a < n; ++a) {
    for (size_t b = 0; b < n; ++b) {
      const PairSums& s = basis.sums[a * n + b];
      double quad = 0.0, lin = 0.0;
      for (size_t t = 0; t < kTypes; ++t) {
        for (size_t u = 0; u < kTypes; ++u) quad += c[t] * c[u] * s.s2[t][u];
        lin += c[t] * s.s1[t];
      }
      const double ta2 = basis.tau_s[a] * basis.tau_s[a], tb2 = basis.tau_s[b] * basis.tau_s[b];
      cov(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(b)) =
          (2.0 * quad + 4.0 * ramp * ta2 * tb2 * lin) / (basis.norm[a] * basis.norm[b]) *
          std::sqrt(basis.gap_scale[a] * basis.gap_scale[b]);
    }
  }
  return 0.5 * (cov + cov.transpose());
}

struct SubsetFit {
  bool fitted = false;  // The solve succeeded (chi2 and z are defined).
  bool admissible = false;
  std::vector<int> terms;
  Eigen::VectorXd c;
  Eigen::MatrixXd cov;
  Eigen::MatrixXd cov_stat;  // Without the model error (discretization, relative_floor).
  Eigen::VectorXd z;         // Standardized residuals (s^2 - model) / sqrt(Cov_ii).
  double chi2 = 0.0;
  double score = 0.0;  // chi2 + the terms' penalties.
};

// One subset of terms by generalized least squares, iterated: the covariance of the variance
// estimates is that of the subset's own fitted model (negative coefficients count as 0), plus
// the relative floor on the diagonal; the start is a fit weighted by the chi-squared variance
// 2 s^4 / edf of each point alone.
SubsetFit FitSubset(const std::vector<Point>& pts, const std::vector<int>& terms,
                    AllanEstimator estimator, const CovarianceBasis& basis,
                    const NoiseFitOptions& options) {
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
      const auto term = static_cast<NoiseTerm>(terms[static_cast<size_t>(j)]);
      const Point& p = pts[static_cast<size_t>(i)];
      METRO_CHECK(NoiseBasis(estimator, term, p.tau_s, &f));
      // The model at the midpoint of the two discretizations (see the excess below).
      if (options.discretization_error) f += 0.5 * ExcessFactor(p, term);
      a(i, j) = f;
    }
  }
  const double floor2 = 4.0 * options.relative_floor * options.relative_floor;
  Eigen::MatrixXd cov = Eigen::MatrixXd::Zero(n, n);
  for (int i = 0; i < n; ++i) {
    cov(i, i) = y(i) * y(i) * (2.0 / pts[static_cast<size_t>(i)].edf + floor2);
  }
  Eigen::VectorXd c = Eigen::VectorXd::Zero(k);
  Eigen::MatrixXd c_cov;
  // Model error in cov: the relative floor on the diagonal, and the sampling's excess e as one
  // systematic pattern. The truth lies between the integrating sampler (the IEEE 952 factors)
  // and the point sampler (+e), and a real sensor may sit at either end, so the model is taken
  // at the midpoint (+e/2, in the design matrix above) with the pattern (e/2)(e/2)': a nuisance
  // amplitude a ~ N(0, 1) times e/2 (the standard deviation of a two-point distribution of
  // half-width e/2; JCGM 100 4.3.7's rectangular e/(2 sqrt 3) would put both ends, where real
  // samplers are, at 1.7 standard deviations). The data may absorb a at a chi2 cost of a^2, so
  // neither discretization biases a term.
  Eigen::VectorXd floor_diag = Eigen::VectorXd::Zero(n);
  Eigen::VectorXd excess = Eigen::VectorXd::Zero(n);
  double chi2 = 0.0;
  for (int it = 0; it <= options.iterations; ++it) {
    const Eigen::LLT<Eigen::MatrixXd> llt(cov);
    if (llt.info() != Eigen::Success) return out;
    Eigen::MatrixXd aw = llt.matrixL().solve(a);
    const Eigen::VectorXd yw = llt.matrixL().solve(y);
    // Columns scaled to unit norm: the basis spans many decades.
    Eigen::VectorXd col = aw.colwise().norm().transpose();
    for (int j = 0; j < k; ++j) {
      if (!(col(j) > 0.0)) return out;
      aw.col(j) /= col(j);
    }
    const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(aw);
    if (qr.rank() < k) return out;
    c = qr.solve(yw).cwiseQuotient(col);
    const Eigen::MatrixXd normal = aw.transpose() * aw;
    c_cov = col.cwiseInverse().asDiagonal() * normal.inverse() * col.cwiseInverse().asDiagonal();
    chi2 = llt.matrixL().solve(y - a * c).squaredNorm();
    if (it == options.iterations) {
      const Eigen::VectorXd r = y - a * c;
      out.z.resize(n);
      for (int i = 0; i < n; ++i) out.z(i) = r(i) / std::sqrt(cov(i, i));
      // The same normal matrix without the model error: u_stat.
      Eigen::MatrixXd stat = cov;
      stat -= excess * excess.transpose();
      for (int i = 0; i < n; ++i) stat(i, i) -= floor_diag(i);
      const Eigen::LLT<Eigen::MatrixXd> llt_stat(stat);
      if (llt_stat.info() == Eigen::Success) {
        const Eigen::MatrixXd as = llt_stat.matrixL().solve(a) * col.cwiseInverse().asDiagonal();
        const Eigen::MatrixXd ns = as.transpose() * as;
        out.cov_stat =
            col.cwiseInverse().asDiagonal() * ns.inverse() * col.cwiseInverse().asDiagonal();
      } else {
        out.cov_stat = c_cov;
      }
      break;
    }
    std::array<double, kNoiseTermCount> cfull{};
    for (int j = 0; j < k; ++j)
      cfull[static_cast<size_t>(terms[static_cast<size_t>(j)])] = std::max(0.0, c(j));
    std::vector<double> model(static_cast<size_t>(n), 0.0);
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < k; ++j) model[static_cast<size_t>(i)] += a(i, j) * std::max(0.0, c(j));
    }
    if (basis.overlapping) {
      cov = VarianceCovariance(basis, cfull);
    } else {  // Non-overlapping estimates: chi-squared variances of the points alone.
      cov.setZero();
      for (int i = 0; i < n; ++i) {
        const double m = model[static_cast<size_t>(i)];
        cov(i, i) = 2.0 * m * m / pts[static_cast<size_t>(i)].edf;
      }
    }
    for (int i = 0; i < n; ++i) {
      const double m = model[static_cast<size_t>(i)];
      const Point& p = pts[static_cast<size_t>(i)];
      // The sampling's excess (point-sampled minus integrating) and the floor.
      double e = 0.0;
      if (options.discretization_error) {
        e = 0.5 * (p.excess_b * cfull[static_cast<size_t>(NoiseTerm::kBiasInstability)] +
                   p.excess_k * cfull[static_cast<size_t>(NoiseTerm::kRateRandomWalk)]);
      }
      excess(i) = e;
      floor_diag(i) = floor2 * m * m;
      // A guard of 1e-6 of the data where the model leaves a point without noise (a
      // noiseless ramp, a term at zero).
      cov(i, i) += floor_diag(i) + 1e-12 * y(i) * y(i);
    }
    cov += excess * excess.transpose();
  }
  const int dof = n - k;
  double scale = 1.0;
  if (dof > 0) {
    // Birge ratio when the model does not describe the curve (chi2 above its 95 % quantile).
    const boost::math::chi_squared dist(dof);
    if (chi2 > boost::math::quantile(dist, 0.95)) scale = chi2 / dof;
  }
  out.c = c;
  out.cov = c_cov * scale;
  if (out.cov_stat.size() == 0) out.cov_stat = c_cov;
  out.cov_stat *= scale;
  out.chi2 = chi2;
  out.score = chi2;
  for (int t : terms) out.score += options.term_penalty[static_cast<size_t>(t)];
  out.fitted = true;
  out.admissible = true;
  for (int j = 0; j < k; ++j) {
    const double u = std::sqrt(std::max(out.cov(j, j), 0.0));
    if (!(c(j) > 0.0) || c(j) < options.min_significance * u) out.admissible = false;
  }
  return out;
}

// Log-log slope between the nearest curve points at least a factor kSlopeSpan below and above
// tau_i (independent of the tau spacing); NaN where either is missing.
constexpr double kSlopeSpan = 1.9;
double SlopeBetween(const AllanCurve& curve, size_t lo, size_t hi) {
  return (std::log(curve.dev[hi]) - std::log(curve.dev[lo])) /
         (std::log(curve.tau_s[hi]) - std::log(curve.tau_s[lo]));
}
bool Neighbours(const AllanCurve& curve, size_t i, size_t* lo, size_t* hi) {
  bool have_lo = false, have_hi = false;
  for (size_t j = i; j-- > 0;) {
    if (curve.dev[j] > 0.0 && curve.tau_s[j] * kSlopeSpan <= curve.tau_s[i] * 1.0001) {
      *lo = j;
      have_lo = true;
      break;
    }
  }
  for (size_t j = i + 1; j < curve.size(); ++j) {
    if (curve.dev[j] > 0.0 && curve.tau_s[j] >= kSlopeSpan * curve.tau_s[i] * 0.9999) {
      *hi = j;
      have_hi = true;
      break;
    }
  }
  return have_lo && have_hi;
}
double LocalSlope(const AllanCurve& curve, size_t i) {
  size_t lo = 0, hi = 0;
  if (!Neighbours(curve, i, &lo, &hi)) return std::nan("");
  return SlopeBetween(curve, lo, hi);
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

// The sums of the points [lo, lo + len) of `basis`.
CovarianceBasis SubBasis(const CovarianceBasis& basis, size_t lo, size_t len) {
  CovarianceBasis out;
  out.overlapping = basis.overlapping;
  out.hadamard = basis.hadamard;
  const size_t n = basis.tau_s.size();
  out.tau_s.assign(basis.tau_s.begin() + static_cast<ptrdiff_t>(lo),
                   basis.tau_s.begin() + static_cast<ptrdiff_t>(lo + len));
  out.norm.assign(basis.norm.begin() + static_cast<ptrdiff_t>(lo),
                  basis.norm.begin() + static_cast<ptrdiff_t>(lo + len));
  out.gap_scale.assign(basis.gap_scale.begin() + static_cast<ptrdiff_t>(lo),
                       basis.gap_scale.begin() + static_cast<ptrdiff_t>(lo + len));
  if (basis.sums.size() == n * n) {
    out.sums.resize(len * len);
    for (size_t a = 0; a < len; ++a) {
      for (size_t b = 0; b < len; ++b) out.sums[a * len + b] = basis.sums[(lo + a) * n + lo + b];
    }
  }
  return out;
}

// The chosen subset of terms and each term's selection statistic.
struct Selection {
  bool ok = false;
  SubsetFit best;
  std::array<double, kNoiseTermCount> delta_chi2;
  SubsetFit with_both_bk;  // The chosen subset plus the one of B, K it lacks (if fitted).
};

// Every non-empty subset of `allowed` is fitted; among the admissible ones (each coefficient
// positive and significant) the smallest chi2 + penalties wins.
Selection SelectTerms(const std::vector<Point>& pts, const std::vector<int>& allowed,
                      AllanEstimator estimator, const CovarianceBasis& basis,
                      const NoiseFitOptions& options) {
  Selection out;
  out.delta_chi2.fill(std::nan(""));
  const int n_allowed = static_cast<int>(allowed.size());
  std::vector<SubsetFit> fits(static_cast<size_t>(1) << n_allowed);
  int best_mask = 0;
  for (int mask = 1; mask < (1 << n_allowed); ++mask) {
    std::vector<int> terms;
    for (int j = 0; j < n_allowed; ++j) {
      if (mask & (1 << j)) terms.push_back(allowed[static_cast<size_t>(j)]);
    }
    if (terms.size() > pts.size()) continue;
    SubsetFit& fit = fits[static_cast<size_t>(mask)];
    fit = FitSubset(pts, terms, estimator, basis, options);
    if (fit.admissible &&
        (best_mask == 0 || fit.score < fits[static_cast<size_t>(best_mask)].score)) {
      best_mask = mask;
    }
  }
  if (best_mask == 0) return out;
  out.ok = true;
  out.best = fits[static_cast<size_t>(best_mask)];
  int bit_b = 0, bit_k = 0;
  for (int j = 0; j < n_allowed; ++j) {
    if (allowed[static_cast<size_t>(j)] == static_cast<int>(NoiseTerm::kBiasInstability)) {
      bit_b = 1 << j;
    }
    if (allowed[static_cast<size_t>(j)] == static_cast<int>(NoiseTerm::kRateRandomWalk)) {
      bit_k = 1 << j;
    }
  }
  if (bit_b != 0 && bit_k != 0 && ((best_mask & bit_b) != 0) != ((best_mask & bit_k) != 0)) {
    out.with_both_bk = fits[static_cast<size_t>(best_mask | bit_b | bit_k)];
  }
  for (int j = 0; j < n_allowed; ++j) {
    const int other = best_mask ^ (1 << j);
    if (other == 0 || !fits[static_cast<size_t>(other)].fitted) continue;
    const double d = fits[static_cast<size_t>(other)].chi2 - out.best.chi2;
    out.delta_chi2[static_cast<size_t>(allowed[static_cast<size_t>(j)])] =
        (best_mask & (1 << j)) ? d : -d;
  }
  return out;
}

// chi2 of a chosen subset against chi-squared with n - k dof.
struct FitTest {
  bool tested = false;
  std::string not_tested;
  int dof = 0;
  double p_value = std::nan("");
};
FitTest TestFit(const SubsetFit& fit, size_t n_points) {
  FitTest t;
  t.dof = static_cast<int>(n_points) - static_cast<int>(fit.terms.size());
  if (t.dof < 1) {
    t.not_tested = fmt::format(
        "the model cannot be tested: {} fitted taus for {} terms leave no degree of freedom",
        n_points, fit.terms.size());
    return t;
  }
  if (!std::isfinite(fit.chi2)) {
    t.not_tested = "the model cannot be tested: chi2 is not finite";
    return t;
  }
  t.tested = true;
  t.p_value = boost::math::cdf(boost::math::complement(boost::math::chi_squared(t.dof), fit.chi2));
  return t;
}

// The fit's summary from a chosen subset over `pts`.
NoiseFit MakeNoiseFit(const Selection& sel, const std::vector<Point>& pts, AllanEstimator estimator,
                      const NoiseFitOptions& options) {
  const SubsetFit& best = sel.best;
  NoiseFit out;
  out.estimator = estimator;
  out.chi2 = best.chi2;
  out.n_points = static_cast<int>(pts.size());
  out.dof = out.n_points - static_cast<int>(best.terms.size());
  out.birge_ratio = out.dof > 0 ? std::sqrt(best.chi2 / out.dof) : 0.0;
  out.fit_tau_min_s = pts.front().tau_s;
  out.fit_tau_max_s = pts.back().tau_s;
  for (NoiseTerm t : kAllNoiseTerms) {
    NoiseTermEstimate& est = out.terms[static_cast<size_t>(t)];
    est.delta_chi2 = sel.delta_chi2[static_cast<size_t>(t)];
    est.penalty_chi2 = options.term_penalty[static_cast<size_t>(t)];
  }
  for (size_t a = 0; a < best.terms.size(); ++a) {
    const int ta = best.terms[a];
    const auto ia = static_cast<Eigen::Index>(a);
    NoiseTermEstimate& est = out.terms[static_cast<size_t>(ta)];
    const double c = best.c(ia);
    est.supported = true;
    est.value = std::sqrt(c);
    est.u = std::sqrt(std::max(best.cov(ia, ia), 0.0)) / (2.0 * est.value);
    const double u_stat = std::sqrt(std::max(best.cov_stat(ia, ia), 0.0)) / (2.0 * est.value);
    est.u_model = std::sqrt(std::max(est.u * est.u - u_stat * u_stat, 0.0));
    for (size_t b = 0; b < best.terms.size(); ++b) {
      out.covariance_c[static_cast<size_t>(ta)][static_cast<size_t>(best.terms[b])] =
          best.cov(ia, static_cast<Eigen::Index>(b));
    }
  }
  // B and K: their correlation, or the joint fit when the record cannot separate them.
  const auto index_of = [](const SubsetFit& f, NoiseTerm t) -> Eigen::Index {
    for (size_t a = 0; a < f.terms.size(); ++a) {
      if (f.terms[a] == static_cast<int>(t)) return static_cast<Eigen::Index>(a);
    }
    return -1;
  };
  const auto correlation = [](const Eigen::MatrixXd& cov, Eigen::Index a, Eigen::Index b) {
    const double d = std::sqrt(cov(a, a) * cov(b, b));
    return d > 0.0 ? cov(a, b) / d : std::nan("");
  };
  const Eigen::Index ib = index_of(best, NoiseTerm::kBiasInstability);
  const Eigen::Index ik = index_of(best, NoiseTerm::kRateRandomWalk);
  if (ib >= 0 && ik >= 0) out.bk_correlation = correlation(best.cov, ib, ik);
  const SubsetFit& both = sel.with_both_bk;
  if (both.fitted && !both.admissible) {
    const Eigen::Index jb = index_of(both, NoiseTerm::kBiasInstability);
    const Eigen::Index jk = index_of(both, NoiseTerm::kRateRandomWalk);
    bool positive = jb >= 0 && jk >= 0;
    for (Eigen::Index a = 0; positive && a < both.c.size(); ++a) positive = both.c(a) > 0.0;
    if (positive) {
      out.bk_joint = true;
      out.bk_correlation = correlation(both.cov, jb, jk);
      const auto fill = [&both](Eigen::Index j, NoiseTermEstimate* e) {
        e->supported = true;
        e->value = std::sqrt(both.c(j));
        e->u = std::sqrt(std::max(both.cov(j, j), 0.0)) / (2.0 * e->value);
        const double u_stat = std::sqrt(std::max(both.cov_stat(j, j), 0.0)) / (2.0 * e->value);
        e->u_model = std::sqrt(std::max(e->u * e->u - u_stat * u_stat, 0.0));
      };
      fill(jb, &out.joint_b);
      fill(jk, &out.joint_k);
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
      NoiseBasis(estimator, static_cast<NoiseTerm>(ta), p.tau_s, &f);
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
  for (double penalty : term_penalty) {
    if (!(penalty >= 0.0 && std::isfinite(penalty))) return fail("term_penalty must be >= 0");
  }
  if (!(model_alpha > 0.0 && model_alpha < 1.0)) return fail("model_alpha must be in (0, 1)");
  if (!(contradiction_z > 0.0 && std::isfinite(contradiction_z))) {
    return fail("contradiction_z must be > 0");
  }
  if (min_holding_points < 2) return fail("min_holding_points must be >= 2");
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
    pts.push_back({tau, curve.dev[i] * curve.dev[i], edf, i});
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
  BasisKey key{curve.estimator, curve.tau0_s, {}, {}, {}};
  for (const Point& p : pts) {
    key.m.push_back(curve.m[p.index]);
    key.n_terms.push_back(curve.n_terms[p.index]);
    key.n_gap_free.push_back(p.index < curve.n_terms_gap_free.size()
                                 ? curve.n_terms_gap_free[p.index]
                                 : curve.n_terms[p.index]);
  }
  const std::shared_ptr<const CovarianceBasis> basis = GetCovarianceBasis(key);
  for (Point& p : pts) {
    const int64_t m = curve.m[p.index];
    double f_b = 0.0;
    if (NoiseBasis(curve.estimator, NoiseTerm::kBiasInstability, p.tau_s, &f_b)) {
      const double point = PointSampledFlickerFactor(basis->hadamard, m);
      p.excess_b = std::isfinite(point) ? std::fabs(point - f_b) : 0.0;
    }
    p.excess_k = curve.tau0_s * curve.tau0_s / (6.0 * p.tau_s);
  }
  const Selection full = SelectTerms(pts, allowed, curve.estimator, *basis, options);
  if (!full.ok) {
    return MakeError(
        "noise fit: no combination of noise terms is supported by the data (every subset has a "
        "non-positive or insignificant coefficient)");
  }
  // Goodness of fit over the whole range (issue #36).
  NoiseModelCheck check;
  check.alpha = options.model_alpha;
  check.contradiction_z = options.contradiction_z;
  const FitTest test = TestFit(full.best, pts.size());
  for (size_t i = 0; i < pts.size(); ++i) {
    check.tau_s.push_back(pts[i].tau_s);
    check.z.push_back(full.best.z(static_cast<Eigen::Index>(i)));
  }
  Selection chosen = full;
  std::vector<Point> chosen_pts = pts;
  if (!test.tested) {
    check.not_tested = test.not_tested;
  } else {
    check.tested = true;
    check.chi2 = full.best.chi2;
    check.dof = test.dof;
    check.p_value = test.p_value;
    check.rejected = test.p_value < options.model_alpha;
    for (size_t i = 0; i < pts.size(); ++i) {
      if (std::fabs(check.z[i]) > options.contradiction_z) {
        check.contradicting_taus_s.push_back(pts[i].tau_s);
      }
    }
    if (!check.rejected) {
      check.holds_tau_min_s = pts.front().tau_s;
      check.holds_tau_max_s = pts.back().tau_s;
      check.holds_chi2 = check.chi2;
      check.holds_dof = check.dof;
      check.holds_p_value = check.p_value;
    } else if (options.restrict_to_holding_range) {
      // The widest stretch of consecutive fitted taus where a refit is accepted (the largest
      // p-value among stretches of that width).
      const size_t n = pts.size();
      const size_t min_len = static_cast<size_t>(options.min_holding_points);
      bool found = false;
      for (size_t len = n - 1; len >= min_len && len >= 2 && !found; --len) {
        double best_p = -1.0;
        for (size_t lo = 0; lo + len <= n; ++lo) {
          const std::vector<Point> sub(pts.begin() + static_cast<ptrdiff_t>(lo),
                                       pts.begin() + static_cast<ptrdiff_t>(lo + len));
          const CovarianceBasis sub_basis = SubBasis(*basis, lo, len);
          Selection sel = SelectTerms(sub, allowed, curve.estimator, sub_basis, options);
          if (!sel.ok) continue;
          const FitTest t = TestFit(sel.best, sub.size());
          if (!t.tested || t.p_value < options.model_alpha || t.p_value <= best_p) continue;
          best_p = t.p_value;
          found = true;
          chosen = std::move(sel);
          chosen_pts = sub;
          check.holds_tau_min_s = sub.front().tau_s;
          check.holds_tau_max_s = sub.back().tau_s;
          check.holds_chi2 = chosen.best.chi2;
          check.holds_dof = t.dof;
          check.holds_p_value = t.p_value;
        }
      }
    }
  }
  NoiseFit out = MakeNoiseFit(chosen, chosen_pts, curve.estimator, options);
  out.model_check = std::move(check);
  return out;
}

Result<std::vector<std::vector<double>>> AllanVarianceCovariance(
    const AllanCurve& curve, const std::array<double, kNoiseTermCount>& coefficients) {
  const EstimatorShape shape = ShapeOf(curve.estimator);
  if (!shape.overlapping || shape.modified) {
    return MakeError(
        fmt::format("variance covariance: defined for the overlapping oadev and ohdev, not {}",
                    AllanEstimatorName(curve.estimator)));
  }
  BasisKey key{
      curve.estimator, curve.tau0_s, curve.m, curve.n_terms,
      curve.n_terms_gap_free.size() == curve.size() ? curve.n_terms_gap_free : curve.n_terms};
  const std::shared_ptr<const CovarianceBasis> basis = GetCovarianceBasis(key);
  std::array<double, kNoiseTermCount> c{};
  for (size_t t = 0; t < c.size(); ++t) c[t] = coefficients[t] * coefficients[t];
  const Eigen::MatrixXd cov = VarianceCovariance(*basis, c);
  std::vector<std::vector<double>> out(curve.size(), std::vector<double>(curve.size()));
  for (size_t a = 0; a < curve.size(); ++a) {
    for (size_t b = 0; b < curve.size(); ++b) {
      out[a][b] = cov(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(b));
    }
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
      // Only at an interior minimum that is flat: the slopes to the points a factor ~2 below
      // and above are both within the tolerance of 0 (a V where N meets K is not B).
      const AllanMinimum min = FindAllanMinimum(curve);
      if (!min.found || min.at_end || min.tau_s <= curve.tau_s.front()) continue;
      size_t i = 0;
      while (curve.tau_s[i] != min.tau_s) ++i;
      size_t lo = 0, hi = 0;
      if (!Neighbours(curve, i, &lo, &hi)) continue;
      if (!(std::fabs(SlopeBetween(curve, lo, i)) <= kReadOffSlopeTol &&
            std::fabs(SlopeBetween(curve, i, hi)) <= kReadOffSlopeTol)) {
        continue;
      }
      ro.found = true;
      ro.value = min.dev / std::sqrt(a);  // IEEE 952 Annex C: B = sigma_min / 0.6643
      ro.u = ro.value * RelativeU(curve, i);
      ro.tau_read_s = ro.tau_min_s = ro.tau_max_s = min.tau_s;
      continue;
    }
    // Read the line sigma(tau) = sqrt(a) tau^slope * coefficient where f(tau) = 1, from the
    // curve points within a factor kReadOffNear of that tau, and only when every one of them
    // has the term's slope (within kReadOffSlopeTol): a read-off is never extrapolated from
    // a distant stretch of the curve.
    const double tau_read = std::pow(a, -1.0 / (2.0 * slope));
    double sum_w = 0.0, sum_log = 0.0, best_u = std::numeric_limits<double>::infinity();
    bool all_on_slope = true;
    for (size_t i = 0; i < curve.size(); ++i) {
      if (!(curve.dev[i] > 0.0)) continue;
      if (curve.tau_s[i] < tau_read / kReadOffNear || curve.tau_s[i] > tau_read * kReadOffNear) {
        continue;
      }
      const double s = LocalSlope(curve, i);
      if (!(std::fabs(s - slope) <= kReadOffSlopeTol)) {
        all_on_slope = false;
        break;
      }
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
    if (!all_on_slope) ro = ReadOff();
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
  if (!fit.success) {
    return MakeFailedError("mean uncertainty: the noise fit failed: " + fit.message);
  }
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
