#include "metro/stats/type_a.hpp"

#include <fftw3.h>
#include <fmt/format.h>

#include <algorithm>
#include <boost/math/distributions/students_t.hpp>
#include <cmath>
#include <map>
#include <mutex>
#include <vector>

namespace metro {
namespace {

// FFTW's planner is not thread-safe; plans are made and destroyed under this lock and
// executed outside it (fftw_execute on distinct plans is thread-safe).
std::mutex& FftwPlannerMutex() {
  static std::mutex mutex;
  return mutex;
}

// Smallest 2^a 3^b 5^c 7^d >= n: sizes FFTW transforms fastest.
size_t NextFastFftSize(size_t n) {
  for (size_t m = std::max<size_t>(n, 1);; ++m) {
    size_t r = m;
    for (size_t p : {2u, 3u, 5u, 7u}) {
      while (r % p == 0) r /= p;
    }
    if (r == 1) return m;
  }
}

// Lags computed directly (in one fused pass) before switching to the FFT.
constexpr size_t kDirectLags = 8;

// Lag sums c_k = sum_i d_i d_{i+k} for k = 0..kDirectLags of the centred series
// d_i = x_i - mean, in one pass with independent accumulators (the loop over k vectorises;
// no reassociation of a single running sum is needed). d is formed on the fly, the same
// doubles as a centred copy would hold, so no copy of the series is written.
void DirectLagSums(const double* x, double mean, size_t n, double* c) {
  double acc[kDirectLags + 1] = {};
  const size_t body = n > kDirectLags ? n - kDirectLags : 0;
  for (size_t i = 0; i < body; ++i) {
    const double di = x[i] - mean;
    for (size_t k = 0; k <= kDirectLags; ++k) acc[k] += di * (x[i + k] - mean);
  }
  for (size_t i = body; i < n; ++i) {
    for (size_t k = 0; i + k < n && k <= kDirectLags; ++k) {
      acc[k] += (x[i] - mean) * (x[i + k] - mean);
    }
  }
  for (size_t k = 0; k <= kDirectLags; ++k) c[k] = acc[k];
}

// Forward (r2c) and backward (c2r) plans of one transform size, made once per process
// and shared by all threads through FFTW's new-array execute functions (thread-safe).
struct FftPlans {
  fftw_plan forward = nullptr;
  fftw_plan backward = nullptr;
};

const FftPlans& PlansForSize(size_t size) {
  // Deliberately never destroyed: the plans live as long as the process (and stay
  // reachable, so leak checkers do not report them), and no thread can find a destroyed
  // plan during static destruction.
  static auto* cache = new std::map<size_t, FftPlans>();
  std::lock_guard<std::mutex> lock(FftwPlannerMutex());
  FftPlans& plans = (*cache)[size];
  if (plans.forward == nullptr) {
    double* real = fftw_alloc_real(size);
    fftw_complex* spectrum = fftw_alloc_complex(size / 2 + 1);
    plans.forward = fftw_plan_dft_r2c_1d(static_cast<int>(size), real, spectrum, FFTW_ESTIMATE);
    plans.backward = fftw_plan_dft_c2r_1d(static_cast<int>(size), spectrum, real, FFTW_ESTIMATE);
    fftw_free(real);
    fftw_free(spectrum);
  }
  return plans;
}

// Lag sums c_k = sum_i d_i d_{i+k}, k = 0..block, of the centred series d (length n), by
// block-wise FFT correlation (block a power of two). With x_b = d[b*L, (b+1)*L) and
// y_b = d[b*L, (b+2)*L), both zero-padded to M = 2L, circular correlation of x_b with y_b
// has no wrap-around for lags k <= L, so
//   c_k = sum_b IDFT(conj(X_b) . Y_b)[k] = IDFT(sum_b conj(X_b) . Y_b)[k] / M,
// and Y_b = X_b + (-1)^j X_{b+1} (x_{b+1} sits L = M/2 samples later). One forward
// transform of size M per block of L samples plus one backward transform in all: about
// 2n log2(2L) operations, in cache, instead of 3n log2(1.5n) for the whole-series padding.
void BlockLagSums(const double* d, size_t n, size_t block, double* c) {
  const size_t size = 2 * block;
  const size_t bins = block + 1;  // size / 2 + 1
  const FftPlans& plans = PlansForSize(size);
  double* real = fftw_alloc_real(size);
  fftw_complex* current = fftw_alloc_complex(bins);
  fftw_complex* next = fftw_alloc_complex(bins);
  fftw_complex* sum = fftw_alloc_complex(bins);
  auto transform = [&](size_t b, fftw_complex* out) {
    const size_t begin = b * block;
    const size_t count = begin < n ? std::min(block, n - begin) : 0;
    std::copy(d + begin, d + begin + count, real);
    std::fill(real + count, real + size, 0.0);
    fftw_execute_dft_r2c(plans.forward, real, out);
  };
  std::fill(&sum[0][0], &sum[0][0] + 2 * bins, 0.0);
  const size_t blocks = (n + block - 1) / block;
  transform(0, current);
  for (size_t b = 0; b < blocks; ++b) {
    if (b + 1 < blocks) {
      transform(b + 1, next);
    } else {
      std::fill(&next[0][0], &next[0][0] + 2 * bins, 0.0);
    }
    for (size_t j = 0; j < bins; ++j) {
      const double sign = (j & 1) != 0 ? -1.0 : 1.0;
      const double yr = current[j][0] + sign * next[j][0];
      const double yi = current[j][1] + sign * next[j][1];
      // conj(X) * Y
      sum[j][0] += current[j][0] * yr + current[j][1] * yi;
      sum[j][1] += current[j][0] * yi - current[j][1] * yr;
    }
    std::swap(current, next);
  }
  fftw_execute_dft_c2r(plans.backward, sum, real);
  for (size_t k = 0; k <= block; ++k) c[k] = real[k] / static_cast<double>(size);
  fftw_free(real);
  fftw_free(current);
  fftw_free(next);
  fftw_free(sum);
}

// First block length tried for lags beyond the direct ones; each retry is 16 x longer.
constexpr size_t kFirstLagBlock = 2048;

// Sum of x with four interleaved partial sums (pairwise-like accuracy, vectorisable).
double Sum4(const double* x, size_t n) {
  double a[4] = {0, 0, 0, 0};
  size_t i = 0;
  for (; i + 4 <= n; i += 4) {
    a[0] += x[i];
    a[1] += x[i + 1];
    a[2] += x[i + 2];
    a[3] += x[i + 3];
  }
  for (; i < n; ++i) a[0] += x[i];
  return (a[0] + a[1]) + (a[2] + a[3]);
}

}  // namespace

bool TypeAOptions::IsValid(std::string* why) const {
  if (!(band_confidence > 0.0 && band_confidence < 1.0)) {
    if (why) *why = "band_confidence must be in (0, 1)";
    return false;
  }
  if (!(max_lag_fraction > 0.0 && max_lag_fraction <= 0.5)) {
    if (why) *why = "max_lag_fraction must be in (0, 0.5]";
    return false;
  }
  return true;
}

void Autocorrelation(const double* x, size_t n, size_t max_lag, double* rho) {
  METRO_CHECK(n >= 1 && max_lag < n);
  double mean = 0.0;
  for (size_t i = 0; i < n; ++i) mean += x[i];
  mean /= static_cast<double>(n);
  // Zero padding to >= n + max_lag makes the circular correlation linear for those lags.
  const size_t size = NextFastFftSize(n + max_lag + 1);
  double* buffer = fftw_alloc_real(size);
  fftw_complex* spectrum = fftw_alloc_complex(size / 2 + 1);
  fftw_plan forward, backward;
  {
    std::lock_guard<std::mutex> lock(FftwPlannerMutex());
    forward = fftw_plan_dft_r2c_1d(static_cast<int>(size), buffer, spectrum, FFTW_ESTIMATE);
    backward = fftw_plan_dft_c2r_1d(static_cast<int>(size), spectrum, buffer, FFTW_ESTIMATE);
  }
  for (size_t i = 0; i < n; ++i) buffer[i] = x[i] - mean;
  std::fill(buffer + n, buffer + size, 0.0);
  fftw_execute(forward);
  for (size_t k = 0; k < size / 2 + 1; ++k) {
    const double re = spectrum[k][0];
    const double im = spectrum[k][1];
    spectrum[k][0] = re * re + im * im;
    spectrum[k][1] = 0.0;
  }
  fftw_execute(backward);
  const double c0 = buffer[0];
  for (size_t k = 0; k <= max_lag; ++k) rho[k] = c0 > 0.0 ? buffer[k] / c0 : 0.0;
  rho[0] = 1.0;
  {
    std::lock_guard<std::mutex> lock(FftwPlannerMutex());
    fftw_destroy_plan(forward);
    fftw_destroy_plan(backward);
  }
  fftw_free(buffer);
  fftw_free(spectrum);
}

Result<TypeAResult> EvaluateTypeA(const double* values, size_t n, const TypeAOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) return MakeError("invalid Type A options: " + why);
  if (n < 2) {
    return MakeError(fmt::format("{} observation{}: a Type A evaluation needs at least 2", n,
                                 n == 1 ? "" : "s"));
  }
  // A NaN or an infinity makes the sum non-finite, so the values are scanned only then.
  const double total = Sum4(values, n);
  if (!std::isfinite(total)) {
    for (size_t i = 0; i < n; ++i) {
      if (!std::isfinite(values[i])) {
        return MakeError(fmt::format("observation {} is not finite", i + 1));
      }
    }
    // Every value is finite but their sum is not: the mean cannot be formed in double.
    return MakeError(fmt::format("the sum of the {} observations overflows double precision", n));
  }
  const double dn = static_cast<double>(n);
  // Corrected two-pass algorithm (Chan, Golub & LeVeque 1983): centre on a first mean,
  // then correct with the residual sum, so no large sums of squares cancel.
  const double first = total / dn;
  double p1[4] = {0, 0, 0, 0}, p2[4] = {0, 0, 0, 0};
  size_t i4 = 0;
  for (; i4 + 4 <= n; i4 += 4) {
    for (size_t j = 0; j < 4; ++j) {
      const double d = values[i4 + j] - first;
      p1[j] += d;
      p2[j] += d * d;
    }
  }
  for (; i4 < n; ++i4) {
    const double d = values[i4] - first;
    p1[0] += d;
    p2[0] += d * d;
  }
  const double s1 = (p1[0] + p1[1]) + (p1[2] + p1[3]);
  const double s2 = (p2[0] + p2[1]) + (p2[2] + p2[3]);
  TypeAResult r;
  r.n = static_cast<int64_t>(n);
  r.mean = first + s1 / dn;
  r.variance = std::max(0.0, (s2 - s1 * s1 / dn) / (dn - 1.0));  // JCGM 100 4.2.2
  r.std = std::sqrt(r.variance);
  r.variance_of_mean = r.variance / dn;  // JCGM 100 4.2.3
  r.std_of_mean = std::sqrt(r.variance_of_mean);
  r.dof = r.n - 1;
  r.n_eff = dn;
  r.std_of_mean_autocorr = r.std_of_mean;
  if (!options.autocorrelation || n < 4 || r.variance == 0.0) return r;

  // Zhang (2006): variance factor from the autocorrelation up to the cut-off lag.
  double direct[kDirectLags + 1];
  DirectLagSums(values, r.mean, n, direct);
  std::vector<double> centred;  // Made only if lags beyond the direct ones are needed.
  const double c0 = direct[0];
  const size_t max_lag = std::max<size_t>(1, static_cast<size_t>(options.max_lag_fraction * dn));
  const boost::math::students_t t_dist(dn - 1.0);
  const double t_q =
      boost::math::quantile(boost::math::complement(t_dist, (1.0 - options.band_confidence) / 2));

  // Lags beyond the direct ones come from BlockLagSums, first up to kFirstLagBlock, then
  // (only if the cut-off is not found there) up to 16 x further, and so on.
  std::vector<double> lag_sums;
  size_t lags_known = 0;
  double factor = 1.0;
  double sum_rho2 = 0.0;
  size_t cutoff = max_lag;
  bool inside = false;
  for (size_t k = 1; k <= max_lag; ++k) {
    double rho_k;
    if (k <= kDirectLags) {
      rho_k = direct[k] / c0;
    } else {
      if (k > lags_known) {
        size_t block = lags_known == 0 ? kFirstLagBlock : 16 * lags_known;
        size_t max_block = 1;
        while (max_block < max_lag) max_block *= 2;
        block = std::min(block, max_block);
        lag_sums.resize(block + 1);
        if (centred.empty()) {
          centred.resize(n);
          for (size_t i = 0; i < n; ++i) centred[i] = values[i] - r.mean;
        }
        BlockLagSums(centred.data(), n, block, lag_sums.data());
        lags_known = block;
      }
      rho_k = lag_sums[k] / lag_sums[0];
    }
    if (k == 1) r.rho1 = rho_k;
    // Bartlett's formula for the standard error of rho_k under "rho_j = 0 for j >= k".
    const double band = t_q * std::sqrt((1.0 + 2.0 * sum_rho2) / dn);
    if (std::abs(rho_k) <= band) {
      cutoff = k - 1;
      inside = true;
      break;
    }
    factor += 2.0 * (1.0 - static_cast<double>(k) / dn) * rho_k;
    sum_rho2 += rho_k * rho_k;
  }
  r.cutoff_lag = static_cast<int64_t>(cutoff);
  r.cutoff_reached_limit = !inside;
  // A strongly negative correlation can drive F towards 0; n_eff is bounded by n^2.
  r.variance_factor = std::max(factor, 1.0 / dn);
  r.n_eff = dn / r.variance_factor;
  r.std_of_mean_autocorr = std::sqrt(r.variance_factor * r.variance / dn);
  return r;
}

}  // namespace metro
