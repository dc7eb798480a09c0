// Allan-variance family of a rate ("frequency") series, with chi-squared confidence
// intervals from the Greenhall-Riley equivalent degrees of freedom.
//
// Rate samples y_k [q] (k = 0..M-1, spacing tau0) are integrated to phase after their mean is
// removed (no cancellation against a large gyro bias; the estimators are blind to the mean):
//   x_0 = 0,  x_{k+1} = x_k + (y_k - mean(y)) tau0            N = M + 1 phase points [q*s]
// With tau = m tau0 (NIST SP 1065, Riley 2008):
//   oadev  5.2.4: s^2 = sum_{i=0}^{N-2m-1} (x_{i+2m} - 2x_{i+m} + x_i)^2 / (2 tau^2 (N-2m))
//   mdev   5.2.5: s^2 = sum_{j=0}^{N-3m} (sum_{i=j}^{j+m-1} (x_{i+2m} - 2x_{i+m} + x_i))^2
//                       / (2 m^2 tau^2 (N-3m+1))
//   ohdev  5.2.9: s^2 = sum_{i=0}^{N-3m-1} (x_{i+3m} - 3x_{i+2m} + 3x_{i+m} - x_i)^2
//                       / (6 tau^2 (N-3m))
//   adev   5.2.2, hdev 5.2.8: the same sums over i = 0, m, 2m, ... only (non-overlapping).
// Each is one O(N) pass per tau. The deviation is reported in [q].
//
// Tau spacings (m = tau / tau0, 1 <= m <= max_m):
//   octave     m = 1, 2, 4, ...                                  cost O(N log2 max_m)
//   decade:K   m = round(10^(j/K)), j = 0, 1, ..., duplicates dropped
//   all        "all tau, thinned as Stable32 does": every m below 53, then
//              m_next = m + floor(m/53) + 1 (steps of ~1.9 %, ~120 taus per decade);
//              identical to Stable32's all-tau averaging factors.       cost O(N * 120 log10 max_m)
//   every      every m = 1..max_m, no thinning.                        cost O(N * max_m)
//              (N = 1e6: ~2e11 operations, minutes; use "all" unless every m is required).
// max_m defaults to floor(M / stop_ratio) with Stable32's stop ratios: 4 for oadev, mdev and
// ohdev, 5 for adev and hdev.
//
// Confidence intervals (SP 1065 5.3.2): chi-squared with the EDF of GreenhallRileyEdf()
// (edf.hpp) for the power-law noise type alpha (S_y ~ f^alpha) identified at each tau by the
// lag-1 autocorrelation (noise_id.hpp), or a fixed alpha.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "metro/core/spill_file.hpp"
#include "metro/core/status.hpp"

namespace metro {

enum class AllanEstimator { kOadev, kMdev, kOhdev, kAdev, kHdev };

// "oadev", "mdev", "ohdev", "adev", "hdev".
const char* AllanEstimatorName(AllanEstimator estimator);
Result<AllanEstimator> ParseAllanEstimator(const std::string& text);

// Parameters of the estimator for the EDF: difference order d (2 Allan, 3 Hadamard), whether
// the sum overlaps (stride tau0) and whether it is a modified variance.
struct EstimatorShape {
  int d = 2;
  bool overlapping = true;
  bool modified = false;
};
EstimatorShape ShapeOf(AllanEstimator estimator);

enum class TauSpacingKind { kOctave, kDecade, kAll, kEvery };

struct TauSpacing {
  TauSpacingKind kind = TauSpacingKind::kOctave;
  int per_decade = 0;  // Only for kDecade: points per decade, >= 1.
};

// "octave", "decade:K" (K an integer 1..1000), "all", "every".
Result<TauSpacing> ParseTauSpacing(const std::string& text);
std::string TauSpacingName(const TauSpacing& spacing);

enum class NoiseIdMethod {
  kLag1Acf,  // Lag-1 autocorrelation per tau (Riley & Greenhall 2004), see noise_id.hpp.
  kFixed,    // AllanOptions::fixed_alpha at every tau.
};

// Where the alpha used for a tau's confidence interval came from.
enum class AlphaSource {
  kLag1Acf,  // Identified at this tau.
  kCarried,  // Too few averages at this tau: the alpha of the largest smaller tau that had
             // enough (Riley's "use the last reliable identification").
  kDefault,  // No tau had enough averages: white rate noise (alpha = 0) is assumed.
  kFixed,    // Given by the caller.
};
const char* AlphaSourceName(AlphaSource source);

struct AllanOptions {
  AllanEstimator estimator = AllanEstimator::kOadev;
  TauSpacing taus;
  // Explicit averaging factors; when non-empty they replace `taus` (sorted, de-duplicated).
  std::vector<int64_t> m_list;
  // Largest averaging factor; 0 = floor(M / stop_ratio) (see above).
  int64_t max_m = 0;
  // Two-sided confidence level of [ci_low, ci_high], in (0, 1).
  double confidence = 0.683;
  NoiseIdMethod noise_id = NoiseIdMethod::kLag1Acf;
  int fixed_alpha = 0;  // Used with kFixed; -2..2 (Allan), -4..2 (Hadamard).
  // Fewest averages (M / m) at which the lag-1 ACF identification is trusted (Riley: 30).
  int64_t min_points_noise_id = 30;
  // Most averages the identification reads at one tau (the first ones): r1 then has a
  // sampling standard deviation near 1/sqrt(65536) = 0.004, far below the 0.25 steps of the
  // decision, and a long record costs no more per tau than 65536 points. >= min_points_noise_id.
  int64_t max_points_noise_id = int64_t{1} << 16;
  // Worker threads for the variance sums; 0 = all hardware threads.
  int threads = 0;

  bool IsValid(std::string* why) const;
};

// One curve; every vector has one entry per tau, in increasing tau.
struct AllanCurve {
  AllanEstimator estimator = AllanEstimator::kOadev;
  double tau0_s = 0.0;
  int64_t n_rate_samples = 0;  // M
  double rate_mean = 0.0;      // Mean removed before integration [q].
  double confidence = 0.683;
  std::vector<int64_t> m;
  std::vector<double> tau_s;
  std::vector<double> dev;       // Deviation [q].
  std::vector<double> ci_low;    // [q]; NaN where no EDF exists.
  std::vector<double> ci_high;   // [q]; NaN where no EDF exists.
  std::vector<double> edf;       // NaN where no EDF exists.
  std::vector<int64_t> n_terms;  // Terms in the sum (Stable32's "#").
  // Terms a record of the same length without missing samples has; n_terms where nothing is
  // missing. 1 - n_terms / n_terms_gap_free is the fraction of terms lost to gaps at a tau.
  std::vector<int64_t> n_terms_gap_free;
  int64_t n_missing_samples = 0;  // Missing grid points among the M (ComputeAllanWithGaps).
  std::vector<int> alpha;
  std::vector<AlphaSource> alpha_source;

  size_t size() const { return tau_s.size(); }
};

// Integrates rate samples to phase as above (N = M + 1 points). *mean_out (optional) receives
// the mean that was removed. Precondition: tau0_s > 0.
std::vector<double> PhaseFromRate(const std::vector<double>& rate, double tau0_s,
                                  double* mean_out = nullptr);

// Number of terms in the sum at averaging factor m for N phase points (0 if none).
int64_t AllanTermCount(AllanEstimator estimator, int64_t n_phase, int64_t m);

// Averaging factors for M rate samples (validates the spacing and max_m; errors name the cause).
Result<std::vector<int64_t>> AveragingFactors(AllanEstimator estimator, const TauSpacing& taus,
                                              int64_t n_rate, int64_t max_m);

// Variances (not deviations) for each m, from phase data, over fixed slices of the data
// shared between threads; the result does not depend on the thread count. Preconditions: every m
// has AllanTermCount() >= 1; tau0_s > 0.
std::vector<double> AllanVariances(const std::vector<double>& phase, double tau0_s,
                                   const std::vector<int64_t>& m, AllanEstimator estimator,
                                   int threads = 1);

// The whole curve: checks the input (finite samples, tau0 > 0, enough samples), integrates,
// computes the variance, identifies the noise type and the confidence interval at each tau.
Result<AllanCurve> ComputeAllan(const std::vector<double>& rate, double tau0_s,
                                const AllanOptions& options = AllanOptions());
// The same on the n samples at `rate`, read in place (not copied; the Python module's
// zero-copy input). Precondition: rate is not null when n > 0.
Result<AllanCurve> ComputeAllan(const double* rate, int64_t n, double tau0_s,
                                const AllanOptions& options = AllanOptions());

// Rate samples on a regular grid of period tau0_s, some of them missing (present[k] == 0: a
// lost BLE packet, a stale or never frame, an absent row), with the gap handling of NIST
// SP 1065 (section 5.15, "Data gaps") and Stable32: a term of the sums above that reads a
// missing sample is left out, and the variance is the mean of the terms that remain,
//   s^2 = (sum over valid terms) / (norm * n_valid)   instead of / (norm * n_terms).
// A term at phase index i reads the rate samples y[i, i + 2m) (oadev, adev), y[i, i + 3m)
// (ohdev, hdev), and the modified sum at j reads y[j, j + 3m - 1); a missing sample is never
// replaced by a guess. The mean removed before integration is that of the present samples.
// Taus left with no valid term are dropped. The valid terms come in runs of consecutive
// terms; terms of different runs read disjoint samples. Each run is a gap-free record with
// N_eq = b + 2m phase points for b terms (oadev; + 3m for ohdev, + 3m - 1 for mdev,
// (b + 1) m + 1 for adev, (b + 2) m + 1 for hdev), and the EDF (SP 1065 5.3.2,
// GreenhallRileyEdf) is the sum of the runs' EDFs, capped at the EDF of the whole record
// without gaps. Runs are independent for white rate noise, where this is exact to the GR
// approximation (68.3 % intervals measured at 63-72 % coverage with 2 % and 5 % loss,
// allan_gaps_test.cpp); for correlated noise the cap keeps the EDF at or below what the full
// record would have. The confidence interval widens as terms are lost. The noise type at each tau
// is identified on the longest gap-free stretch (the lag-1 ACF needs consecutive averages); where
// that stretch is too short, alpha is carried from a smaller tau as in ComputeAllan. Every curve
// field is as in ComputeAllan; n_terms counts the valid terms, n_terms_gap_free what the record
// would have without gaps, n_missing_samples the missing grid points. With every sample present the
// curve equals ComputeAllan's to rounding. Errors: sizes differ, fewer than 2 present samples, a
// present sample not finite, no tau with a valid term.
Result<AllanCurve> ComputeAllanWithGaps(const std::vector<double>& rate,
                                        const std::vector<uint8_t>& present, double tau0_s,
                                        const AllanOptions& options = AllanOptions());

// The same curve as ComputeAllan for a record of n_rate samples read in chunks (the streaming
// mode, issue #38 step 2): memory independent of the length (a few MB), three passes over
// the record. The phase is regenerated block by block exactly as ComputeAllan integrates it
// (the same bits); the sums differ from ComputeAllan's only in the order of their terms
// (relative differences of order 1e-15); mdev, adev and hdev sums are added in
// ComputeAllan's order, so they are the same bits. Every estimator, at the spacing's
// factors; explicit m lists return an Error saying so.
Result<AllanCurve> ComputeAllanChunked(const ChunkReader& read, int64_t n_rate, double tau0_s,
                                       const AllanOptions& options = AllanOptions());

}  // namespace metro
