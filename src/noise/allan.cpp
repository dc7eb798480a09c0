#include "metro/noise/allan.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <functional>
#include <thread>
#include <utility>

#include "core/parallel.hpp"
#include "core/simd_clones.hpp"
#include "metro/core/cancel.hpp"
#include "metro/noise/edf.hpp"
#include "metro/noise/noise_id.hpp"
#include "noise/allan_internal.hpp"

namespace metro {
namespace {

// Block of phase indices processed for every tau before moving on, so that the streams
// x[i], x[i+m], x[i+2m] of neighbouring taus are reused from cache.
constexpr int64_t kBlock = 2048;
// Below this many phase points one thread does everything.
constexpr int64_t kMinPointsPerThread = 1 << 16;
// Stable32's all-tau thinning: every m below kAllTauDense, then m += m / kAllTauDense + 1.
constexpr int64_t kAllTauDense = 53;

int64_t StopRatio(AllanEstimator estimator) {
  switch (estimator) {
    case AllanEstimator::kAdev:
    case AllanEstimator::kHdev:
      return 5;
    default:
      return 4;
  }
}

int ResolveThreads(int requested, int64_t work_points) {
  int threads = requested > 0 ? requested : static_cast<int>(std::thread::hardware_concurrency());
  threads = std::max(threads, 1);
  const int64_t useful = std::max<int64_t>(1, work_points / kMinPointsPerThread);
  return static_cast<int>(std::min<int64_t>(threads, useful));
}

// Eight lanes of doubles as two 4-wide vectors (GCC/Clang vector extension): lane j of the
// accumulators sums the terms i = j (mod 8) of a call, and the lanes are added in one fixed
// order, so the result is the same whatever instructions carry the vectors (SSE2 pairs by
// default, AVX2 where the CPU has it; no FMA is enabled, so nothing is contracted).
using Lanes4 = double __attribute__((vector_size(32)));

// Vectors go through pointers and references only: by value they would depend on the ISA's
// ABI. *lo = p[0..3], *hi = p[4..7].
inline void Load8(const double* p, Lanes4* lo, Lanes4* hi) {
  std::memcpy(lo, p, sizeof(Lanes4));
  std::memcpy(hi, p + 4, sizeof(Lanes4));
}

inline double AddLanes(const Lanes4& s0, const Lanes4& s1) {
  return ((s0[0] + s0[1]) + (s0[2] + s0[3])) + ((s1[0] + s1[1]) + (s1[2] + s1[3]));
}

// sum_{i=i0}^{i1-1} (x[i+2m] - 2 x[i+m] + x[i])^2 in eight lanes.
METRO_SIMD_CLONES
double SumSecondDifferences(const double* x, int64_t m, int64_t i0, int64_t i1) {
  const double* a = x + i0;
  const double* b = x + i0 + m;
  const double* c = x + i0 + 2 * m;
  const int64_t n = i1 - i0;
  const Lanes4 two = {2.0, 2.0, 2.0, 2.0};
  Lanes4 s0 = {0.0, 0.0, 0.0, 0.0};
  Lanes4 s1 = s0;
  int64_t i = 0;
  for (; i + 8 <= n; i += 8) {
    Lanes4 a0, a1, b0, b1, c0, c1;
    Load8(a + i, &a0, &a1);
    Load8(b + i, &b0, &b1);
    Load8(c + i, &c0, &c1);
    const Lanes4 d0 = (c0 - two * b0) + a0;
    const Lanes4 d1 = (c1 - two * b1) + a1;
    s0 += d0 * d0;
    s1 += d1 * d1;
  }
  for (int64_t j = 0; i < n; ++i, ++j) {
    const double d = (c[i] - 2.0 * b[i]) + a[i];
    if (j < 4) {
      s0[j] += d * d;
    } else {
      s1[j - 4] += d * d;
    }
  }
  return AddLanes(s0, s1);
}

// sum_{i=i0}^{i1-1} (x[i+3m] - 3 x[i+2m] + 3 x[i+m] - x[i])^2 in eight lanes.
METRO_SIMD_CLONES
double SumThirdDifferences(const double* x, int64_t m, int64_t i0, int64_t i1) {
  const double* a = x + i0;
  const double* b = x + i0 + m;
  const double* c = x + i0 + 2 * m;
  const double* e = x + i0 + 3 * m;
  const int64_t n = i1 - i0;
  const Lanes4 three = {3.0, 3.0, 3.0, 3.0};
  Lanes4 s0 = {0.0, 0.0, 0.0, 0.0};
  Lanes4 s1 = s0;
  int64_t i = 0;
  for (; i + 8 <= n; i += 8) {
    Lanes4 a0, a1, b0, b1, c0, c1, e0, e1;
    Load8(a + i, &a0, &a1);
    Load8(b + i, &b0, &b1);
    Load8(c + i, &c0, &c1);
    Load8(e + i, &e0, &e1);
    const Lanes4 d0 = (e0 - a0) - three * (c0 - b0);
    const Lanes4 d1 = (e1 - a1) - three * (c1 - b1);
    s0 += d0 * d0;
    s1 += d1 * d1;
  }
  for (int64_t j = 0; i < n; ++i, ++j) {
    const double d = (e[i] - a[i]) - 3.0 * (c[i] - b[i]);
    if (j < 4) {
      s0[j] += d * d;
    } else {
      s1[j - 4] += d * d;
    }
  }
  return AddLanes(s0, s1);
}

// Overlapping Allan / Hadamard sums for all m. The index range is cut into a fixed number
// of slices (whatever the thread count); a slice is one blocked pass over its part of the
// data for every m, and may run on any thread. Sums() adds the slices' partial sums in
// slice order, so the result does not depend on the thread count.
class OverlappingSums {
 public:
  OverlappingSums(const double* x, int64_t n_phase, const std::vector<int64_t>& m,
                  AllanEstimator estimator)
      : x_(x), m_(m), hadamard_(estimator == AllanEstimator::kOhdev), limit_(m.size()) {
    for (size_t k = 0; k < m.size(); ++k) {
      limit_[k] = AllanTermCount(estimator, n_phase, m[k]);
      max_limit_ = std::max(max_limit_, limit_[k]);
    }
    slices_ = std::clamp<int64_t>(max_limit_ / kMinPointsPerThread, 1, kMaxSlices);
    partial_.assign(static_cast<size_t>(slices_), std::vector<double>(m.size(), 0.0));
  }
  int64_t slices() const { return slices_; }

  void RunSlice(int64_t s) {
    const int64_t lo = max_limit_ * s / slices_;
    const int64_t hi = max_limit_ * (s + 1) / slices_;
    std::vector<double>& sums = partial_[static_cast<size_t>(s)];
    for (int64_t b = lo; b < hi; b += kBlock) {
      const int64_t block_end = std::min(b + kBlock, hi);
      for (size_t k = 0; k < m_.size(); ++k) {
        const int64_t end = std::min(block_end, limit_[k]);
        if (end <= b) continue;
        ThrowIfCancelled();  // A block at one m is microseconds: Ctrl-C stops "every" at once.
        sums[k] += hadamard_ ? SumThirdDifferences(x_, m_[k], b, end)
                             : SumSecondDifferences(x_, m_[k], b, end);
      }
    }
  }

  std::vector<double> Sums() const {
    std::vector<double> sums(m_.size(), 0.0);
    for (const std::vector<double>& p : partial_) {
      for (size_t k = 0; k < m_.size(); ++k) sums[k] += p[k];
    }
    return sums;
  }

 private:
  static constexpr int64_t kMaxSlices = 32;
  const double* x_;
  const std::vector<int64_t>& m_;
  bool hadamard_;
  std::vector<int64_t> limit_;
  int64_t max_limit_ = 0;
  int64_t slices_ = 1;
  std::vector<std::vector<double>> partial_;
};

// Modified Allan sum for one m (NIST SP 1065 5.2.5): sum_{j=0}^{N-3m} (sum_{i=j}^{j+m-1} d_i)^2,
// d_i the second difference at lag m. The inner sum slides in O(1) per j and is recomputed
// from scratch at the start of every segment of ModifiedSegmentTerms(m) terms, so that
// rounding cannot accumulate; the segments' totals are added in their order, so the sum does
// not depend on the thread count, and ComputeAllanChunked reproduces it bit for bit.
double ModifiedSum(const double* p, int64_t n_phase, int64_t m, int threads) {
  const int64_t n_terms = AllanTermCount(AllanEstimator::kMdev, n_phase, m);
  const int64_t segment = internal::ModifiedSegmentTerms(m);
  const int64_t segments = (n_terms + segment - 1) / segment;
  auto d = [p, m](int64_t i) { return (p[i + 2 * m] - 2.0 * p[i + m]) + p[i]; };
  std::vector<double> totals(static_cast<size_t>(segments), 0.0);
  internal::RunAllanTasks(ResolveThreads(threads, n_terms), segments, [&](int64_t s) {
    const int64_t start = s * segment;
    const int64_t stop = std::min(start + segment, n_terms);
    double inner = 0.0;
    for (int64_t i = start; i < start + m; ++i) inner += d(i);
    double total = inner * inner;
    for (int64_t j = start + 1; j < stop; ++j) {
      inner += d(j + m - 1) - d(j - 1);
      total += inner * inner;
    }
    totals[static_cast<size_t>(s)] = total;
  });
  double sum = 0.0;
  for (double t : totals) sum += t;
  return sum;
}

// Non-overlapping Allan / Hadamard sum for one m (stride m): O(N / m).
double NonOverlappingSum(const double* x, int64_t n_phase, int64_t m, bool hadamard) {
  const int64_t n_terms =
      AllanTermCount(hadamard ? AllanEstimator::kHdev : AllanEstimator::kAdev, n_phase, m);
  double sum = 0.0;
  for (int64_t k = 0; k < n_terms; ++k) {
    const int64_t i = k * m;
    const double v = hadamard ? (x[i + 3 * m] - x[i]) - 3.0 * (x[i + 2 * m] - x[i + m])
                              : (x[i + 2 * m] - 2.0 * x[i + m]) + x[i];
    sum += v * v;
  }
  return sum;
}

// AllanVariances on the n_phase points at phase.
std::vector<double> PhaseVariances(const double* phase, int64_t n_phase, double tau0_s,
                                   const std::vector<int64_t>& m, AllanEstimator estimator,
                                   int threads);

// Variances from the sums of squared differences (NIST SP 1065 5.2.2-5.2.9).
std::vector<double> VariancesFromSums(const std::vector<double>& sums, int64_t n_phase,
                                      double tau0_s, const std::vector<int64_t>& m,
                                      AllanEstimator estimator);

// Rate samples per block of the phase integration. Blocks are fixed, whatever the thread
// count, so the phase does not depend on it.
constexpr int64_t kPhaseBlock = int64_t{1} << 14;
// Blocks whose running sums advance together: four independent dependency chains.
constexpr int64_t kPhaseLanes = 4;

// sum += v with Neumaier's compensation in *carry.
inline void CompensatedAdd(double v, double* sum, double* carry) {
  const double t = *sum + v;
  *carry += std::fabs(*sum) >= std::fabs(v) ? (*sum - t) + v : (v - t) + *sum;
  *sum = t;
}

struct PhaseResult {
  double mean = 0.0;
  int64_t first_bad = -1;  // First non-finite rate sample, -1 if none.
};

// Sizes *phase to n values (zeros), with huge pages asked for first.
double* NewPhase(size_t n, std::vector<double>* phase) {
  phase->reserve(n);  // Allocated, not yet touched.
  internal::AdviseHugePages(phase->data(), n * sizeof(double));
  phase->resize(n);
  return phase->data();
}

// Compensated running sums of the centred steps (y_k - mean) tau0 over the blocks
// [b0, b1) (block b covers samples [b kPhaseBlock, min(n, (b + 1) kPhaseBlock))), each
// from its start (x[b], carry[b]) on entry; on return x[b], carry[b] hold its end. With a
// phase array, phase[k + 1] = x + carry after each step. kPhaseLanes full blocks advance
// together (independent dependency chains); every block sees its samples in order, so the
// result does not depend on how blocks are grouped.
void RunBlocks(const double* y, int64_t n, double mean, double tau0_s, int64_t b0, int64_t b1,
               double* x, double* carry, double* phase) {
  int64_t b = b0;
  for (; b + kPhaseLanes <= b1 && (b + kPhaseLanes) * kPhaseBlock <= n; b += kPhaseLanes) {
    double xl[kPhaseLanes], cl[kPhaseLanes];
    for (int64_t j = 0; j < kPhaseLanes; ++j) {
      xl[j] = x[b + j];
      cl[j] = carry[b + j];
    }
    const int64_t lo = b * kPhaseBlock;
    for (int64_t k = 0; k < kPhaseBlock; ++k) {
      for (int64_t j = 0; j < kPhaseLanes; ++j) {
        const int64_t i = lo + j * kPhaseBlock + k;
        CompensatedAdd((y[i] - mean) * tau0_s, &xl[j], &cl[j]);
        if (phase != nullptr) phase[i + 1] = xl[j] + cl[j];
      }
    }
    for (int64_t j = 0; j < kPhaseLanes; ++j) {
      x[b + j] = xl[j];
      carry[b + j] = cl[j];
    }
  }
  for (; b < b1; ++b) {
    double xb = x[b], cb = carry[b];
    const int64_t hi = std::min(n, (b + 1) * kPhaseBlock);
    for (int64_t i = b * kPhaseBlock; i < hi; ++i) {
      CompensatedAdd((y[i] - mean) * tau0_s, &xb, &cb);
      if (phase != nullptr) phase[i + 1] = xb + cb;
    }
    x[b] = xb;
    carry[b] = cb;
  }
}

// PhaseFromRate on `threads` threads, in three passes over fixed blocks of kPhaseBlock
// samples (each pass splits the blocks between the threads):
//   1. per-block sums of y (four interleaved sums) -> mean; a non-finite block sum sends
//      the block to a scan for its first non-finite sample;
//   2. per-block compensated sums of (y_k - mean) tau0 -> block totals; their compensated
//      running sum gives each block's starting phase;
//   3. per block, the compensated running sum from that start:
//      x_0 = 0, x_{k+1} = x_k + (y_k - mean) tau0.
// y holds n rate samples, phase receives n + 1 phase points; phase may be y - 1 (the phase
// then replaces the samples in place: step k reads y[k] before it writes phase[k + 1], the
// same element). `phase` is allocated by the caller, `get_phase` returns it once passes 1
// and 2 are done (so that a fresh array is touched only after them). With
// `stop_at_non_finite`, passes 2 and 3 are skipped when a sample is not finite.
template <typename GetPhase>
PhaseResult IntegratePhase(const double* y, int64_t n, double tau0_s, int threads,
                           bool stop_at_non_finite, GetPhase get_phase) {
  const int64_t blocks = (n + kPhaseBlock - 1) / kPhaseBlock;
  const int n_threads = ResolveThreads(threads, n);
  PhaseResult out;
  std::vector<double> block_sum(static_cast<size_t>(blocks), 0.0);
  std::vector<int64_t> block_bad(static_cast<size_t>(blocks), -1);
  internal::ParallelSlices(n_threads, blocks, [&](int64_t b0, int64_t b1, int) {
    for (int64_t b = b0; b < b1; ++b) {
      const int64_t lo = b * kPhaseBlock;
      const int64_t hi = std::min(n, lo + kPhaseBlock);
      double s4[4] = {0.0, 0.0, 0.0, 0.0};
      int64_t k = lo;
      for (; k + 4 <= hi; k += 4) {
        for (int64_t j = 0; j < 4; ++j) s4[j] += y[k + j];
      }
      for (; k < hi; ++k) s4[0] += y[k];
      const double sum = (s4[0] + s4[1]) + (s4[2] + s4[3]);
      block_sum[static_cast<size_t>(b)] = sum;
      if (!std::isfinite(sum)) {
        for (k = lo; k < hi; ++k) {
          if (!std::isfinite(y[k])) {
            block_bad[static_cast<size_t>(b)] = k;
            break;
          }
        }
      }
    }
  });
  double total = 0.0, total_carry = 0.0;
  for (int64_t b = 0; b < blocks; ++b) {
    if (out.first_bad < 0) out.first_bad = block_bad[static_cast<size_t>(b)];
    CompensatedAdd(block_sum[static_cast<size_t>(b)], &total, &total_carry);
  }
  if (stop_at_non_finite && out.first_bad >= 0) return out;
  const double mean = n == 0 ? 0.0 : (total + total_carry) / static_cast<double>(n);
  out.mean = mean;
  // Pass 2: block totals of the centred steps (sum and its compensation).
  std::vector<double> step_sum(static_cast<size_t>(blocks), 0.0);
  std::vector<double> step_carry(static_cast<size_t>(blocks), 0.0);
  internal::ParallelSlices(n_threads, blocks, [&](int64_t b0, int64_t b1, int) {
    RunBlocks(y, n, mean, tau0_s, b0, b1, step_sum.data(), step_carry.data(), nullptr);
  });
  // Starting phase of each block (x and its compensation).
  std::vector<double> start_x(static_cast<size_t>(blocks), 0.0);
  std::vector<double> start_carry(static_cast<size_t>(blocks), 0.0);
  double x = 0.0, carry = 0.0;
  for (int64_t b = 0; b < blocks; ++b) {
    start_x[static_cast<size_t>(b)] = x;
    start_carry[static_cast<size_t>(b)] = carry;
    CompensatedAdd(step_sum[static_cast<size_t>(b)], &x, &carry);
    carry += step_carry[static_cast<size_t>(b)];
  }
  double* phase = get_phase();
  phase[0] = 0.0;
  internal::ParallelSlices(n_threads, blocks, [&](int64_t b0, int64_t b1, int) {
    RunBlocks(y, n, mean, tau0_s, b0, b1, start_x.data(), start_carry.data(), phase);
  });
  return out;
}

}  // namespace

const char* AllanEstimatorName(AllanEstimator estimator) {
  switch (estimator) {
    case AllanEstimator::kOadev:
      return "oadev";
    case AllanEstimator::kMdev:
      return "mdev";
    case AllanEstimator::kOhdev:
      return "ohdev";
    case AllanEstimator::kAdev:
      return "adev";
    case AllanEstimator::kHdev:
      return "hdev";
  }
  return "?";
}

Result<AllanEstimator> ParseAllanEstimator(const std::string& text) {
  for (AllanEstimator e : {AllanEstimator::kOadev, AllanEstimator::kMdev, AllanEstimator::kOhdev,
                           AllanEstimator::kAdev, AllanEstimator::kHdev}) {
    if (text == AllanEstimatorName(e)) return e;
  }
  return MakeError(
      fmt::format("unknown Allan estimator '{}': expected oadev, mdev, ohdev, adev or hdev", text));
}

EstimatorShape ShapeOf(AllanEstimator estimator) {
  switch (estimator) {
    case AllanEstimator::kOadev:
      return {2, true, false};
    case AllanEstimator::kMdev:
      return {2, true, true};
    case AllanEstimator::kOhdev:
      return {3, true, false};
    case AllanEstimator::kAdev:
      return {2, false, false};
    case AllanEstimator::kHdev:
      return {3, false, false};
  }
  return {};
}

Result<TauSpacing> ParseTauSpacing(const std::string& text) {
  TauSpacing spacing;
  if (text == "octave") return spacing;
  if (text == "all") {
    spacing.kind = TauSpacingKind::kAll;
    return spacing;
  }
  if (text == "every") {
    spacing.kind = TauSpacingKind::kEvery;
    return spacing;
  }
  const std::string prefix = "decade:";
  if (text.rfind(prefix, 0) == 0) {
    const std::string number = text.substr(prefix.size());
    bool digits =
        !number.empty() && number.size() <= 4 &&
        std::all_of(number.begin(), number.end(), [](char c) { return c >= '0' && c <= '9'; });
    const int k = digits ? std::stoi(number) : 0;
    if (k < 1 || k > 1000) {
      return MakeError(fmt::format(
          "tau spacing '{}': decade:K needs an integer K from 1 to 1000 points per decade", text));
    }
    spacing.kind = TauSpacingKind::kDecade;
    spacing.per_decade = k;
    return spacing;
  }
  return MakeError(
      fmt::format("unknown tau spacing '{}': expected octave, decade:K, all or every", text));
}

std::string TauSpacingName(const TauSpacing& spacing) {
  switch (spacing.kind) {
    case TauSpacingKind::kOctave:
      return "octave";
    case TauSpacingKind::kDecade:
      return fmt::format("decade:{}", spacing.per_decade);
    case TauSpacingKind::kAll:
      return "all";
    case TauSpacingKind::kEvery:
      return "every";
  }
  return "?";
}

const char* AlphaSourceName(AlphaSource source) {
  switch (source) {
    case AlphaSource::kLag1Acf:
      return "lag1_acf";
    case AlphaSource::kCarried:
      return "carried";
    case AlphaSource::kDefault:
      return "default";
    case AlphaSource::kFixed:
      return "fixed";
  }
  return "?";
}

bool AllanOptions::IsValid(std::string* why) const {
  auto fail = [why](std::string message) {
    if (why != nullptr) *why = std::move(message);
    return false;
  };
  if (taus.kind == TauSpacingKind::kDecade && (taus.per_decade < 1 || taus.per_decade > 1000)) {
    return fail("taus: decade spacing needs 1 to 1000 points per decade");
  }
  for (int64_t m : m_list) {
    if (m < 1) return fail(fmt::format("m_list: averaging factor {} is below 1", m));
  }
  if (max_m < 0) return fail("max_m must be >= 0 (0 = Stable32 stop ratio)");
  if (!(confidence > 0.0 && confidence < 1.0)) {
    return fail(fmt::format("confidence {} is not in (0, 1)", confidence));
  }
  if (noise_id == NoiseIdMethod::kFixed) {
    const int lowest = ShapeOf(estimator).d == 3 ? -4 : -2;
    if (fixed_alpha < lowest || fixed_alpha > 2) {
      return fail(fmt::format("fixed_alpha {} is outside [{}, 2] for {}", fixed_alpha, lowest,
                              AllanEstimatorName(estimator)));
    }
  }
  if (min_points_noise_id < 8) return fail("min_points_noise_id must be >= 8");
  if (max_points_noise_id < min_points_noise_id) {
    return fail("max_points_noise_id must be >= min_points_noise_id");
  }
  if (threads < 0) return fail("threads must be >= 0 (0 = all hardware threads)");
  return true;
}

std::vector<double> PhaseFromRate(const std::vector<double>& rate, double tau0_s,
                                  double* mean_out) {
  METRO_CHECK(tau0_s > 0.0);
  std::vector<double> phase;
  const PhaseResult r = IntegratePhase(rate.data(), static_cast<int64_t>(rate.size()), tau0_s, 0,
                                       false, [&] { return NewPhase(rate.size() + 1, &phase); });
  if (mean_out != nullptr) *mean_out = r.mean;
  return phase;
}

int64_t AllanTermCount(AllanEstimator estimator, int64_t n_phase, int64_t m) {
  if (m < 1 || n_phase < 2) return 0;
  int64_t n = 0;
  switch (estimator) {
    case AllanEstimator::kOadev:
      n = n_phase - 2 * m;
      break;
    case AllanEstimator::kMdev:
      n = n_phase - 3 * m + 1;
      break;
    case AllanEstimator::kOhdev:
      n = n_phase - 3 * m;
      break;
    case AllanEstimator::kAdev:
      n = (n_phase - 1) / m - 1;
      break;
    case AllanEstimator::kHdev:
      n = (n_phase - 1) / m - 2;
      break;
  }
  return std::max<int64_t>(n, 0);
}

Result<std::vector<int64_t>> AveragingFactors(AllanEstimator estimator, const TauSpacing& taus,
                                              int64_t n_rate, int64_t max_m) {
  const int64_t stop_ratio = StopRatio(estimator);
  int64_t top = max_m > 0 ? max_m : n_rate / stop_ratio;
  if (top < 1) {
    return MakeError(fmt::format(
        "{} samples are too few for {}: at least {} are needed (Stable32 stop ratio {})", n_rate,
        AllanEstimatorName(estimator), stop_ratio, stop_ratio));
  }
  if (AllanTermCount(estimator, n_rate + 1, top) < 1) {
    return MakeError(fmt::format("max_m {} leaves no term for {} with {} samples", top,
                                 AllanEstimatorName(estimator), n_rate));
  }
  std::vector<int64_t> m;
  switch (taus.kind) {
    case TauSpacingKind::kOctave:
      for (int64_t v = 1; v <= top; v *= 2) m.push_back(v);
      break;
    case TauSpacingKind::kDecade: {
      if (taus.per_decade < 1) return MakeError("decade spacing needs at least 1 point per decade");
      for (int j = 0;; ++j) {
        const double v = std::round(std::pow(10.0, static_cast<double>(j) / taus.per_decade));
        if (v > static_cast<double>(top)) break;
        const int64_t mv = static_cast<int64_t>(v);
        if (m.empty() || mv > m.back()) m.push_back(mv);
      }
      break;
    }
    case TauSpacingKind::kAll:
      for (int64_t v = 1; v <= top; v += v / kAllTauDense + 1) m.push_back(v);
      break;
    case TauSpacingKind::kEvery:
      m.reserve(static_cast<size_t>(top));
      for (int64_t v = 1; v <= top; ++v) m.push_back(v);
      break;
  }
  return m;
}

std::vector<double> AllanVariances(const std::vector<double>& phase, double tau0_s,
                                   const std::vector<int64_t>& m, AllanEstimator estimator,
                                   int threads) {
  return PhaseVariances(phase.data(), static_cast<int64_t>(phase.size()), tau0_s, m, estimator,
                        threads);
}

namespace {

std::vector<double> PhaseVariances(const double* phase, int64_t n_phase, double tau0_s,
                                   const std::vector<int64_t>& m, AllanEstimator estimator,
                                   int threads) {
  METRO_CHECK(tau0_s > 0.0);
  for (int64_t mk : m) METRO_CHECK(AllanTermCount(estimator, n_phase, mk) >= 1);
  std::vector<double> sums(m.size(), 0.0);
  switch (estimator) {
    case AllanEstimator::kOadev:
    case AllanEstimator::kOhdev: {
      OverlappingSums overlapping(phase, n_phase, m, estimator);
      internal::RunAllanTasks(ResolveThreads(threads, n_phase), overlapping.slices(),
                              [&](int64_t slice) { overlapping.RunSlice(slice); });
      sums = overlapping.Sums();
      break;
    }
    case AllanEstimator::kMdev:
      for (size_t k = 0; k < m.size(); ++k) sums[k] = ModifiedSum(phase, n_phase, m[k], threads);
      break;
    case AllanEstimator::kAdev:
    case AllanEstimator::kHdev:
      for (size_t k = 0; k < m.size(); ++k) {
        sums[k] = NonOverlappingSum(phase, n_phase, m[k], estimator == AllanEstimator::kHdev);
      }
      break;
  }
  return VariancesFromSums(sums, n_phase, tau0_s, m, estimator);
}

std::vector<double> VariancesFromSums(const std::vector<double>& sums, int64_t n_phase,
                                      double tau0_s, const std::vector<int64_t>& m,
                                      AllanEstimator estimator) {
  std::vector<double> variance(m.size());
  for (size_t k = 0; k < m.size(); ++k) {
    const double tau = static_cast<double>(m[k]) * tau0_s;
    const double n = static_cast<double>(AllanTermCount(estimator, n_phase, m[k]));
    const double md = static_cast<double>(m[k]);
    switch (estimator) {
      case AllanEstimator::kOadev:  // NIST SP 1065 5.2.4
      case AllanEstimator::kAdev:   // NIST SP 1065 5.2.2
        variance[k] = sums[k] / (2.0 * tau * tau * n);
        break;
      case AllanEstimator::kMdev:  // NIST SP 1065 5.2.5
        variance[k] = sums[k] / (2.0 * md * md * tau * tau * n);
        break;
      case AllanEstimator::kOhdev:  // NIST SP 1065 5.2.9
      case AllanEstimator::kHdev:   // NIST SP 1065 5.2.8
        variance[k] = sums[k] / (6.0 * tau * tau * n);
        break;
    }
  }
  return variance;
}

}  // namespace

namespace {

// ComputeAllan after the integration: phase (N = n_rate + 1 points) and the removed mean.
Result<AllanCurve> AllanFromPhase(const double* phase, int64_t n_rate, double rate_mean,
                                  double tau0_s, const AllanOptions& options);

}  // namespace

Result<AllanCurve> ComputeAllan(const std::vector<double>& rate, double tau0_s,
                                const AllanOptions& options) {
  return ComputeAllan(rate.data(), static_cast<int64_t>(rate.size()), tau0_s, options);
}

Result<AllanCurve> ComputeAllan(const double* rate, int64_t n, double tau0_s,
                                const AllanOptions& options) {
  METRO_CHECK(rate != nullptr || n == 0);
  std::string why;
  if (!options.IsValid(&why)) return MakeError("Allan options: " + why);
  if (!(std::isfinite(tau0_s) && tau0_s > 0.0)) {
    return MakeError(fmt::format("sample period tau0 = {} s is not a positive number", tau0_s));
  }
  std::vector<double> phase;
  const PhaseResult integrated = IntegratePhase(rate, n, tau0_s, options.threads, true, [&] {
    return NewPhase(static_cast<size_t>(n) + 1, &phase);
  });
  if (integrated.first_bad >= 0) {
    const int64_t i = integrated.first_bad;
    return MakeError(fmt::format("rate sample {} (0-based) is not finite ({})", i, rate[i]));
  }
  return AllanFromPhase(phase.data(), n, integrated.mean, tau0_s, options);
}

namespace internal {

void FillAlphaAndIntervals(const std::vector<char>& identified,
                           const std::vector<int>& identified_alpha,
                           const std::vector<EdfRecords>& records, const AllanOptions& options,
                           AllanCurve* curve) {
  const size_t n = curve->m.size();
  const EstimatorShape shape = ShapeOf(options.estimator);
  curve->ci_low.resize(n);
  curve->ci_high.resize(n);
  curve->edf.resize(n);
  curve->alpha.resize(n);
  curve->alpha_source.resize(n);
  bool have_identified = false;
  int last_alpha = 0;
  for (size_t k = 0; k < n; ++k) {
    if (options.noise_id == NoiseIdMethod::kFixed) {
      curve->alpha[k] = options.fixed_alpha;
      curve->alpha_source[k] = AlphaSource::kFixed;
    } else if (identified[k]) {
      curve->alpha[k] = identified_alpha[k];
      curve->alpha_source[k] = AlphaSource::kLag1Acf;
      last_alpha = identified_alpha[k];
      have_identified = true;
    } else if (have_identified) {
      curve->alpha[k] = last_alpha;
      curve->alpha_source[k] = AlphaSource::kCarried;
    } else {
      curve->alpha[k] = 0;
      curve->alpha_source[k] = AlphaSource::kDefault;
    }
    auto edf_of = [&](int64_t n_phase) {
      return GreenhallRileyEdf(curve->alpha[k], shape.d, curve->m[k], n_phase, shape.overlapping,
                               shape.modified);
    };
    const EdfRecords& record = records[k];
    Result<double> edf = MakeError("no run of terms");
    if (record.run_phase_points.size() == 1) {
      edf = edf_of(record.run_phase_points[0]);
    } else if (!record.run_phase_points.empty()) {
      double sum = 0.0;
      for (int64_t n_phase : record.run_phase_points) {
        const Result<double> part = edf_of(n_phase);
        if (part.ok()) sum += part.value();
      }
      const Result<double> whole = edf_of(record.whole_phase_points);
      edf = whole.ok() ? std::min(sum, whole.value()) : sum;
    }
    const double nan = std::nan("");
    curve->edf[k] = edf.ok() ? edf.value() : nan;
    curve->ci_low[k] = nan;
    curve->ci_high[k] = nan;
    if (edf.ok()) {
      const Result<DeviationInterval> ci =
          ChiSquaredInterval(curve->dev[k], edf.value(), options.confidence);
      if (ci.ok()) {
        curve->ci_low[k] = ci.value().low;
        curve->ci_high[k] = ci.value().high;
      }
    }
  }
}

void RunAllanTasks(int threads, int64_t count, const std::function<void(int64_t)>& task) {
  if (count <= 0) return;
  ParallelFor(static_cast<size_t>(count), std::max(threads, 1),
              [&task](size_t t) { task(static_cast<int64_t>(t)); });
}

Result<AllanCurve> ComputeAllanInPlace(std::vector<double>* buffer, double tau0_s,
                                       const AllanOptions& options) {
  METRO_CHECK(buffer != nullptr && !buffer->empty());
  return ComputeAllanInPlace(buffer->data(), static_cast<int64_t>(buffer->size()), tau0_s, options);
}

Result<AllanCurve> ComputeAllanInPlace(double* data, int64_t size, double tau0_s,
                                       const AllanOptions& options) {
  METRO_CHECK(data != nullptr && size >= 1);
  std::string why;
  if (!options.IsValid(&why)) return MakeError("Allan options: " + why);
  if (!(std::isfinite(tau0_s) && tau0_s > 0.0)) {
    return MakeError(fmt::format("sample period tau0 = {} s is not a positive number", tau0_s));
  }
  const int64_t n_rate = size - 1;
  const PhaseResult integrated =
      IntegratePhase(data + 1, n_rate, tau0_s, options.threads, true, [data] { return data; });
  if (integrated.first_bad >= 0) {
    const size_t i = static_cast<size_t>(integrated.first_bad);
    return MakeError(fmt::format("rate sample {} (0-based) is not finite ({})", i, data[i + 1]));
  }
  return AllanFromPhase(data, n_rate, integrated.mean, tau0_s, options);
}

int64_t PhaseBlockSamples() { return kPhaseBlock; }

void AddCompensated(double v, double* sum, double* carry) { CompensatedAdd(v, sum, carry); }

void RunPhaseBlock(const double* y, int64_t count, double mean, double tau0_s, double* x,
                   double* carry, double* phase) {
  METRO_CHECK(count <= kPhaseBlock);
  RunBlocks(y, count, mean, tau0_s, 0, 1, x, carry, phase);
}

int64_t ModifiedSegmentTerms(int64_t m) { return std::max<int64_t>(int64_t{1} << 16, 16 * m); }

std::vector<double> VariancesOfSums(const std::vector<double>& sums, int64_t n_phase, double tau0_s,
                                    const std::vector<int64_t>& m, AllanEstimator estimator) {
  return VariancesFromSums(sums, n_phase, tau0_s, m, estimator);
}

void FinishGapFreeCurve(const std::vector<int64_t>& m, const std::vector<double>& variance,
                        int64_t n_phase, const std::vector<char>& identified,
                        const std::vector<int>& identified_alpha, const AllanOptions& options,
                        AllanCurve* curve) {
  const size_t n = m.size();
  const double tau0_s = curve->tau0_s;
  curve->m = m;
  curve->tau_s.resize(n);
  curve->dev.resize(n);
  curve->n_terms.resize(n);
  std::vector<EdfRecords> records(n);
  for (size_t k = 0; k < n; ++k) {
    curve->tau_s[k] = static_cast<double>(m[k]) * tau0_s;
    curve->dev[k] = std::sqrt(std::max(variance[k], 0.0));
    curve->n_terms[k] = AllanTermCount(options.estimator, n_phase, m[k]);
    records[k].run_phase_points = {n_phase};
    records[k].whole_phase_points = n_phase;
  }
  curve->n_terms_gap_free = curve->n_terms;
  FillAlphaAndIntervals(identified, identified_alpha, records, options, curve);
}

}  // namespace internal

namespace {

Result<AllanCurve> AllanFromPhase(const double* phase, int64_t n_rate, double rate_mean,
                                  double tau0_s, const AllanOptions& options) {
  const int64_t n_phase = n_rate + 1;
  std::vector<int64_t> m;
  if (!options.m_list.empty()) {
    m = options.m_list;
    std::sort(m.begin(), m.end());
    m.erase(std::unique(m.begin(), m.end()), m.end());
    for (int64_t mk : m) {
      if (AllanTermCount(options.estimator, n_phase, mk) < 1) {
        return MakeError(fmt::format("averaging factor m = {} leaves no {} term with {} samples",
                                     mk, AllanEstimatorName(options.estimator), n_rate));
      }
    }
  } else {
    Result<std::vector<int64_t>> factors =
        AveragingFactors(options.estimator, options.taus, n_rate, options.max_m);
    if (!factors.ok()) return factors.error();
    m = std::move(factors).value();
  }

  AllanCurve curve;
  curve.estimator = options.estimator;
  curve.tau0_s = tau0_s;
  curve.n_rate_samples = n_rate;
  curve.confidence = options.confidence;
  curve.rate_mean = rate_mean;
  const EstimatorShape shape = ShapeOf(options.estimator);
  const size_t n = m.size();

  // Lag-1 noise identification at every tau with enough points (each reads only the phase).
  std::vector<char> identified(n, 0);
  std::vector<int> identified_alpha(n, 0);
  std::vector<size_t> todo;
  if (options.noise_id != NoiseIdMethod::kFixed) {
    for (size_t k = 0; k < n; ++k) {
      if ((n_phase - 1) / m[k] + 1 >= options.min_points_noise_id) todo.push_back(k);
    }
  }
  const auto identify = [&](size_t j) {
    const size_t k = todo[j];
    const Result<NoiseIdentification> id = IdentifyNoiseLag1(
        phase, n_phase, m[k], shape.d, options.min_points_noise_id, options.max_points_noise_id);
    if (id.ok()) {
      identified[k] = 1;
      identified_alpha[k] = id.value().alpha;
    }
  };
  const int threads = ResolveThreads(options.threads, n_phase);
  const int64_t n_id = static_cast<int64_t>(todo.size());
  std::vector<double> variance;
  if (options.estimator == AllanEstimator::kOadev || options.estimator == AllanEstimator::kOhdev) {
    // One pool of tasks: the identifications (smallest m, the costliest, first), then the
    // slices of the variance sums.
    OverlappingSums overlapping(phase, n_phase, m, options.estimator);
    internal::RunAllanTasks(threads, n_id + overlapping.slices(), [&](int64_t t) {
      if (t < n_id) {
        identify(static_cast<size_t>(t));
      } else {
        overlapping.RunSlice(t - n_id);
      }
    });
    variance = VariancesFromSums(overlapping.Sums(), n_phase, tau0_s, m, options.estimator);
  } else {
    variance = PhaseVariances(phase, n_phase, tau0_s, m, options.estimator, threads);
    internal::RunAllanTasks(threads, n_id, [&](int64_t t) { identify(static_cast<size_t>(t)); });
  }

  internal::FinishGapFreeCurve(m, variance, n_phase, identified, identified_alpha, options, &curve);
  return curve;
}

}  // namespace

}  // namespace metro
