// Private entry point of the Allan computation for readers that own their sample buffer.
//
// ComputeAllanInPlace takes a buffer laid out as [unused, y_0, ..., y_{M-1}] (M + 1 values)
// and turns it into the phase x_0 .. x_M in place (allan.hpp: x_0 = 0,
// x_{k+1} = x_k + (y_k - mean) tau0), so a reader that parses straight into the buffer needs
// one 8 M-byte array instead of two. The curve is bit-identical to
// ComputeAllan({y_0, ..., y_{M-1}}, tau0_s, options), errors included (the message names the
// 0-based sample index). On an error the buffer may hold samples or phase.
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include "metro/core/status.hpp"
#include "metro/noise/allan.hpp"

namespace metro {
namespace internal {

// Precondition: buffer is not null and holds at least one value (slot 0).
Result<AllanCurve> ComputeAllanInPlace(std::vector<double>* buffer, double tau0_s,
                                       const AllanOptions& options = AllanOptions());

// The same on the `size` values at data (data[0] unused, then the M = size - 1 samples), for
// a reader that allocates its own buffer (e.g. without zero-filling it first).
// Precondition: data is not null and size >= 1.
Result<AllanCurve> ComputeAllanInPlace(double* data, int64_t size, double tau0_s,
                                       const AllanOptions& options = AllanOptions());

// The records whose terms make up the estimate at one tau, for its EDF: the phase points
// of each gap-free run of terms (one run, the whole record, without gaps), and of the record
// as a whole had it no gaps.
struct EdfRecords {
  std::vector<int64_t> run_phase_points;
  int64_t whole_phase_points = 0;
};

// The last stage of every curve: alpha at each tau (identified where identified[k], else
// carried from the largest smaller tau identified, else white rate noise; or the fixed
// alpha), then the EDF and the chi-squared interval (NIST SP 1065 5.3.2). The EDF is the
// Greenhall-Riley EDF of a single run; with several runs it is the sum of the runs' EDFs
// (runs read disjoint samples: independent for white noise), capped at the EDF of the whole
// record without gaps, which no subset of its terms can exceed. curve->m and curve->dev must
// be filled.
void FillAlphaAndIntervals(const std::vector<char>& identified,
                           const std::vector<int>& identified_alpha,
                           const std::vector<EdfRecords>& records, const AllanOptions& options,
                           AllanCurve* curve);

// The curve of a record without gaps from its variances at each m (tau, deviation, terms;
// one run of n_phase points for the EDF), then FillAlphaAndIntervals. curve->tau0_s and the
// curve's header (estimator, counts, mean) must be set.
void FinishGapFreeCurve(const std::vector<int64_t>& m, const std::vector<double>& variance,
                        int64_t n_phase, const std::vector<char>& identified,
                        const std::vector<int>& identified_alpha, const AllanOptions& options,
                        AllanCurve* curve);

// How the Allan module runs its parallel work: task(0..count-1) on up to `threads` threads
// (core/parallel.hpp ParallelFor); an exception thrown by a task is rethrown here, in the
// caller, once the other threads have stopped (it used to end the process).
void RunAllanTasks(int threads, int64_t count, const std::function<void(int64_t)>& task);

// The pieces of the phase integration (allan.cpp) that the chunked computation
// (allan_chunked.cpp) repeats block by block, so that both give the same phase bits:
// rate samples per block; sum += v with Neumaier's compensation; the compensated running
// sum of one block's centred steps (y_k - mean) tau0 from (*x, *carry), with phase[k + 1] =
// x + carry after step k when phase is not null; and the variances from the sums of squared
// differences (NIST SP 1065 5.2.2-5.2.9).
int64_t PhaseBlockSamples();
void AddCompensated(double v, double* sum, double* carry);
void RunPhaseBlock(const double* y, int64_t count, double mean, double tau0_s, double* x,
                   double* carry, double* phase);
// The modified Allan sum's segments: its inner sum is recomputed from scratch at the start of
// every segment of this many terms (at least 16 m, so that the recomputation, O(m), stays a
// small share of the segment's work).
int64_t ModifiedSegmentTerms(int64_t m);
std::vector<double> VariancesOfSums(const std::vector<double>& sums, int64_t n_phase, double tau0_s,
                                    const std::vector<int64_t>& m, AllanEstimator estimator);

}  // namespace internal
}  // namespace metro
