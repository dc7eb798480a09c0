// Monte Carlo propagation of distributions (JCGM 101:2008).
//
// Each trial draws every input from its distribution (6.4) and evaluates the model. Trials
// are grouped in chunks of kChunkTrials; chunk c draws its words from four interleaved pcg64
// engines (pcg-cpp, PCG XSL RR 128/64), engine j starting at state
// splitmix64(splitmix64(seed) + 4c + j) on stream 4c + j, so the values depend on the seed
// only, never on the number of threads or on how chunks are shared between them. Each chunk
// draws input by input, in blocks (samplers and their accuracy: src/uncertainty/
// mc_sampling.hpp; t inputs by Bailey's polar method). Chunks are spread over worker threads
// (McOptions::threads, default: all cores) by core/parallel.
//
//   estimate y = mean of the M model values, u(y) their standard deviation      (7.6)
//   (two passes per chunk, chunks merged in chunk order by the pairwise update of
//   Chan, Golub and LeVeque, so the result does not depend on the thread count)
//   q = round(p M); probabilistically symmetric interval [y_(r), y_(r+q)],
//   r = (M - q)/2 rounded up; shortest interval: the r minimising y_(r+q) - y_(r)  (7.7)
//   (reported: the minimum of that width located by a least-squares parabola over the
//   ranks around the discrete one, end points interpolated between ranks (7.5.2); the
//   discrete r wanders like M^(-1/3), docs/uncertainty.md "Shortest interval")
//   Only the L = M - q lowest and highest order statistics are put in order: for
//   M >= 2^18 and L <= M/8 they are copied out by thresholds taken from a pilot subsample
//   (on all threads), otherwise by partial selection (std::nth_element); never a full sort.
//
// Adaptive run (7.9) with the stopping rule of docs/uncertainty.md: blocks of
// M_b = max(100/(1-p), 1e4) trials (rounded up to whole chunks); after h >= 10 blocks,
// stage 1 asks t_0.975(h-1) * s(h block values)/sqrt(h) <= delta for the mean, u(y) and both
// symmetric end points, delta = 1/2 10^l with u(y) = c 10^l, c an ndig-digit integer
// (7.9.2); stage 2 then tests the shortest end points themselves: the pooled values in
// G = 10 groups, t_0.975(9) s_G 10^(-2/5) <= delta for both end points. The reported
// results come from the pooled h M_b values; McResult::stability holds the half-widths.
// Chunks run on core/parallel: an exception in a worker (one thrown by
// McOptions::on_trials_done, std::bad_alloc) reaches the caller of RunMonteCarlo.
#pragma once

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "metro/core/status.hpp"
#include "metro/uncertainty/budget.hpp"
#include "metro/uncertainty/gum.hpp"

namespace metro {

constexpr int64_t kChunkTrials = 1000;

struct CoverageInterval {
  double low = std::numeric_limits<double>::quiet_NaN();
  double high = std::numeric_limits<double>::quiet_NaN();
};

// 95 % half-widths of the reported numbers at the stop of an adaptive run (JCGM 101 7.9.4
// with t factors, docs/uncertainty.md): each is compared with delta. NaN when not computed
// (fixed-size runs; the shortest end points before their test was reached).
struct McStability {
  double value = std::numeric_limits<double>::quiet_NaN();
  double u = std::numeric_limits<double>::quiet_NaN();
  double symmetric_low = std::numeric_limits<double>::quiet_NaN();
  double symmetric_high = std::numeric_limits<double>::quiet_NaN();
  double shortest_low = std::numeric_limits<double>::quiet_NaN();
  double shortest_high = std::numeric_limits<double>::quiet_NaN();
  int64_t groups = 0;  // G of the shortest end points' test
};

struct McResult {
  bool ok = false;  // False until a run finished (and, adaptive, converged).
  bool adaptive = false;
  bool converged = false;  // Adaptive: the stopping rule was met before max_trials.
  int64_t trials = 0;      // M actually used.
  int64_t blocks = 0;      // h (adaptive), else 1.
  uint64_t seed = 0;
  int threads = 0;
  std::string generator;
  double coverage = std::numeric_limits<double>::quiet_NaN();
  double value = std::numeric_limits<double>::quiet_NaN();  // y
  double u = std::numeric_limits<double>::quiet_NaN();      // u(y)
  CoverageInterval symmetric;
  CoverageInterval shortest;           // Fitted minimum of the width (docs/uncertainty.md).
  CoverageInterval shortest_discrete;  // JCGM 101 7.7 as written: the discrete minimiser.
  McStability stability;               // Adaptive runs.
  double delta = std::numeric_limits<double>::quiet_NaN();  // Numerical tolerance (7.9.2).
  std::string message;                                      // Why not ok, or notes.
  std::vector<double> samples;  // The M model values (unordered), if McOptions asked.
  // Inputs drawn from a t distribution with nu <= 2 (a Type A input of 2 or 3 readings;
  // JCGM 101 6.4.9.4: t_nu has a variance only for nu > 2 and a mean only for nu > 1),
  // "name (nu = 2)". With any of them u(y) is undefined: `u` is NaN and u_defined false; with
  // nu <= 1 the mean is undefined too (`value` NaN, mean_defined false). The coverage
  // intervals (quantiles) stay defined and are reported; delta and the adaptive stopping
  // rule then rest on the symmetric interval alone (docs/uncertainty.md, "Inputs without a
  // variance").
  std::vector<std::string> inputs_without_variance;
  bool u_defined = true;
  bool mean_defined = true;
};

// The inputs of `budget` whose Monte Carlo distribution has no variance (t with nu <= 2,
// JCGM 101 6.4.9.4), as "name (nu = 2)", for a caller to name before sampling.
std::vector<std::string> InputsWithoutVariance(const Budget& budget);

// Runs the Monte Carlo method with the budget's own McOptions (budget.monte_carlo).
Result<McResult> RunMonteCarlo(const Budget& budget);
// With explicit options; keep_samples returns the model values in McResult::samples.
Result<McResult> RunMonteCarlo(const Budget& budget, const McOptions& options,
                               bool keep_samples = false);

// Coverage intervals of a sample (may be reordered in place). Precondition: 0 < p < 1, at
// least two values, no NaN.
CoverageInterval SymmetricInterval(std::vector<double>* values, double coverage);
// ShortestInterval is JCGM 101 7.7 as written (the r minimising y_(r+q) - y_(r));
// ShortestIntervalFitted locates the minimum of that width by a least-squares parabola over
// the ranks around it (docs/uncertainty.md, "Shortest interval"), which is what McResult
// reports: its end points converge like M^(-1/2) to M^(-2/5) instead of M^(-1/3).
CoverageInterval ShortestInterval(std::vector<double>* values, double coverage);
CoverageInterval ShortestIntervalFitted(std::vector<double>* values, double coverage);

// Numerical tolerance of u with ndig significant digits (JCGM 101 7.9.2): u = c 10^l with
// c an ndig-digit integer, delta = 10^l / 2 (0.0996, ndig 2 -> c = 10, l = -2, 0.005).
double NumericalTolerance(double u, int ndig);

// GUF validation (JCGM 101 8.2): d_low = |y - U - y_low|, d_high = |y + U - y_high| against
// the MCM shortest interval, delta from the GUF u(y) at ndig digits (from the MCM u(y)
// when the GUF u is zero); validated when both are <= delta.
struct GufValidation {
  double delta = std::numeric_limits<double>::quiet_NaN();
  double d_low = std::numeric_limits<double>::quiet_NaN();
  double d_high = std::numeric_limits<double>::quiet_NaN();
  bool validated = false;
};
GufValidation ValidateGuf(const GumResult& gum, const McResult& mc, int ndig);

}  // namespace metro
