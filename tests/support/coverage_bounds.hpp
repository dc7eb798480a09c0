// Acceptance bounds for a coverage count, set by the number of records (tests only).
//
// A coverage test counts how many of n independent records have the truth within u (or 2u). A
// method whose true coverage is p gives a Binomial(n, p) count, so a bound that a correct
// method breaks with probability alpha follows from n: a test sized down to fewer records keeps
// the same false-alarm rate with bounds that widen as n falls, and the full-size measurement
// run (more records) tightens them again with the same code.
#pragma once

#include <algorithm>
#include <boost/math/distributions/binomial.hpp>
#include <cmath>

namespace metro::testing {

// The false-alarm probability of one bound. A coverage test makes about 100 of them: at 2e-4
// each a correct method fails one with probability about 2 %.
constexpr double kCoverageAlpha = 2e-4;

// The least count k with P(X < k) <= alpha for X ~ Binomial(n, p): a count below it says the
// rate is under p.
inline int MinCount(int n, double p, double alpha = kCoverageAlpha) {
  if (n <= 0 || p <= 0.0) return 0;
  if (p >= 1.0) return n;
  const boost::math::binomial_distribution<double> b(n, p);
  int k = static_cast<int>(std::floor(boost::math::quantile(b, alpha)));
  while (k > 0 && boost::math::cdf(b, k - 1) > alpha) --k;  // P(X <= k - 1) <= alpha
  while (k < n && boost::math::cdf(b, k) <= alpha) ++k;
  return std::clamp(k, 0, n);
}

// The greatest count k with P(X > k) <= alpha for X ~ Binomial(n, p): a count above it says the
// rate is over p.
inline int MaxCount(int n, double p, double alpha = kCoverageAlpha) {
  if (n <= 0) return 0;
  if (p <= 0.0) return 0;
  if (p >= 1.0) return n;
  const boost::math::binomial_distribution<double> b(n, p);
  int k = static_cast<int>(std::ceil(boost::math::quantile(boost::math::complement(b, alpha))));
  k = std::clamp(k, 0, n);
  while (k < n && boost::math::cdf(boost::math::complement(b, k)) > alpha) ++k;
  while (k > 0 && boost::math::cdf(boost::math::complement(b, k - 1)) <= alpha) --k;
  return k;
}

}  // namespace metro::testing
