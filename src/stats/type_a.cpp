// EvaluateTypeAContinuous runs these stages, in this order (method: docs/type-a.md):
//
//   sums       SumsOf, CentredLagSums    one pass: the centred sum and direct lag sums
//   classical  Classical                 mean, s, s(mean) (JCGM 100 4.2.2, 4.2.3); a constant
//                                        series, autocorrelation off or n <= 3 end here
//   AR         ArAndBatchMeans           u_mean from the AR(p) spectrum, the batch-means
//                                        stationarity check
//   Zhang      DirectLagSums,            autocorrelation to the cut-off lag, variance factor,
//              ZhangFactor               n_eff (FFT block lag sums beyond kDirectLags)
#include "metro/stats/type_a.hpp"

#include <fftw3.h>
#include <fmt/format.h>

#include <algorithm>
#include <boost/math/distributions/students_t.hpp>
#include <cmath>
#include <cstring>
#include <map>
#include <memory>
#include <mutex>

#include "core/simd_clones.hpp"
#include "metro/stats/spectral_mean.hpp"

namespace metro {
namespace {

// FFTW's planner is not thread-safe; plans are made and destroyed under this lock and
// executed outside it (fftw_execute on distinct plans is thread-safe).
std::mutex& FftwPlannerMutex() {
  static std::mutex mutex;
  return mutex;
}

// Lags computed directly (in the fused pass) before switching to the FFT.
constexpr size_t kDirectLags = 8;

// Four lanes of doubles (GCC/Clang vector extension): lane j of an accumulator sums the
// terms i = j (mod 4), and the lanes are added in one fixed order, so the result is the same
// whatever instructions carry the vectors (SSE2 pairs by default, AVX2 where the CPU has it;
// no FMA is enabled, so nothing is contracted).
using Lanes4 = double __attribute__((vector_size(32)));

// Vectors go through pointers and references only: by value they would depend on the ISA's
// ABI.
inline void Load4(const double* p, Lanes4* v) { std::memcpy(v, p, sizeof(Lanes4)); }

inline double AddLanes(const Lanes4& s) { return (s[0] + s[1]) + (s[2] + s[3]); }

// The lane of term i of a sum over i = 0..n-1: i mod 4, except that the n mod 4 terms past
// the last full group of four go to lane 0.
inline size_t LaneOf(size_t i, size_t n) { return i < n - n % 4 ? i % 4 : 0; }

// Adds x to the four lanes *s (pairwise-like accuracy); over consecutive chunks whose sizes
// are multiples of 4 (the last one aside) the lanes hold the same terms as over the whole.
METRO_SIMD_CLONES
void AddSum4(const double* x, size_t n, Lanes4* s) {
  size_t i = 0;
  for (; i + 4 <= n; i += 4) {
    Lanes4 v;
    Load4(x + i, &v);
    *s += v;
  }
  for (; i < n; ++i) (*s)[0] += x[i];
}

double Sum4(const double* x, size_t n) {
  Lanes4 s = {0.0, 0.0, 0.0, 0.0};
  AddSum4(x, n, &s);
  return AddLanes(s);
}

// The record an evaluation reads: in memory, or in chunks through a ChunkReader (the
// streaming mode, spectral_mean.hpp). Chunks are a whole number of 512-value sub-chunks and
// of lanes, so every sum adds the same terms in the same order either way.
class Record {
 public:
  static constexpr size_t kChunk = size_t{1} << 16;
  Record(const double* values, size_t n) : values_(values), n_(n) {}
  Record(const ChunkReader& read, size_t n) : read_(&read), n_(n) {}
  size_t size() const { return n_; }
  bool in_memory() const { return values_ != nullptr; }
  const double* values() const { return values_; }
  const ChunkReader& reader() const { return *read_; }
  Status Read(size_t begin, size_t count, double* out) const {
    if (values_ != nullptr) {
      std::copy(values_ + begin, values_ + begin + count, out);
      return Status::Ok();
    }
    return (*read_)(begin, count, out);
  }
  // f(x, begin, count) over consecutive chunks covering [begin, end); x[0, count + lookahead)
  // holds values begin.. (fewer past n). In memory: one call on the values themselves.
  template <typename F>
  Status ForEachChunk(size_t begin, size_t end, size_t lookahead, const F& f) const {
    if (values_ != nullptr) {
      if (end > begin) f(values_ + begin, begin, end - begin);
      return Status::Ok();
    }
    std::vector<double> buffer(kChunk + lookahead);
    for (size_t at = begin; at < end; at += kChunk) {
      const size_t count = std::min(kChunk, end - at);
      if (Status s = Read(at, std::min(count + lookahead, n_ - at), buffer.data()); !s.ok()) {
        return s;
      }
      f(buffer.data(), at, count);
    }
    return Status::Ok();
  }
  // What a failed read of the spill file said (the first one).
  Status error() const { return error_; }
  void Fail(Status s) const {
    if (error_.ok()) error_ = std::move(s);
  }

 private:
  const double* values_ = nullptr;
  const ChunkReader* read_ = nullptr;
  size_t n_ = 0;
  mutable Status error_ = Status::Ok();
};

double Sum4(const Record& x) {
  if (x.in_memory()) return Sum4(x.values(), x.size());
  Lanes4 s = {0.0, 0.0, 0.0, 0.0};
  x.Fail(x.ForEachChunk(0, x.size(), 0,
                        [&s](const double* v, size_t, size_t count) { AddSum4(v, count, &s); }));
  return AddLanes(s);
}

// One pass over x for the corrected two-pass algorithm and the direct lags: with
// e_i = x_i - centre,
//   *s1 = sum_i e_i,   p[k] = sum_{i=0}^{n-1-k} e_i e_{i+k}   (k = 0..kDirectLags).
// The series is centred chunk by chunk into a buffer that stays in L1, and every sum runs
// in four lanes (LaneOf), so the nine products per i are independent of each other and of
// the previous i. s1 and p[0] add the same terms in the same order as a plain four-lane
// loop would. (CentredLanes, AddCentredBody, CentredLagSums.)
struct CentredLanes {
  Lanes4 sum = {0.0, 0.0, 0.0, 0.0};
  Lanes4 acc[kDirectLags + 1] = {};
};

// The body of CentredLagSums for m (a multiple of 4, at most 512) terms starting at x, which
// holds m + kDirectLags values.
METRO_SIMD_CLONES
void AddCentredBody(const double* x, size_t m, double centre, CentredLanes* lanes) {
  constexpr size_t kChunk = 512;
  alignas(32) double e[kChunk + kDirectLags];
  for (size_t j = 0; j < m + kDirectLags; ++j) e[j] = x[j] - centre;
  // The accumulators in registers for the loop (a local copy: no store through `lanes`).
  CentredLanes l = *lanes;
  for (size_t j = 0; j < m; j += 4) {
    Lanes4 e0;
    Load4(e + j, &e0);
    l.sum += e0;
    for (size_t k = 0; k <= kDirectLags; ++k) {
      Lanes4 ek;
      Load4(e + j + k, &ek);
      l.acc[k] += e0 * ek;
    }
  }
  *lanes = l;
}

void CentredLagSums(const Record& x, double centre, double* s1, double* p) {
  const size_t n = x.size();
  CentredLanes lanes;
  // Below `body` every lag k <= kDirectLags has its partner e_{i+k} (i + k < n), and
  // `body` is a multiple of 4.
  const size_t body = n > kDirectLags ? (n - kDirectLags) / 4 * 4 : 0;
  x.Fail(x.ForEachChunk(0, body, kDirectLags, [&](const double* v, size_t, size_t count) {
    for (size_t j = 0; j < count; j += 512) {
      AddCentredBody(v + j, std::min<size_t>(512, count - j), centre, &lanes);
    }
  }));
  std::vector<double> rest(n - body);
  x.Fail(x.Read(body, n - body, rest.data()));
  for (size_t i = body; i < n; ++i) {
    const size_t lane = LaneOf(i, n);
    const double ei = rest[i - body] - centre;
    lanes.sum[lane] += ei;
    for (size_t k = 0; k <= kDirectLags && i + k < n; ++k) {
      lanes.acc[k][lane] += ei * (rest[i + k - body] - centre);
    }
  }
  *s1 = AddLanes(lanes.sum);
  for (size_t k = 0; k <= kDirectLags; ++k) p[k] = AddLanes(lanes.acc[k]);
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

// sum[j] += conj(X[j]) * (X[j] + (-1)^j N[j]) for j = 0..bins-1 (bins odd), on interleaved
// (re, im) arrays: re += Xr Yr + Xi Yi, im += Xr Yi - Xi Yr. Two bins per vector (j even,
// then j odd); the same operations, in the same order, as the scalar form.
METRO_SIMD_CLONES
void AccumulateCrossSpectrum(const double* cur, const double* nxt, size_t bins, double* sum) {
  const Lanes4 sign = {1.0, 1.0, -1.0, -1.0};
  size_t j = 0;
  for (; j + 2 <= bins; j += 2) {
    Lanes4 c, x, s;
    Load4(cur + 2 * j, &c);
    Load4(nxt + 2 * j, &x);
    Load4(sum + 2 * j, &s);
    const Lanes4 y = c + sign * x;
    const Lanes4 y_swapped = {y[1], y[0], y[3], y[2]};
    const Lanes4 p = c * y;          // Xr Yr, Xi Yi (two bins)
    const Lanes4 q = c * y_swapped;  // Xr Yi, Xi Yr
    const Lanes4 first = {p[0], q[0], p[2], q[2]};
    const Lanes4 second = {p[1], -q[1], p[3], -q[3]};
    s += first + second;
    std::memcpy(sum + 2 * j, &s, sizeof(Lanes4));
  }
  for (; j < bins; ++j) {
    const double sgn = (j & 1) != 0 ? -1.0 : 1.0;
    const double yr = cur[2 * j] + sgn * nxt[2 * j];
    const double yi = cur[2 * j + 1] + sgn * nxt[2 * j + 1];
    sum[2 * j] += cur[2 * j] * yr + cur[2 * j + 1] * yi;
    sum[2 * j + 1] += cur[2 * j] * yi - cur[2 * j + 1] * yr;
  }
}

// The buffers of BlockLagSums for one block length L (aligned by FFTW for its SIMD plans).
struct FftWorkspace {
  explicit FftWorkspace(size_t block_length)
      : block(block_length),
        real(fftw_alloc_real(2 * block_length)),
        current(fftw_alloc_complex(block_length + 1)),
        next(fftw_alloc_complex(block_length + 1)),
        sum(fftw_alloc_complex(block_length + 1)) {}
  ~FftWorkspace() {
    fftw_free(real);
    fftw_free(current);
    fftw_free(next);
    fftw_free(sum);
  }
  FftWorkspace(const FftWorkspace&) = delete;
  FftWorkspace& operator=(const FftWorkspace&) = delete;

  size_t block;
  double* real;  // 2L values; on return from BlockLagSums, c_0..c_L.
  fftw_complex* current;
  fftw_complex* next;
  fftw_complex* sum;
};

// Blocks up to this length keep their workspace per thread (at most 2 MB for L = 32768),
// so the series of a session do not fault the same pages in again and again; longer blocks
// (only for series longer than 2^17 samples with a cut-off beyond 32768 lags) get theirs
// per call, where the transforms cost far more than the allocation.
constexpr size_t kMaxCachedLagBlock = 32768;

// The workspace for `block`: the thread's cached one, or a new one owned by *owned.
FftWorkspace& WorkspaceFor(size_t block, std::unique_ptr<FftWorkspace>* owned) {
  if (block <= kMaxCachedLagBlock) {
    thread_local std::map<size_t, std::unique_ptr<FftWorkspace>> cache;
    std::unique_ptr<FftWorkspace>& slot = cache[block];
    if (slot == nullptr) slot = std::make_unique<FftWorkspace>(block);
    return *slot;
  }
  *owned = std::make_unique<FftWorkspace>(block);
  return **owned;
}

// Lag sums c_k = sum_i d_i d_{i+k}, k = 0..block, of the centred series d_i = x_i - mean
// (length n), by block-wise FFT correlation (block a power of two). Each block is centred
// while it is copied into the transform buffer (the same doubles as a centred copy of the
// whole series would hold, without writing one). With x_b = d[b*L, (b+1)*L) and
// y_b = d[b*L, (b+2)*L), both zero-padded to M = 2L, circular correlation of x_b with y_b
// has no wrap-around for lags k <= L, so
//   c_k = sum_b IDFT(conj(X_b) . Y_b)[k] = IDFT(sum_b conj(X_b) . Y_b)[k] / M,
// and Y_b = X_b + (-1)^j X_{b+1} (x_{b+1} sits L = M/2 samples later). One forward
// transform of size M per block of L samples plus one backward transform in all: about
// 2n log2(2L) operations, in cache, instead of 3n log2(1.5n) for the whole-series padding.
// L = ws->block; returns c_0..c_L (in ws->real).
const double* BlockLagSums(const Record& x, double mean, FftWorkspace* ws) {
  const size_t n = x.size();
  const size_t block = ws->block;
  const size_t size = 2 * block;
  const size_t bins = block + 1;  // size / 2 + 1
  const FftPlans& plans = PlansForSize(size);
  double* real = ws->real;
  fftw_complex* current = ws->current;
  fftw_complex* next = ws->next;
  fftw_complex* sum = ws->sum;
  auto transform = [&](size_t b, fftw_complex* out) {
    const size_t begin = b * block;
    const size_t count = begin < n ? std::min(block, n - begin) : 0;
    if (x.in_memory()) {
      for (size_t i = 0; i < count; ++i) real[i] = x.values()[begin + i] - mean;
    } else {
      x.Fail(x.Read(begin, count, real));
      for (size_t i = 0; i < count; ++i) real[i] -= mean;
    }
    // [block, size) stays zero: the out-of-place r2c transform preserves its input.
    std::fill(real + count, real + block, 0.0);
    fftw_execute_dft_r2c(plans.forward, real, out);
  };
  std::fill(real + block, real + size, 0.0);
  std::fill(&sum[0][0], &sum[0][0] + 2 * bins, 0.0);
  const size_t blocks = (n + block - 1) / block;
  transform(0, current);
  for (size_t b = 0; b < blocks; ++b) {
    if (b + 1 < blocks) {
      transform(b + 1, next);
    } else {
      std::fill(&next[0][0], &next[0][0] + 2 * bins, 0.0);
    }
    AccumulateCrossSpectrum(&current[0][0], &next[0][0], bins, &sum[0][0]);
    std::swap(current, next);
  }
  fftw_execute_dft_c2r(plans.backward, sum, real);
  for (size_t k = 0; k <= block; ++k) real[k] /= static_cast<double>(size);
  return real;
}

// First block length tried for lags beyond the direct ones; each retry is 16 x longer, and 4 x
// from kLargeLagBlock on: a block's buffers take 64 bytes per lag, so a 16 x step past a
// cut-off at 0.75 M lags of a 10^7-sample record took a 4 M-lag block (256 MB) where 2 M
// does, for about the same time (a pass costs O(n log block)); retries cost a pass each, so
// small blocks still grow 16 x.
constexpr size_t kFirstLagBlock = 2048;
constexpr size_t kLargeLagBlock = size_t{1} << 19;
constexpr size_t kMaxChunkedLagBlock = size_t{1} << 19;
// Longest record whose AR fit the chunked evaluation runs in memory when the lattice is needed.
constexpr size_t kMaxLatticeInMemory = size_t{1} << 21;

// rho at lag kDirectLags above which the first block is skipped: an AR(1) decay through it,
// rho_k = rho_8^(k/8), would still be above 0.5 at lag kFirstLagBlock (0.5^(8/2048)),
// far outside any Bartlett band.
constexpr double kLongCorrelationRho = 0.99729605608547;

}  // namespace

static Result<TypeAResult> EvaluateTypeAContinuous(const Record& values,
                                                   const TypeAOptions& options);

bool TypeAOptions::IsValid(std::string* why) const {
  if (!(band_confidence > 0.0 && band_confidence < 1.0)) {
    if (why) *why = "band_confidence must be in (0, 1)";
    return false;
  }
  if (!(max_lag_fraction > 0.0 && max_lag_fraction <= 0.5)) {
    if (why) *why = "max_lag_fraction must be in (0, 0.5]";
    return false;
  }
  if (!(quantization_step >= 0.0 && std::isfinite(quantization_step))) {
    if (why) *why = "quantization_step must be finite and >= 0 (0: not known)";
    return false;
  }
  if (truncated && quantization_step == 0.0) {
    if (why) *why = "truncated readings need their quantization_step";
    return false;
  }
  return true;
}

void Autocorrelation(const double* x, size_t n, size_t max_lag, double* rho) {
  METRO_CHECK(n >= 1 && max_lag < n);
  const double mean = Sum4(x, n) / static_cast<double>(n);
  // The block lag sums of the Type A evaluation, with a block of at least max_lag (a power of
  // two, at least 256): O(n log max_lag) and cached plans, where a transform of the whole
  // zero-padded series cost O(n log n) and a new plan per call.
  size_t block = 256;
  while (block < max_lag) block *= 2;
  std::unique_ptr<FftWorkspace> owned;
  const double* c = BlockLagSums(Record(x, n), mean, &WorkspaceFor(block, &owned));
  const double c0 = c[0];
  for (size_t k = 0; k <= max_lag; ++k) rho[k] = c0 > 0.0 ? c[k] / c0 : 0.0;
  rho[0] = 1.0;
}

namespace {

// Spreads within this fraction of the step are "none" or "one step": readings printed with
// fixed decimals sit on the lattice up to the rounding of their binary representation.
constexpr double kStepTolerance = 1e-6;

}  // namespace

double DigitizedUMean(size_t n, double step, double x_min, double x_max, double mean, double u_0) {
  const double spread = x_max - x_min;
  if (spread <= kStepTolerance * step) {
    // Willink (2007): no spread; c from his Table for n = 2, 3 and n >= 4.
    const double c = n == 2 ? 6.4 : n == 3 ? 1.3 : 1.0;
    return std::sqrt(c / 12.0) * step;
  }
  if (std::fabs(spread - step) <= kStepTolerance * step) {
    const double mid = 0.5 * (x_max + x_min);
    return std::sqrt(std::max(u_0 * u_0, (mid - mean) * (mid - mean) / 3.0));
  }
  return u_0;
}

namespace {

// EvaluateTypeA on a record in memory or in chunks: the continuous evaluation, then
// Willink's rules when the quantization step is known.
Result<TypeAResult> EvaluateRecord(const Record& values, const TypeAOptions& options) {
  const size_t n = values.size();
  Result<TypeAResult> result = EvaluateTypeAContinuous(values, options);
  if (!result.ok() || !(options.quantization_step > 0.0)) return result;
  TypeAResult& r = result.value();
  const double step = options.quantization_step;
  double lo = HUGE_VAL, hi = -HUGE_VAL;
  values.Fail(values.ForEachChunk(0, n, 0, [&](const double* v, size_t, size_t count) {
    const auto [l, h] = std::minmax_element(v, v + count);
    lo = std::min(lo, *l);
    hi = std::max(hi, *h);
  }));
  if (!values.error().ok()) return values.error().error();
  const double spread = hi - lo;
  const double u_0 = r.u_mean_available ? r.u_mean : 0.0;
  const double u = DigitizedUMean(n, step, lo, hi, r.mean, u_0);
  const bool none = spread <= kStepTolerance * step;
  if (none || u > u_0) {
    r.u_mean_available = true;
    r.u_mean = u;
    r.u_mean_dof = static_cast<double>(n) - 1.0;
    r.u_mean_method = kUMeanDigitized;
    if (!r.u_mean_note.empty()) r.u_mean_note += "; ";
    r.u_mean_note += fmt::format(
        "digitized readings (step {:.6g}), {}: u_mean by Willink's rules (Metrologia 44 (2007) "
        "73), {:.6g} with n - 1 = {} dof",
        step,
        none ? "all equal"
             : fmt::format("a spread of one step with the mean {:.6g} off its middle",
                           r.mean - 0.5 * (lo + hi)),
        u, n - 1);
  }
  if (options.truncated) r.mean += 0.5 * step;  // GTC's truncate: readings cut, not rounded.
  return result;
}

}  // namespace

Result<TypeAResult> EvaluateTypeA(const double* values, size_t n, const TypeAOptions& options) {
  return EvaluateRecord(Record(values, n), options);
}

Result<TypeAResult> EvaluateTypeAChunked(const ChunkReader& read, size_t n,
                                         const TypeAOptions& options) {
  return EvaluateRecord(Record(read, n), options);
}

namespace {

// ---- moments ------------------------------------------------------------------------------

// The sums of one pass over the series, centred on a first mean.
struct CentredSums {
  double first = 0.0;              // sum x_i / n
  double s1 = 0.0;                 // sum (x_i - first)
  double p[kDirectLags + 1] = {};  // p_k = sum_i (x_i - first)(x_{i+k} - first); p_0 = s2
};

// The sums, or why the series cannot be evaluated (n < 2, a value or a sum not finite).
Result<CentredSums> SumsOf(const Record& values) {
  const size_t n = values.size();
  if (n < 2) {
    return MakeError(fmt::format("{} observation{}: a Type A evaluation needs at least 2", n,
                                 n == 1 ? "" : "s"));
  }
  // A NaN or an infinity makes the sum non-finite, so the values are scanned only then.
  const double total = Sum4(values);
  if (!values.error().ok()) return values.error().error();
  if (!std::isfinite(total)) {
    size_t bad = n;
    values.Fail(
        values.ForEachChunk(0, n, 0, [&bad, n](const double* v, size_t begin, size_t count) {
          for (size_t i = 0; i < count && bad == n; ++i) {
            if (!std::isfinite(v[i])) bad = begin + i;
          }
        }));
    if (!values.error().ok()) return values.error().error();
    if (bad < n) return MakeError(fmt::format("observation {} is not finite", bad + 1));
    // Every value is finite but their sum is not: the mean cannot be formed in double.
    return MakeError(fmt::format("the sum of the {} observations overflows double precision", n));
  }
  const double dn = static_cast<double>(n);
  // Corrected two-pass algorithm (Chan, Golub & LeVeque 1983): centre on a first mean,
  // then correct with the residual sum, so no large sums of squares cancel.
  CentredSums sums;
  sums.first = total / dn;
  // The same pass forms the direct lag sums about `first` (used only if autocorrelation is
  // on; they cost no extra read of the series).
  CentredLagSums(values, sums.first, &sums.s1, sums.p);
  if (!values.error().ok()) return values.error().error();
  const double s2 = sums.p[0];
  if (!std::isfinite(s2) || !std::isfinite(sums.s1)) {
    // Deviations beyond about 1e154 square past the largest double: the variance (and so u)
    // cannot be formed; a NaN or infinite u is never reported.
    return MakeError(fmt::format(
        "the sum of squared deviations of the {} observations overflows double precision "
        "(deviations from the mean of order 1e154 or more); express the quantity in a larger "
        "unit",
        n));
  }
  return sums;
}

// The classical evaluation, JCGM 100 4.2.2 and 4.2.3.
TypeAResult Classical(size_t n, const CentredSums& sums) {
  const double dn = static_cast<double>(n);
  const double first = sums.first;
  const double s1 = sums.s1;
  const double s2 = sums.p[0];
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
  r.u_mean_available = true;
  r.u_mean = r.std_of_mean;
  r.u_mean_dof = dn - 1.0;
  r.u_mean_method = kUMeanClassical;
  return r;
}

// ---- AR spectral u and the stationarity check ---------------------------------------------

// metro's u_mean: the AR(p) spectral density at frequency zero (spectral_mean.hpp), unless
// the series is a deterministic pattern; then the batch-means stationarity check.
void ArAndBatchMeans(const Record& values, TypeAResult* result) {
  const size_t n = values.size();
  TypeAResult& r = *result;
  const double dn = static_cast<double>(n);
  // A series the AR model predicts almost exactly (innovations below 1e-6 of the variance:
  // a deterministic pattern, not noise) has no noise to test the batch means against; the
  // fit stops as soon as that is certain (the remaining orders would change nothing).
  constexpr double kDeterministicInnovationRatio = 1e-6;
  ArSpectralOptions ar_options;
  ar_options.stop_below_innovation_variance = kDeterministicInnovationRatio * r.variance;
  auto ar = values.in_memory() ? ArSpectralMeanUncertainty(values.values(), n, ar_options)
                               : ArSpectralMeanUncertaintyChunked(values.reader(), n, ar_options);
  if (!ar.ok() && !values.in_memory()) {
    // The chunked fit cannot run the lattice (spectral_mean.hpp). A record of at most
    // kMaxLatticeInMemory values is read in (the lattice's five arrays: 80 MB at most) and
    // fitted as in memory; a longer one keeps the classical s(mean), said, never guessed.
    if (n <= kMaxLatticeInMemory) {
      std::vector<double> whole(n);
      values.Fail(values.Read(0, n, whole.data()));
      ar = ArSpectralMeanUncertainty(whole.data(), n, ar_options);
    } else {
      r.u_mean_note = "u_mean is the classical s(mean): " + ar.error().message;
    }
  }
  const bool deterministic =
      ar.ok() && (ar.value().stopped_below ||
                  ar.value().innovation_variance < kDeterministicInnovationRatio * r.variance);
  if (ar.ok() && !ar.value().stopped_below) {
    r.u_mean = ar.value().u_mean;
    r.u_mean_ar = r.u_mean;
    r.u_mean_dof = ar.value().dof;
    r.u_mean_method = kUMeanArSpectral;
    r.ar_order = ar.value().order;
  }
  if (deterministic) {
    // Its spectral density at zero is no noise model (a period-5 pattern gave u_mean 2e-17):
    // the classical s(mean), which never understates a pattern's spread, stands instead.
    r.u_mean = r.std_of_mean;
    r.u_mean_dof = dn - 1.0;
    r.u_mean_method = kUMeanClassical;
    r.u_mean_note =
        "the AR model predicts the series almost exactly (a deterministic pattern, not noise): "
        "u_mean is the classical s(mean)";
  }
  if (n >= kBatchMeansMinN && !deterministic) {
    // Stationarity check: batch means of the last b * m values (type_a.hpp).
    const size_t b = kStationarityBatches;
    const size_t m = n / b;
    const size_t start = n - b * m;
    double means[kStationarityBatches];
    double sum = 0.0;
    values.Fail(values.ForEachChunk(start, n, 0, [&](const double* v, size_t begin, size_t count) {
      // Batch by batch within the chunk (no division per value), in order.
      for (size_t i = 0; i < count;) {
        const size_t at = begin + i - start;
        const size_t batch_end = (at / m + 1) * m;
        const size_t take = std::min(count - i, batch_end - at);
        for (size_t k = 0; k < take; ++k) sum += v[i + k] - r.mean;
        i += take;
        if (at + take == batch_end) {
          means[at / m] = sum / static_cast<double>(m);
          sum = 0.0;
        }
      }
    }));
    double grand = 0.0;
    for (double v : means) grand += v;
    grand /= static_cast<double>(b);
    double ss = 0.0;
    for (double v : means) ss += (v - grand) * (v - grand);
    r.u_mean_batch = std::sqrt(ss / static_cast<double>((b - 1) * b));
    if (r.u_mean_batch > 2.0 * r.u_mean) {
      r.drift_detected = true;
      r.u_mean = r.u_mean_batch;
      r.u_mean_dof = static_cast<double>(b - 1);
      r.u_mean_method = kUMeanBatchMeans;
    }
  }
}

// ---- Zhang's variance factor --------------------------------------------------------------

// Direct lag sums c_0..c_kDirectLags about the mean from those about `first`.
void DirectLagSums(const Record& values, const CentredSums& sums, double direct[kDirectLags + 1]) {
  const size_t n = values.size();
  const double dn = static_cast<double>(n);
  // The first and last kDirectLags values (H_k and T_k below).
  const size_t edge = std::min(n, kDirectLags);
  double first_values[kDirectLags], last_values[kDirectLags];
  values.Fail(values.Read(0, edge, first_values));
  values.Fail(values.Read(n - edge, edge, last_values));
  const double first = sums.first;
  const double s1 = sums.s1;
  const double s2 = sums.p[0];
  const double* p = sums.p;
  // Direct lag sums about the mean from those about `first`: with e_i = x_i - first and
  // delta = mean - first = s1/n,
  //   c_k = sum_{i=0}^{n-1-k} (e_i - delta)(e_{i+k} - delta)
  //       = p_k - delta (2 s1 - H_k - T_k) + (n - k) delta^2,
  // H_k = sum_{i<k} e_i, T_k = sum_{i>=n-k} e_i. For k = 0 this is the corrected two-pass
  // sum s2 - s1^2/n; delta is of the order of the rounding of `first`, so the correction
  // is as small as the two-pass one.
  const double delta = s1 / dn;
  direct[0] = s2 - s1 * s1 / dn;
  double head = 0.0, tail = 0.0;
  for (size_t k = 1; k <= kDirectLags; ++k) {
    const size_t kn = std::min(k, n);
    if (k <= n) {
      head += first_values[k - 1] - first;
      tail += last_values[edge - k] - first;
    }
    direct[k] =
        p[k] - delta * (2.0 * s1 - head - tail) + static_cast<double>(n - kn) * delta * delta;
  }
}

// Zhang (2006): variance factor from the autocorrelation up to the cut-off lag (Bartlett's
// band), n_eff and std_of_mean_autocorr.
// In chunks (the streaming mode) the lag sums stop at kMaxChunkedLagBlock lags (64 bytes of
// buffers per lag): a cut-off beyond it is not computed, and the Error says so.
Status ZhangFactor(const Record& values, const TypeAOptions& options,
                   const double direct[kDirectLags + 1], TypeAResult* result) {
  const size_t n = values.size();
  TypeAResult& r = *result;
  const double dn = static_cast<double>(n);
  const double c0 = direct[0];
  const size_t max_lag = std::max<size_t>(1, static_cast<size_t>(options.max_lag_fraction * dn));
  const boost::math::students_t t_dist(dn - 1.0);
  const double t_q =
      boost::math::quantile(boost::math::complement(t_dist, (1.0 - options.band_confidence) / 2));

  // Lags beyond the direct ones come from BlockLagSums, first up to kFirstLagBlock, then
  // (only if the cut-off is not found there) up to 16 x further, and so on.
  std::unique_ptr<FftWorkspace> owned_workspace;
  const double* lag_sums = nullptr;
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
        // A correlation that has hardly decayed by lag kDirectLags (drift) will not end
        // within the first block: start at the second size directly. The block size only
        // changes the cost, never which lags are used or their values beyond rounding.
        size_t block = lags_known == 0
                           ? (direct[kDirectLags] / c0 > kLongCorrelationRho ? 16 * kFirstLagBlock
                                                                             : kFirstLagBlock)
                           : (lags_known >= kLargeLagBlock ? 4 : 16) * lags_known;
        size_t max_block = 1;
        while (max_block < max_lag) max_block *= 2;
        block = std::min(block, max_block);
        if (!values.in_memory() && block > kMaxChunkedLagBlock) {
          return MakeError(fmt::format(
              "the autocorrelation is still outside its band at lag {} (a long correlation "
              "or drift); Zhang's factor needs lags beyond the {} the streaming mode keeps: "
              "n_eff and std_of_mean_autocorr are not available in streaming mode (run without "
              "--stream)",
              lags_known, kMaxChunkedLagBlock));
        }
        lag_sums = BlockLagSums(values, r.mean, &WorkspaceFor(block, &owned_workspace));
        if (!values.error().ok()) return values.error();
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
  return Status::Ok();
}

}  // namespace

static Result<TypeAResult> EvaluateTypeAContinuous(const Record& values,
                                                   const TypeAOptions& options) {
  const size_t n = values.size();
  std::string why;
  if (!options.IsValid(&why)) return MakeError("invalid Type A options: " + why);
  Result<CentredSums> sums = SumsOf(values);
  if (!sums.ok()) return sums.error();
  TypeAResult r = Classical(n, sums.value());
  if (r.variance == 0.0) {
    // s = 0 says nothing about the mean's uncertainty, for any n (issue #36: n <= 3 gave
    // u = 0 silently): the readings' resolution bounds it (the digitized rules, when the
    // step is known; a Type B input otherwise).
    r.autocorr_note =
        "constant series (s = 0): no autocorrelation and no uncertainty of the mean can be "
        "computed from it; the readings' resolution (a Type B input) bounds u";
    r.u_mean_available = false;
    r.u_mean = 0.0;
    r.u_mean_dof = 0.0;
    r.u_mean_method.clear();
    return r;
  }
  if (!options.autocorrelation) {
    r.autocorr_note = "autocorrelation off: u_mean is the classical s(mean)";
    return r;
  }
  if (n < 4) {
    r.autocorr_note = fmt::format(
        "n = {} <= 3: too few observations to estimate an autocorrelation; u_mean is the "
        "classical s(mean) with n - 1 dof",
        n);
    return r;
  }
  ArAndBatchMeans(values, &r);
  double direct[kDirectLags + 1];
  DirectLagSums(values, sums.value(), direct);
  const Status zhang = ZhangFactor(values, options, direct, &r);
  if (!values.error().ok()) return values.error().error();
  if (zhang.ok()) {
    r.autocorr_computed = true;
  } else {
    r.autocorr_note = zhang.error().message;
  }
  return r;
}

}  // namespace metro
