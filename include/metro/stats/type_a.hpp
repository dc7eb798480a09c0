// GUM Type A evaluation of a series of observations, with an autocorrelation-aware
// standard uncertainty of the mean.
//
// Classical (JCGM 100:2008 4.2), for observations q_1..q_n:
//   mean q_bar = (1/n) sum q_k                                     (4.2.1, eq. 3)
//   s^2(q_k) = 1/(n-1) sum (q_k - q_bar)^2                          (4.2.2, eq. 4)
//   s^2(q_bar) = s^2(q_k) / n,  dof = n - 1                         (4.2.3, eq. 5; 4.2.6)
// computed with the corrected two-pass algorithm (no naive sum of squares).
//
// Autocorrelated observations (Zhang, Metrologia 43 (2006) S276; JCGM 100 4.2.7 notes
// that s(q_bar) assumes independence):
//   rho_k = sum_{i=1}^{n-k} (q_i - q_bar)(q_{i+k} - q_bar) / sum_{i=1}^{n} (q_i - q_bar)^2
//   F = 1 + 2 sum_{k=1}^{n_c} (1 - k/n) rho_k
//   s^2(q_bar)_autocorr = F s^2(q_k) / n,   n_eff = n / F
// n_c is the last lag, scanning k = 1, 2, ... upward, whose |rho_k| lies outside the
// Bartlett band  t_{0.975}(n-1) sqrt((1 + 2 sum_{j<k} rho_j^2) / n)  (the first lag inside
// the band ends the scan; lag n_c itself is included), and at most n/4.
// rho_k is computed directly for the first lags and by FFT (FFTW) when the correlation
// extends further, so the cost is O(n log n) in the worst case.
//
// u_mean, metro's recommended standard uncertainty of the mean (docs/type-a.md): the AR(p)
// spectral density at frequency zero (stats/spectral_mean.hpp), u_mean^2 = S(0) / n, with
// dof nu = 1 / (2 R^2) (JCGM 100 G.4.2). Zhang's s(q_bar)_autocorr covers the mean too
// rarely under strong correlation (about 82 % instead of 95 % for AR(1), phi = 0.9,
// n = 200, with dof n_eff - 1); the AR estimator covers 94-96 % for phi <= 0.95, n >= 200.
// For n <= 3, or with autocorrelation off, u_mean is the classical s(q_bar) with n - 1 dof.
//
// Digitized readings (Willink, Metrologia 44 (2007) 73; GTC's type_a.estimate_digitized):
// with the readings' quantization step delta known (TypeAOptions::quantization_step, found
// by QuantizationStep), a series whose spread hides the noise is evaluated by Willink's
// rules, u_mean_method kUMeanDigitized, dof n - 1:
//   no spread (all readings equal):   u = sqrt(c / 12) delta,  c = 6.4, 1.3, 1.0 for
//                                     n = 2, 3, >= 4
//   a spread of exactly one step:     u = sqrt(max(u_0^2, (x_mid - q_bar)^2 / 3)),
//                                     x_mid = (x_max + x_min) / 2
// where u_0 is the u_mean of the rules above (GTC and Willink: s/sqrt(n); metro keeps its
// autocorrelation-aware value when it has one); the method stays u_0's when u_0 is the
// larger. A wider spread is not touched. `truncated` readings (cut, not rounded, to the
// step) raise the mean by delta / 2 (GTC's truncate), whatever the spread.
// Without a known step a constant series has no u_mean (u_mean_available false), for every n.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "metro/core/status.hpp"
#include "metro/stats/spectral_mean.hpp"

namespace metro {

struct TypeAOptions {
  // Two-sided confidence of the Bartlett band that decides the cut-off lag n_c.
  double band_confidence = 0.95;
  // Largest lag considered, as a fraction of n (Zhang: n/4).
  double max_lag_fraction = 0.25;
  // Compute n_eff and std_of_mean_autocorr.
  bool autocorrelation = true;
  // The readings' quantization step (resolution), in the series' unit; 0: not known. With
  // a step, a series with no spread or a spread of one step follows Willink's rules (above).
  double quantization_step = 0.0;
  // The readings were truncated to the step rather than rounded (needs a step).
  bool truncated = false;

  bool IsValid(std::string* why) const;
};

struct TypeAResult {
  int64_t n = 0;
  double mean = 0.0;
  double variance = 0.0;          // s^2(q_k), n - 1 in the denominator.
  double std = 0.0;               // s(q_k).
  double variance_of_mean = 0.0;  // s^2(q_bar) = s^2 / n.
  double std_of_mean = 0.0;       // s(q_bar).
  int64_t dof = 0;                // n - 1.
  // Autocorrelation-aware (Zhang 2006). Computed only when autocorr_computed; otherwise
  // (autocorrelation off, n <= 3, a constant series) they hold the classical values
  // (n_eff = n, F = 1, rho1 = 0, n_c = 0) for callers that need a number, the report
  // writes them as null and autocorr_note says why.
  bool autocorr_computed = false;
  std::string autocorr_note;
  double n_eff = 0.0;
  double std_of_mean_autocorr = 0.0;
  int64_t cutoff_lag = 0;        // n_c.
  double rho1 = 0.0;             // Lag-1 sample autocorrelation.
  double variance_factor = 1.0;  // F.
  // True when the lag scan reached max_lag_fraction * n without entering the band: the
  // series is dominated by drift and even n_eff is optimistic.
  bool cutoff_reached_limit = false;

  // Recommended standard uncertainty of the mean (unit of the series) and its dof.
  // u_mean_available is false only for a constant series (s = 0 says nothing about the
  // mean's uncertainty: the readings' resolution, a Type B input, bounds it).
  bool u_mean_available = false;
  double u_mean = 0.0;
  double u_mean_dof = 0.0;
  std::string u_mean_method;  // kUMeanArSpectral, kUMeanClassical, or "" (not available).
  int ar_order = 0;           // p of the AR fit (u_mean_method ar_spectral).
  // Why u_mean is not the AR value when the series was long enough for one (a deterministic
  // pattern the AR model predicts almost exactly); empty otherwise. Reported as a warning.
  std::string u_mean_note;
  // Stationarity check (n >= kBatchMeansMinN): non-overlapping batch means of b = 10
  // batches (Schmeiser, Oper. Res. 30 (1982) 556), u_batch^2 = s^2(batch means) / b with
  // b - 1 dof. A drift or random walk inflates it (a trend's spread stays in the batch
  // means however many samples a batch holds) while the AR fit absorbs it as noise. When
  // u_batch > 2 u_mean (by chance with probability < 1e-4 for stationary data: chi^2 with 9
  // dof beyond 36), u_mean takes u_batch, u_mean_dof = b - 1, u_mean_method
  // "batch_means" and drift_detected is set; the session report warns. Not made when the AR
  // innovations are below 1e-6 of the variance (a deterministic pattern, no noise).
  double u_mean_batch = 0.0;  // 0 when not computed.
  // The AR spectral u before the check; 0 when not computed (a deterministic pattern stops
  // the fit before it, spectral_mean.hpp).
  double u_mean_ar = 0.0;
  bool drift_detected = false;
};

inline constexpr size_t kBatchMeansMinN = 100;
inline constexpr int kStationarityBatches = 10;

// Values of TypeAResult::u_mean_method (the session report adds "allan_noise_model" and
// "batch_means" when drift makes them larger; docs/type-a.md).
inline constexpr const char* kUMeanArSpectral = "ar_spectral";
inline constexpr const char* kUMeanClassical = "classical";
inline constexpr const char* kUMeanBatchMeans = "batch_means";
// Willink's rules for digitized readings (above).
inline constexpr const char* kUMeanDigitized = "digitized_willink";

// u of the mean of n >= 2 readings quantized to `step` with spread x_max - x_min, by
// Willink's rules: sqrt(c/12) step for no spread, sqrt(max(u_0^2, (x_mid - mean)^2 / 3))
// for a spread of one step (u_0 the u from the spread alone), u_0 otherwise.
double DigitizedUMean(size_t n, double step, double x_min, double x_max, double mean, double u_0);

// Evaluates n observations. Requires n >= 2 (one observation has no Type A evaluation)
// and finite values; returns an Error otherwise.
Result<TypeAResult> EvaluateTypeA(const double* values, size_t n, const TypeAOptions& options = {});

// The same evaluation of a record read in chunks (the streaming mode, issue #38): memory
// independent of n, and the same numbers as EvaluateTypeA to the last bit, with two
// exceptions said in the result rather than guessed: a strongly correlated series of more
// than 2^21 values whose AR fit needs the lattice (shorter ones are read in for it; u_mean is
// then the classical s(mean), u_mean_note says why), and an
// autocorrelation whose cut-off lies beyond 2^19 lags (autocorr_computed false, autocorr_note
// says why).
Result<TypeAResult> EvaluateTypeAChunked(const ChunkReader& read, size_t n,
                                         const TypeAOptions& options = {});

// Sample autocorrelation rho_0..rho_max_lag of x (rho_0 = 1), normalised by
// sum (x - mean)^2, via FFT. Exposed for tests and for the noise module.
void Autocorrelation(const double* x, size_t n, size_t max_lag, double* rho);

}  // namespace metro
