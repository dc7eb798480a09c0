#include "metro/stats/quantization.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "core/simd_clones.hpp"

namespace metro {
namespace {

// Values closer than the doubles' own rounding (1e-9 of the data's scale) are one value.
constexpr double kSameFraction = 1e-9;
// A gap is a whole multiple of the step when its ratio is within this of an integer.
constexpr double kWholeTolerance = 1e-3;

// The decision on the gaps between consecutive distinct values: the smallest gap q is the
// step when at least 95 % of the gaps are whole multiples of it. `for_each_gap(f)` calls f on
// every gap in ascending order of the values, twice (the gaps are not stored: 10^7 of them
// were 80 MB of a --allan run's peak).
template <typename ForEachGap>
double StepOfGaps(const ForEachGap& for_each_gap) {
  size_t count = 0;
  double q = std::numeric_limits<double>::infinity();
  for_each_gap([&](double g) {
    ++count;
    q = std::min(q, g);
  });
  if (count < 4) return 0.0;
  // Values printed with a fixed number of decimals differ by whole multiples of that step up
  // to the rounding of their binary representation.
  size_t whole = 0;
  for_each_gap([&](double g) {
    const double ratio = g / q;
    if (std::fabs(ratio - std::round(ratio)) <= kWholeTolerance) ++whole;
  });
  return static_cast<double>(whole) >= 0.95 * static_cast<double>(count) ? q : 0.0;
}

// The finite values of x in ascending order. A long series is distributed first into up to
// 2^20 buckets of equal width over [lo, hi] (the bucket index floor((v - lo) * scale) never
// decreases with v, so the buckets in turn, each sorted, are the sorted series) and the
// buckets sorted one by one: O(n) for values spread over the range, where one sort of 10^7
// values took most of a --allan run's time.
std::vector<double> SortedFinite(const double* x, size_t n, double lo, double hi) {
  size_t finite = 0;
  for (const double* p = x; p != x + n; ++p) finite += std::isfinite(*p) ? 1 : 0;
  constexpr size_t kDirectSort = 1 << 16;
  if (finite <= kDirectSort || !(hi > lo)) {
    std::vector<double> v;
    v.reserve(finite);
    for (const double* p = x; p != x + n; ++p) {
      if (std::isfinite(*p)) v.push_back(*p);
    }
    std::sort(v.begin(), v.end());
    return v;
  }
  // Straight from x into the buckets (no copy of the finite values first).
  const size_t buckets = std::min<size_t>(size_t{1} << 20, finite / 4);
  const double scale = static_cast<double>(buckets) / (hi - lo);
  const auto bucket_of = [&](double d) {
    const double b = std::floor((d - lo) * scale);
    return b <= 0.0 ? size_t{0} : std::min(buckets - 1, static_cast<size_t>(b));
  };
  std::vector<uint32_t> start(buckets + 1, 0);
  for (const double* p = x; p != x + n; ++p) {
    if (std::isfinite(*p)) ++start[bucket_of(*p) + 1];
  }
  for (size_t b = 0; b < buckets; ++b) start[b + 1] += start[b];
  std::vector<double> sorted(finite);
  std::vector<uint32_t> next(start.begin(), start.end() - 1);
  for (const double* p = x; p != x + n; ++p) {
    if (std::isfinite(*p)) sorted[next[bucket_of(*p)]++] = *p;
  }
  for (size_t b = 0; b < buckets; ++b) {
    if (start[b + 1] - start[b] > 1) {
      std::sort(sorted.begin() + start[b], sorted.begin() + start[b + 1]);
    }
  }
  return sorted;
}

// The step from the gaps the definition names, from every finite value in ascending order.
double StepBySorting(const double* x, size_t n, double lo, double hi, double same) {
  const std::vector<double> v = SortedFinite(x, n, lo, hi);
  return StepOfGaps([&](const auto& f) {
    for (size_t i = 0; i + 1 < v.size(); ++i) {
      if (v[i + 1] - v[i] > same) f(v[i + 1] - v[i]);
    }
  });
}

// Each finite value's bucket round((v - lo) / q): its lowest and highest value. False when a
// value lies more than kWholeTolerance q off the lattice or outside [0, buckets). The
// quotient is formed as a product with 1 / q: it differs from (v - lo) / q by about an ulp,
// which moves round() only near a half-integer, and those values are off the lattice either
// way (the caller then sorts), so the buckets are those of the division.
METRO_SIMD_CLONES
bool FillBuckets(const double* x, size_t n, double lo, double q, size_t buckets, double* low,
                 double* high) {
  const double inv_q = 1.0 / q;
  const double top = static_cast<double>(buckets);
  for (size_t i = 0; i < n; ++i) {
    const double v = x[i];
    if (!std::isfinite(v)) continue;
    const double k = (v - lo) * inv_q;
    const double r = std::round(k);
    if (std::fabs(k - r) > kWholeTolerance || r < 0.0 || r >= top) return false;
    const size_t b = static_cast<size_t>(r);
    low[b] = std::min(low[b], v);
    high[b] = std::max(high[b], v);
  }
  return true;
}

// The same gaps without a sort when the values sit on a lattice: a strided sample's smallest
// gap q is tried as the lattice step; if every value lies within 1e-3 q of lo + k q and the
// values at each k agree to `same`, a bucket per k orders them, and the gap between two
// occupied buckets is the lowest value of the upper one less the highest of the lower one:
// exactly the difference the sorted array would give. Returns false (the caller sorts) when
// the sample finds no candidate, a value is off the lattice, a bucket spreads, or the range
// holds too many buckets.
bool GapsOnLattice(const double* x, size_t n, double lo, double hi, double same,
                   std::vector<double>* gaps) {
  constexpr size_t kSample = 4096;
  // At most 2^20 buckets (16 MB of bounds) and 4 per value: beyond that a sort is cheaper.
  const double max_buckets = std::min(double{1 << 20}, 4.0 * static_cast<double>(n));
  std::vector<double> sample;
  sample.reserve(kSample + 1);
  const size_t stride = std::max<size_t>(1, n / kSample);
  for (size_t i = 0; i < n; i += stride) {
    if (std::isfinite(x[i])) sample.push_back(x[i]);
  }
  std::sort(sample.begin(), sample.end());
  double q = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i + 1 < sample.size(); ++i) {
    const double g = sample[i + 1] - sample[i];
    if (g > same) q = std::min(q, g);
  }
  if (!std::isfinite(q) || (hi - lo) / q > max_buckets) return false;
  const size_t buckets = static_cast<size_t>(std::llround((hi - lo) / q)) + 1;
  std::vector<double> low(buckets, std::numeric_limits<double>::infinity());
  std::vector<double> high(buckets, -std::numeric_limits<double>::infinity());
  if (!FillBuckets(x, n, lo, q, buckets, low.data(), high.data())) return false;
  double previous_high = -std::numeric_limits<double>::infinity();
  for (size_t b = 0; b < buckets; ++b) {
    if (!(low[b] <= high[b])) continue;  // empty
    if (high[b] - low[b] > same) return false;
    if (std::isfinite(previous_high)) gaps->push_back(low[b] - previous_high);
    previous_high = high[b];
  }
  return true;
}

}  // namespace

double QuantizationStep(const std::vector<double>& x) {
  return QuantizationStep(x.data(), x.size());
}

double QuantizationStep(const double* x, size_t n) {
  double lo = std::numeric_limits<double>::infinity();
  double hi = -lo;
  size_t finite = 0;
  for (const double* p = x; p != x + n; ++p) {
    const double d = *p;
    if (!std::isfinite(d)) continue;
    ++finite;
    lo = std::min(lo, d);
    hi = std::max(hi, d);
  }
  if (finite < 5) return 0.0;
  const double same = kSameFraction * std::max({std::fabs(lo), std::fabs(hi), hi - lo});
  std::vector<double> gaps;
  if (GapsOnLattice(x, n, lo, hi, same, &gaps)) {
    return StepOfGaps([&gaps](const auto& f) {
      for (double g : gaps) f(g);
    });
  }
  return StepBySorting(x, n, lo, hi, same);
}

}  // namespace metro
