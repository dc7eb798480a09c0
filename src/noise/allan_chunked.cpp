// ComputeAllanChunked (allan.hpp): the overlapping Allan and Hadamard deviations of a record
// read in chunks, in memory independent of its length (the streaming mode, issue #38 step 2).
//
// Stages, each a pass over the rate samples through the ChunkReader:
//   1. BlockSums      per-block sums in IntegratePhase's four lanes -> the mean (compensated)
//   2. BlockStarts    per-block compensated totals of (y - mean) tau0 -> each block's
//                     starting phase and carry
//   3. SweepTerms     the phase regenerated block by block from those starts (the same bits
//                     as ComputeAllan's phase array) at every offset the sums read: offsets up
//                     to kNearOffsets from one sliding window, larger ones from a cursor each;
//                     the sums of squared differences at every m, and the decimated phase the
//                     lag-1 noise identification reads (its first max_points_noise_id points)
//   4. the variances, the identification and the intervals, as in ComputeAllan.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <tuple>

#include "metro/noise/noise_id.hpp"
#include "noise/allan_internal.hpp"

namespace metro {
namespace {

// Rate samples read per chunk, and the largest offset served from the sliding window.
constexpr int64_t kChunk = int64_t{1} << 16;
constexpr int64_t kNearOffsets = int64_t{1} << 16;

struct Blocks {
  double mean = 0.0;
  std::vector<double> start_x, start_carry;
};

Result<Blocks> BlockSums(const ChunkReader& read, int64_t n, double tau0_s) {
  const int64_t block = internal::PhaseBlockSamples();
  const int64_t blocks = (n + block - 1) / block;
  std::vector<double> y(static_cast<size_t>(block));
  double total = 0.0, total_carry = 0.0;
  for (int64_t b = 0; b < blocks; ++b) {
    const int64_t lo = b * block, hi = std::min(n, lo + block);
    if (Status s = read(static_cast<size_t>(lo), static_cast<size_t>(hi - lo), y.data()); !s.ok()) {
      return s.error();
    }
    double s4[4] = {0.0, 0.0, 0.0, 0.0};
    int64_t k = 0;
    for (; k + 4 <= hi - lo; k += 4) {
      for (int64_t j = 0; j < 4; ++j) s4[j] += y[static_cast<size_t>(k + j)];
    }
    for (; k < hi - lo; ++k) s4[0] += y[static_cast<size_t>(k)];
    const double sum = (s4[0] + s4[1]) + (s4[2] + s4[3]);
    if (!std::isfinite(sum)) {
      for (k = 0; k < hi - lo; ++k) {
        if (!std::isfinite(y[static_cast<size_t>(k)])) {
          return MakeError(fmt::format("rate sample {} (0-based) is not finite ({})", lo + k,
                                       y[static_cast<size_t>(k)]));
        }
      }
    }
    internal::AddCompensated(sum, &total, &total_carry);
  }
  Blocks out;
  out.mean = n == 0 ? 0.0 : (total + total_carry) / static_cast<double>(n);
  // Stage 2: each block's total of centred steps, then the running starts.
  out.start_x.assign(static_cast<size_t>(blocks), 0.0);
  out.start_carry.assign(static_cast<size_t>(blocks), 0.0);
  double x = 0.0, carry = 0.0;
  for (int64_t b = 0; b < blocks; ++b) {
    const int64_t lo = b * block, hi = std::min(n, lo + block);
    if (Status s = read(static_cast<size_t>(lo), static_cast<size_t>(hi - lo), y.data()); !s.ok()) {
      return s.error();
    }
    double bx = 0.0, bc = 0.0;
    internal::RunPhaseBlock(y.data(), hi - lo, out.mean, tau0_s, &bx, &bc, nullptr);
    out.start_x[static_cast<size_t>(b)] = x;
    out.start_carry[static_cast<size_t>(b)] = carry;
    internal::AddCompensated(bx, &x, &carry);
    carry += bc;
  }
  return out;
}

// The phase x_j, j = 0..n, in order from any first index, regenerated from the block starts.
class PhaseCursor {
 public:
  PhaseCursor(const ChunkReader& read, int64_t n, double tau0_s, const Blocks& blocks)
      : read_(read),
        n_(n),
        tau0_s_(tau0_s),
        blocks_(blocks),
        block_(internal::PhaseBlockSamples()),
        y_(static_cast<size_t>(block_)),
        phase_(static_cast<size_t>(block_) + 1) {}

  // out[0, count) = x_j, x_{j+1}, ...; j must not go back between calls.
  Status Fill(int64_t j, int64_t count, double* out) {
    for (int64_t k = 0; k < count; ++k) {
      const int64_t at = j + k;
      if (at == 0) {
        out[k] = 0.0;
        continue;
      }
      // x_at follows sample at - 1, in block b.
      const int64_t b = (at - 1) / block_;
      if (b != loaded_) {
        if (Status s = Load(b); !s.ok()) return s;
      }
      out[k] = phase_[static_cast<size_t>(at - b * block_)];
    }
    return Status::Ok();
  }

 private:
  Status Load(int64_t b) {
    const int64_t lo = b * block_, hi = std::min(n_, lo + block_);
    if (Status s = read_(static_cast<size_t>(lo), static_cast<size_t>(hi - lo), y_.data());
        !s.ok()) {
      return s;
    }
    double x = blocks_.start_x[static_cast<size_t>(b)];
    double carry = blocks_.start_carry[static_cast<size_t>(b)];
    // phase_[k + 1] = x_{lo + k + 1}, after step k.
    internal::RunPhaseBlock(y_.data(), hi - lo, blocks_.mean, tau0_s_, &x, &carry, phase_.data());
    loaded_ = b;
    return Status::Ok();
  }

  const ChunkReader& read_;
  int64_t n_;
  double tau0_s_;
  const Blocks& blocks_;
  int64_t block_;
  std::vector<double> y_, phase_;
  int64_t loaded_ = -1;
};

// The largest offset, in multiples of m, at which an estimator's terms read the phase: x_i
// .. x_{i+2m} (oadev, adev), x_i .. x_{i+3m} (ohdev, hdev; mdev, whose slide at i reads
// d_i and d_{i+m}).
int64_t OffsetOrder(AllanEstimator estimator) {
  return estimator == AllanEstimator::kOadev || estimator == AllanEstimator::kAdev ? 2 : 3;
}

// What one averaging factor accumulates over the sweep.
struct TermSums {
  double sum = 0.0;  // The sum of squares (mdev: of the closed segments).
  // mdev: the inner sum at each segment's first term (ModifiedStarts; empty when 3 m <=
  // kNearOffsets, where the sweep's window holds it: InnerSum), the running inner sum and the
  // open segment's total.
  std::vector<double> starts;
  double inner = 0.0, segment_total = 0.0;
};

// mdev: inner + d_0 + ... + d_{count-1}, d_k = (x2[k] - 2 x1[k]) + x0[k], in allan.cpp's
// ModifiedSum's order and form.
double InnerSum(double inner, const double* x0, const double* x1, const double* x2, int64_t count) {
  for (int64_t k = 0; k < count; ++k) inner += (x2[k] - 2.0 * x1[k]) + x0[k];
  return inner;
}

// mdev: the inner sum sum_{i=s}^{s+m-1} d_i at the first term s of every segment, in the
// order of allan.cpp's ModifiedSum (the same bits), from three cursors at x_s, x_{s+m} and
// x_{s+2m}.
Result<std::vector<double>> ModifiedStarts(const ChunkReader& read, int64_t n_phase, double tau0_s,
                                           const Blocks& blocks, int64_t m) {
  const int64_t n_terms = AllanTermCount(AllanEstimator::kMdev, n_phase, m);
  const int64_t segment = internal::ModifiedSegmentTerms(m);
  PhaseCursor c0(read, n_phase - 1, tau0_s, blocks), c1(read, n_phase - 1, tau0_s, blocks),
      c2(read, n_phase - 1, tau0_s, blocks);
  const int64_t piece = std::min(m, kChunk);
  std::vector<double> x0(static_cast<size_t>(piece)), x1(x0.size()), x2(x0.size());
  std::vector<double> starts;
  for (int64_t s = 0; s < n_terms; s += segment) {
    double inner = 0.0;
    for (int64_t i = s; i < s + m; i += piece) {
      const int64_t c = std::min(piece, s + m - i);
      for (auto [cursor, out, offset] : {std::tuple{&c0, &x0, int64_t{0}}, std::tuple{&c1, &x1, m},
                                         std::tuple{&c2, &x2, 2 * m}}) {
        if (Status st = cursor->Fill(i + offset, c, out->data()); !st.ok()) return st.error();
      }
      inner = InnerSum(inner, x0.data(), x1.data(), x2.data(), c);
    }
    starts.push_back(inner);
  }
  return starts;
}

// One chunk's terms for one m: at[q][i] = x_{j0 + i + q m}, i < count.
void AddChunkTerms(AllanEstimator estimator, const double* const at[4], int64_t mk, int64_t j0,
                   int64_t count, int64_t n_terms, TermSums* t) {
  switch (estimator) {
    case AllanEstimator::kOadev:
    case AllanEstimator::kOhdev: {
      // x_i - 2 x_{i+m} + x_{i+2m} (NIST SP 1065 5.2.4) and x_i - 3 x_{i+m} + 3 x_{i+2m} -
      // x_{i+3m} (5.2.9), every i < n_terms.
      const int64_t stop = std::min(count, n_terms - j0);
      double sum = 0.0;
      if (estimator == AllanEstimator::kOadev) {
        for (int64_t i = 0; i < stop; ++i) {
          const double d = at[0][i] - 2.0 * at[1][i] + at[2][i];
          sum += d * d;
        }
      } else {
        for (int64_t i = 0; i < stop; ++i) {
          const double d = at[0][i] - 3.0 * at[1][i] + 3.0 * at[2][i] - at[3][i];
          sum += d * d;
        }
      }
      t->sum += sum;
      break;
    }
    case AllanEstimator::kAdev:
    case AllanEstimator::kHdev: {
      // The same differences at i = k m, k < n_terms (5.2.2, 5.2.8), added in allan.cpp's
      // NonOverlappingSum's order and form.
      for (int64_t i = (j0 + mk - 1) / mk * mk - j0; i < count && (j0 + i) / mk < n_terms;
           i += mk) {
        const double v = estimator == AllanEstimator::kHdev
                             ? (at[3][i] - at[0][i]) - 3.0 * (at[2][i] - at[1][i])
                             : (at[2][i] - 2.0 * at[1][i]) + at[0][i];
        t->sum += v * v;
      }
      break;
    }
    case AllanEstimator::kMdev: {
      // Term j = b + 1 slides from d_b to d_{b+m}, or starts a segment (ModifiedSum).
      const int64_t segment = internal::ModifiedSegmentTerms(mk);
      if (j0 == 0 && t->starts.empty()) {
        t->inner = InnerSum(0.0, at[0], at[0] + mk, at[0] + 2 * mk, mk);
        t->segment_total = t->inner * t->inner;
      }
      const int64_t stop = std::min(count, n_terms - 1 - j0);
      for (int64_t i = 0; i < stop; ++i) {
        const int64_t j = j0 + i + 1;
        if (j % segment == 0) {
          t->sum += t->segment_total;
          t->segment_total = 0.0;
          t->inner = t->starts.empty() ? InnerSum(0.0, at[0] + i + 1, at[0] + i + 1 + mk,
                                                  at[0] + i + 1 + 2 * mk, mk)
                                       : t->starts[static_cast<size_t>(j / segment)];
        } else {
          const double d_hi = (at[3][i] - 2.0 * at[2][i]) + at[1][i];
          const double d_lo = (at[2][i] - 2.0 * at[1][i]) + at[0][i];
          t->inner += d_hi - d_lo;
        }
        t->segment_total += t->inner * t->inner;
      }
      break;
    }
  }
}

struct Sweep {
  std::vector<TermSums> terms;                 // Per m.
  std::vector<std::vector<double>> decimated;  // Per m: x_{k m}, k < used (noise id).
};

// Before the sweep: mdev's segment starts and its first term.
Status PrepareTerms(const ChunkReader& read, int64_t n_phase, double tau0_s, const Blocks& blocks,
                    const std::vector<int64_t>& m, AllanEstimator estimator, Sweep* out) {
  out->terms.assign(m.size(), TermSums());
  out->decimated.resize(m.size());
  if (estimator != AllanEstimator::kMdev) return Status::Ok();
  for (size_t k = 0; k < m.size(); ++k) {
    if (3 * m[k] <= kNearOffsets) continue;  // The window holds them (AddChunkTerms).
    Result<std::vector<double>> starts = ModifiedStarts(read, n_phase, tau0_s, blocks, m[k]);
    if (!starts.ok()) return starts.error();
    TermSums& t = out->terms[k];
    t.starts = std::move(starts).value();
    t.inner = t.starts.front();
    t.segment_total = t.inner * t.inner;
  }
  return Status::Ok();
}

// Stage 3 (see the top of the file).
Result<Sweep> SweepTerms(const ChunkReader& read, int64_t n_phase, double tau0_s,
                         const Blocks& blocks, const std::vector<int64_t>& m,
                         const std::vector<int64_t>& used, AllanEstimator estimator) {
  const int64_t n_rate = n_phase - 1;
  const int64_t order = OffsetOrder(estimator);
  // The far offsets (q m > kNearOffsets) and a cursor for each.
  std::map<int64_t, std::unique_ptr<PhaseCursor>> far;
  for (int64_t mk : m) {
    for (int64_t q = 1; q <= order; ++q) {
      if (q * mk > kNearOffsets && far.count(q * mk) == 0) {
        far[q * mk] = std::make_unique<PhaseCursor>(read, n_rate, tau0_s, blocks);
      }
    }
  }
  std::map<int64_t, std::vector<double>> far_values;
  for (const auto& f : far) far_values[f.first].resize(static_cast<size_t>(kChunk));
  PhaseCursor near(read, n_rate, tau0_s, blocks);
  std::vector<double> window(static_cast<size_t>(kChunk + kNearOffsets));
  Sweep out;
  if (Status s = PrepareTerms(read, n_phase, tau0_s, blocks, m, estimator, &out); !s.ok()) {
    return s.error();
  }
  int64_t filled_to = 0;  // The window holds x_{j0} .. x_{filled_to - 1}.
  for (int64_t j0 = 0; j0 < n_phase; j0 += kChunk) {
    const int64_t count = std::min(kChunk, n_phase - j0);
    const int64_t have = std::min(kChunk + kNearOffsets, n_phase - j0);
    if (j0 > 0) {
      // Slide: the values past the last chunk move to the front.
      std::copy(window.begin() + kChunk, window.begin() + (filled_to - j0 + kChunk),
                window.begin());
    }
    const int64_t kept = std::max<int64_t>(0, filled_to - j0);
    if (Status s = near.Fill(j0 + kept, have - kept, window.data() + kept); !s.ok()) {
      return s.error();
    }
    filled_to = j0 + have;
    for (auto& f : far) {
      const int64_t from = j0 + f.first;
      if (from >= n_phase) continue;
      const int64_t c = std::min(count, n_phase - from);
      if (Status s = f.second->Fill(from, c, far_values[f.first].data()); !s.ok()) {
        return s.error();
      }
    }
    for (size_t k = 0; k < m.size(); ++k) {
      const int64_t mk = m[k];
      const double* at[4] = {window.data(), nullptr, nullptr, nullptr};
      for (int64_t q = 1; q <= order; ++q) {
        at[q] = q * mk > kNearOffsets ? far_values[q * mk].data() : window.data() + q * mk;
      }
      AddChunkTerms(estimator, at, mk, j0, count, AllanTermCount(estimator, n_phase, mk),
                    &out.terms[k]);
      std::vector<double>& z = out.decimated[k];
      for (int64_t p = (j0 + mk - 1) / mk; p < used[k] && p * mk < j0 + count; ++p) {
        z.push_back(window[static_cast<size_t>(p * mk - j0)]);
      }
    }
  }
  for (TermSums& t : out.terms) t.sum += t.segment_total;  // mdev's last segment; 0 otherwise.
  return out;
}

}  // namespace

Result<AllanCurve> ComputeAllanChunked(const ChunkReader& read, int64_t n_rate, double tau0_s,
                                       const AllanOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) return MakeError("Allan options: " + why);
  if (!(std::isfinite(tau0_s) && tau0_s > 0.0)) {
    return MakeError(fmt::format("sample period tau0 = {} s is not a positive number", tau0_s));
  }
  if (!options.m_list.empty()) {
    return MakeError("explicit averaging factors are not available in streaming mode");
  }
  Result<std::vector<int64_t>> factors =
      AveragingFactors(options.estimator, options.taus, n_rate, options.max_m);
  if (!factors.ok()) return factors.error();
  const std::vector<int64_t>& m = factors.value();
  const int64_t n_phase = n_rate + 1;
  Result<Blocks> blocks = BlockSums(read, n_rate, tau0_s);
  if (!blocks.ok()) return blocks.error();
  // The identification's points at each m (noise_id.hpp: the first max_points of them).
  const size_t n = m.size();
  std::vector<int64_t> used(n, 0);
  if (options.noise_id != NoiseIdMethod::kFixed) {
    for (size_t k = 0; k < n; ++k) {
      const int64_t points = (n_phase - 1) / m[k] + 1;
      if (points >= options.min_points_noise_id) {
        used[k] =
            std::min(points, std::max(options.max_points_noise_id, options.min_points_noise_id));
      }
    }
  }
  Result<Sweep> sweep =
      SweepTerms(read, n_phase, tau0_s, blocks.value(), m, used, options.estimator);
  if (!sweep.ok()) return sweep.error();
  std::vector<double> sums;
  for (const TermSums& t : sweep.value().terms) sums.push_back(t.sum);
  const std::vector<double> variance =
      internal::VariancesOfSums(sums, n_phase, tau0_s, m, options.estimator);
  const EstimatorShape shape = ShapeOf(options.estimator);
  std::vector<char> identified(n, 0);
  std::vector<int> identified_alpha(n, 0);
  for (size_t k = 0; k < n; ++k) {
    if (used[k] == 0) continue;
    const std::vector<double>& z = sweep.value().decimated[k];
    const Result<NoiseIdentification> id =
        IdentifyNoiseLag1(z.data(), static_cast<int64_t>(z.size()), 1, shape.d,
                          options.min_points_noise_id, options.max_points_noise_id);
    if (id.ok()) {
      identified[k] = 1;
      identified_alpha[k] = id.value().alpha;
    }
  }
  AllanCurve curve;
  curve.estimator = options.estimator;
  curve.tau0_s = tau0_s;
  curve.n_rate_samples = n_rate;
  curve.confidence = options.confidence;
  curve.rate_mean = blocks.value().mean;
  internal::FinishGapFreeCurve(m, variance, n_phase, identified, identified_alpha, options, &curve);
  return curve;
}

}  // namespace metro
