#include "metro/noise/edf.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <boost/math/distributions/chi_squared.hpp>
#include <cmath>
#include <limits>

namespace metro {
namespace {

// Greenhall & Riley (2003) evaluate the generalized autocovariances at arguments up to
// about d + 1 + 1/F; long double keeps the F^2 second difference of sx accurate for large F.
using Real = long double;

constexpr int kJMax = 100;  // Greenhall & Riley's truncation of the basic sum.
const Real kInfinity = std::numeric_limits<Real>::infinity();

// Greenhall & Riley eq. (7): generalized autocovariance of the power-law phase noise.
// (The overall sign of each case cancels in the EDF, which is a ratio of squares.)
Real Sw(Real t, int alpha) {
  const Real a = std::fabs(t);
  switch (alpha) {
    case 2:
      return -a;
    case 1:
      return a == 0 ? 0 : t * t * std::log(a);
    case 0:
      return a * a * a;
    case -1:
      return a == 0 ? 0 : -(t * t) * (t * t) * std::log(a);
    case -2:
      return -(a * a) * (a * a) * a;
    case -3:
      return a == 0 ? 0 : (t * t) * (t * t) * (t * t) * std::log(a);
    case -4:
      return (a * a) * (a * a) * (a * a) * a;
  }
  METRO_CHECK(false);
  return 0;
}

// sx(t, F, alpha): the phase averaged over 1/F of tau (F = infinity: no averaging).
Real Sx(Real t, Real f, int alpha) {
  if (std::isinf(f)) return Sw(t, alpha + 2);
  return f * f * (2 * Sw(t, alpha) - Sw(t - 1 / f, alpha) - Sw(t + 1 / f, alpha));
}

// sz(t, F, alpha, d) = sum_{k=-d}^{d} (-1)^k C(2d, d+k) sx(t + k): d-th differences at lag tau.
Real Sz(Real t, Real f, int alpha, int d) {
  static const Real kBinomial[4][4] = {{1, 0, 0, 0}, {2, 1, 0, 0}, {6, 4, 1, 0}, {20, 15, 6, 1}};
  Real sum = kBinomial[d][0] * Sx(t, f, alpha);
  for (int k = 1; k <= d; ++k) {
    const Real sign = (k % 2 == 1) ? -1 : 1;
    sum += sign * kBinomial[d][k] * (Sx(t - k, f, alpha) + Sx(t + k, f, alpha));
  }
  return sum;
}

// BasicSum(J, M, S, F) = sz(0)^2 + (1 - J/M) sz(J/S)^2 + 2 sum_{j=1}^{J-1} (1 - j/M) sz(j/S)^2.
Real BasicSum(Real j_max, Real big_m, Real s, Real f, int alpha, int d) {
  const Real z0 = Sz(0, f, alpha, d);
  const Real zj = Sz(j_max / s, f, alpha, d);
  Real sum = z0 * z0 + (1 - j_max / big_m) * zj * zj;
  const int64_t last = static_cast<int64_t>(j_max);
  for (int64_t j = 1; j < last; ++j) {
    const Real z = Sz(static_cast<Real>(j) / s, f, alpha, d);
    sum += 2 * (1 - static_cast<Real>(j) / big_m) * z * z;
  }
  return sum;
}

// Greenhall & Riley Table 1 (modified variances): {a0, a1}, rows alpha = 2..-4, columns d.
bool Table1(int alpha, int d, Real* a0, Real* a1) {
  static const Real kTable[7][3][2] = {
      {{2.0L / 3, 1.0L / 3}, {7.0L / 9, 1.0L / 2}, {22.0L / 25, 2.0L / 3}},
      {{0.840L, 0.345L}, {0.997L, 0.616L}, {1.141L, 0.843L}},
      {{1.079L, 0.368L}, {1.033L, 0.607L}, {1.184L, 0.848L}},
      {{0, 0}, {1.048L, 0.534L}, {1.180L, 0.816L}},
      {{0, 0}, {1.302L, 0.535L}, {1.175L, 0.777L}},
      {{0, 0}, {0, 0}, {1.194L, 0.703L}},
      {{0, 0}, {0, 0}, {1.489L, 0.702L}}};
  *a0 = kTable[2 - alpha][d - 1][0];
  *a1 = kTable[2 - alpha][d - 1][1];
  return *a0 > 0;
}

// Greenhall & Riley Table 2 (unmodified variances).
bool Table2(int alpha, int d, Real* a0, Real* a1) {
  static const Real kTable[7][3][2] = {
      {{3.0L / 2, 1.0L / 2}, {35.0L / 18, 1}, {231.0L / 100, 3.0L / 2}},
      {{78.6L, 25.2L}, {790.0L, 410.0L}, {9950.0L, 6520.0L}},
      {{2.0L / 3, 1.0L / 6}, {2.0L / 3, 1.0L / 3}, {7.0L / 9, 1.0L / 2}},
      {{0, 0}, {0.852L, 0.375L}, {0.997L, 0.617L}},
      {{0, 0}, {1.079L, 0.368L}, {1.033L, 0.607L}},
      {{0, 0}, {0, 0}, {1.053L, 0.553L}},
      {{0, 0}, {0, 0}, {1.302L, 0.535L}}};
  *a0 = kTable[2 - alpha][d - 1][0];
  *a1 = kTable[2 - alpha][d - 1][1];
  return *a0 > 0;
}

// Greenhall & Riley Table 3 (alpha = 1, unmodified): {b0, b1}.
void Table3(int d, Real* b0, Real* b1) {
  static const Real kTable[3][2] = {{6.0L, 4.0L}, {15.23L, 12.0L}, {47.8L, 40.0L}};
  *b0 = kTable[d - 1][0];
  *b1 = kTable[d - 1][1];
}

Real Binomial(int n, int k) {
  Real r = 1;
  for (int i = 1; i <= k; ++i) r = r * (n - k + i) / i;
  return r;
}

}  // namespace

Result<double> GreenhallRileyEdf(int alpha, int d, int64_t m, int64_t n_phase, bool overlapping,
                                 bool modified) {
  if (alpha < -4 || alpha > 2) {
    return MakeError(fmt::format("EDF: noise exponent alpha = {} is outside [-4, 2]", alpha));
  }
  if (d < 1 || d > 3) return MakeError(fmt::format("EDF: difference order d = {} is not 1..3", d));
  if (alpha + 2 * d <= 1) {
    return MakeError(fmt::format("EDF: alpha = {} needs a difference order d > {} (alpha + 2d > 1)",
                                 alpha, (1 - alpha) / 2));
  }
  if (m < 1) return MakeError(fmt::format("EDF: averaging factor m = {} is below 1", m));
  // L = m/F + m d with F = 1 (modified) or m (unmodified); S = m (overlapping) or 1.
  const int64_t length = (modified ? m : 1) + m * d;
  if (n_phase < length) {
    return MakeError(
        fmt::format("EDF: {} phase points are fewer than the filter length L = {} at m = {}",
                    n_phase, length, m));
  }
  const Real mm = static_cast<Real>(m);
  const Real s = overlapping ? mm : 1;
  const Real big_m =
      static_cast<Real>(overlapping ? 1 + (n_phase - length) : 1 + (n_phase - length) / m);
  const Real j = std::min(big_m, (d + 1) * s);
  const Real r = big_m / s;
  Real inv_edf = 0;
  if (modified) {
    // Case 1: modified variances, all alpha.
    if (j <= kJMax) {
      const Real z0 = Sz(0, 1, alpha, d);
      inv_edf = BasicSum(j, big_m, s, 1, alpha, d) / (z0 * z0 * big_m);
    } else if (r > d + 1) {
      Real a0 = 0, a1 = 0;
      if (!Table1(alpha, d, &a0, &a1)) return MakeError("EDF: no Table 1 entry");
      inv_edf = (a0 - a1 / r) / r;
    } else {
      const Real m_prime = kJMax / r;
      const Real z0 = Sz(0, 1, alpha, d);
      inv_edf = BasicSum(kJMax, kJMax, m_prime, 1, alpha, d) / (z0 * z0 * kJMax);
    }
  } else if (alpha <= 0) {
    // Case 2: unmodified variances, alpha <= 0.
    if (j <= kJMax) {
      const Real m_prime = mm * (d + 1) <= kJMax ? mm : kInfinity;
      const Real z0 = Sz(0, m_prime, alpha, d);
      inv_edf = BasicSum(j, big_m, s, m_prime, alpha, d) / (z0 * z0 * big_m);
    } else if (r > d + 1) {
      Real a0 = 0, a1 = 0;
      if (!Table2(alpha, d, &a0, &a1)) return MakeError("EDF: no Table 2 entry");
      inv_edf = (a0 - a1 / r) / r;
    } else {
      const Real m_prime = kJMax / r;
      const Real z0 = Sz(0, kInfinity, alpha, d);
      inv_edf = BasicSum(kJMax, kJMax, m_prime, kInfinity, alpha, d) / (z0 * z0 * kJMax);
    }
  } else if (alpha == 1) {
    // Case 3: unmodified variances, flicker PM; the b0 + b1 ln m factor normalizes sz(0).
    Real b0 = 0, b1 = 0;
    Table3(d, &b0, &b1);
    const Real norm = b0 + b1 * std::log(mm);
    if (j <= kJMax) {
      const Real z0 = Sz(0, mm, 1, d);
      inv_edf = BasicSum(j, big_m, s, mm, 1, d) / (z0 * z0 * big_m);
    } else if (r > d + 1) {
      Real a0 = 0, a1 = 0;
      Table2(1, d, &a0, &a1);
      inv_edf = (a0 - a1 / r) / (norm * norm * r);
    } else {
      const Real m_prime = kJMax / r;
      inv_edf = BasicSum(kJMax, kJMax, m_prime, m_prime, 1, d) / (norm * norm * kJMax);
    }
  } else {
    // Case 4: unmodified variances, white PM.
    const Real k = std::ceil(r);
    if (k <= d) {
      // Here M <= d S < (d + 1) S, so J = M and the sum is exact.
      const Real z0 = Sz(0, mm, 2, d);
      inv_edf = BasicSum(big_m, big_m, s, mm, 2, d) / (z0 * z0 * big_m);
    } else {
      const Real a0 = Binomial(4 * d, 2 * d) / (Binomial(2 * d, d) * Binomial(2 * d, d));
      const Real a1 = static_cast<Real>(d) / 2;
      inv_edf = (a0 - a1 / r) / big_m;
    }
  }
  if (!(inv_edf > 0) || !std::isfinite(static_cast<double>(inv_edf))) {
    return MakeError(fmt::format("EDF: no positive value for alpha = {}, d = {}, m = {}, N = {}",
                                 alpha, d, m, n_phase));
  }
  return static_cast<double>(1 / inv_edf);
}

Result<double> SimpleOadevEdf(int alpha, int64_t m, int64_t n_phase) {
  if (alpha < -2 || alpha > 2) {
    return MakeError(fmt::format("simple EDF: alpha = {} is outside [-2, 2]", alpha));
  }
  if (m < 1 || n_phase < 2 * m + 1 || n_phase <= 3) {
    return MakeError(fmt::format("simple EDF: {} phase points are too few for m = {}", n_phase, m));
  }
  const double n = static_cast<double>(n_phase);
  const double md = static_cast<double>(m);
  double edf = 0.0;
  // NIST TN 1337 Table 12-4 (Howe, Allan & Barnes 1981); NIST SP 1065 Table 5.
  switch (alpha) {
    case 2:
      edf = (n + 1) * (n - 2 * md) / (2 * (n - md));
      break;
    case 1:
      edf =
          std::exp(std::sqrt(std::log((n - 1) / (2 * md)) * std::log((2 * md + 1) * (n - 1) / 4)));
      break;
    case 0:
      edf = (3 * (n - 1) / (2 * md) - 2 * (n - 2) / n) * 4 * md * md / (4 * md * md + 5);
      break;
    case -1:
      edf = m == 1 ? 2 * (n - 2) * (n - 2) / (2.3 * n - 4.9) : 5 * n * n / (4 * md * (n + 3 * md));
      break;
    case -2:
      edf =
          (n - 2) / md * ((n - 1) * (n - 1) - 3 * md * (n - 1) + 4 * md * md) / ((n - 3) * (n - 3));
      break;
  }
  if (!(edf > 0) || !std::isfinite(edf)) {
    return MakeError(fmt::format("simple EDF: no positive value for alpha = {}, m = {}, N = {}",
                                 alpha, m, n_phase));
  }
  return edf;
}

Result<DeviationInterval> ChiSquaredInterval(double deviation, double edf, double confidence) {
  if (!(std::isfinite(edf) && edf > 0.0)) {
    return MakeError(fmt::format("confidence interval: EDF {} is not a positive number", edf));
  }
  if (!(confidence > 0.0 && confidence < 1.0)) {
    return MakeError(fmt::format("confidence interval: level {} is not in (0, 1)", confidence));
  }
  if (!(std::isfinite(deviation) && deviation >= 0.0)) {
    return MakeError(fmt::format("confidence interval: deviation {} is not >= 0", deviation));
  }
  try {
    // NIST SP 1065 5.3.2.
    const boost::math::chi_squared_distribution<double> chi2(edf);
    const double tail = (1.0 - confidence) / 2.0;
    const double q_low = boost::math::quantile(chi2, tail);
    const double q_high = boost::math::quantile(chi2, 1.0 - tail);
    DeviationInterval interval;
    interval.low = deviation * std::sqrt(edf / q_high);
    interval.high = deviation * std::sqrt(edf / q_low);
    return interval;
  } catch (const std::exception& e) {
    return MakeError(
        fmt::format("confidence interval: Boost.Math failed for EDF {}: {}", edf, e.what()));
  }
}

}  // namespace metro
