#include "metro/noise/allan.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <thread>
#include <utility>

#include "metro/noise/edf.hpp"
#include "metro/noise/noise_id.hpp"

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

// Runs fn(lo, hi, thread_index) on `threads` contiguous slices of [0, n).
template <typename Fn>
void ParallelSlices(int threads, int64_t n, Fn fn) {
  if (threads <= 1 || n < 2) {
    fn(int64_t{0}, n, 0);
    return;
  }
  std::vector<std::thread> pool;
  pool.reserve(static_cast<size_t>(threads));
  for (int t = 0; t < threads; ++t) {
    const int64_t lo = n * t / threads;
    const int64_t hi = n * (t + 1) / threads;
    pool.emplace_back([=, &fn] { fn(lo, hi, t); });
  }
  for (std::thread& th : pool) th.join();
}

// sum_{i=i0}^{i1-1} (x[i+2m] - 2 x[i+m] + x[i])^2 with four independent accumulators.
double SumSecondDifferences(const double* x, int64_t m, int64_t i0, int64_t i1) {
  const double* a = x + i0;
  const double* b = x + i0 + m;
  const double* c = x + i0 + 2 * m;
  const int64_t n = i1 - i0;
  double s0 = 0.0, s1 = 0.0, s2 = 0.0, s3 = 0.0;
  int64_t i = 0;
  for (; i + 4 <= n; i += 4) {
    const double d0 = (c[i] - 2.0 * b[i]) + a[i];
    const double d1 = (c[i + 1] - 2.0 * b[i + 1]) + a[i + 1];
    const double d2 = (c[i + 2] - 2.0 * b[i + 2]) + a[i + 2];
    const double d3 = (c[i + 3] - 2.0 * b[i + 3]) + a[i + 3];
    s0 += d0 * d0;
    s1 += d1 * d1;
    s2 += d2 * d2;
    s3 += d3 * d3;
  }
  for (; i < n; ++i) {
    const double d = (c[i] - 2.0 * b[i]) + a[i];
    s0 += d * d;
  }
  return (s0 + s1) + (s2 + s3);
}

// sum_{i=i0}^{i1-1} (x[i+3m] - 3 x[i+2m] + 3 x[i+m] - x[i])^2.
double SumThirdDifferences(const double* x, int64_t m, int64_t i0, int64_t i1) {
  const double* a = x + i0;
  const double* b = x + i0 + m;
  const double* c = x + i0 + 2 * m;
  const double* e = x + i0 + 3 * m;
  const int64_t n = i1 - i0;
  double s0 = 0.0, s1 = 0.0, s2 = 0.0, s3 = 0.0;
  int64_t i = 0;
  for (; i + 4 <= n; i += 4) {
    const double d0 = (e[i] - a[i]) - 3.0 * (c[i] - b[i]);
    const double d1 = (e[i + 1] - a[i + 1]) - 3.0 * (c[i + 1] - b[i + 1]);
    const double d2 = (e[i + 2] - a[i + 2]) - 3.0 * (c[i + 2] - b[i + 2]);
    const double d3 = (e[i + 3] - a[i + 3]) - 3.0 * (c[i + 3] - b[i + 3]);
    s0 += d0 * d0;
    s1 += d1 * d1;
    s2 += d2 * d2;
    s3 += d3 * d3;
  }
  for (; i < n; ++i) {
    const double d = (e[i] - a[i]) - 3.0 * (c[i] - b[i]);
    s0 += d * d;
  }
  return (s0 + s1) + (s2 + s3);
}

// Overlapping Allan / Hadamard sums for all m in one blocked pass per thread.
std::vector<double> OverlappingSums(const std::vector<double>& x, const std::vector<int64_t>& m,
                                    AllanEstimator estimator, int threads) {
  const int64_t n_phase = static_cast<int64_t>(x.size());
  const bool hadamard = estimator == AllanEstimator::kOhdev;
  std::vector<int64_t> limit(m.size());
  int64_t max_limit = 0;
  for (size_t k = 0; k < m.size(); ++k) {
    limit[k] = AllanTermCount(estimator, n_phase, m[k]);
    max_limit = std::max(max_limit, limit[k]);
  }
  const int n_threads = ResolveThreads(threads, max_limit);
  std::vector<std::vector<double>> partial(static_cast<size_t>(n_threads),
                                           std::vector<double>(m.size(), 0.0));
  ParallelSlices(n_threads, max_limit, [&](int64_t lo, int64_t hi, int t) {
    std::vector<double>& sums = partial[static_cast<size_t>(t)];
    for (int64_t b = lo; b < hi; b += kBlock) {
      const int64_t block_end = std::min(b + kBlock, hi);
      for (size_t k = 0; k < m.size(); ++k) {
        const int64_t end = std::min(block_end, limit[k]);
        if (end <= b) continue;
        sums[k] += hadamard ? SumThirdDifferences(x.data(), m[k], b, end)
                            : SumSecondDifferences(x.data(), m[k], b, end);
      }
    }
  });
  std::vector<double> sums(m.size(), 0.0);
  for (const std::vector<double>& p : partial) {
    for (size_t k = 0; k < m.size(); ++k) sums[k] += p[k];
  }
  return sums;
}

// Modified Allan sum for one m: sum_{j=0}^{N-3m} (sum_{i=j}^{j+m-1} d_i)^2, d_i the second
// difference at lag m. The inner sum slides in O(1) per j and is recomputed from scratch
// every kResync steps so that rounding cannot accumulate.
double ModifiedSum(const std::vector<double>& x, int64_t m, int threads) {
  const int64_t n_phase = static_cast<int64_t>(x.size());
  const int64_t n_terms = AllanTermCount(AllanEstimator::kMdev, n_phase, m);
  const double* p = x.data();
  auto d = [p, m](int64_t i) { return (p[i + 2 * m] - 2.0 * p[i + m]) + p[i]; };
  const int64_t resync = std::max<int64_t>(int64_t{1} << 16, 16 * m);
  const int n_threads = ResolveThreads(threads, n_terms);
  std::vector<double> partial(static_cast<size_t>(n_threads), 0.0);
  ParallelSlices(n_threads, n_terms, [&](int64_t lo, int64_t hi, int t) {
    double total = 0.0;
    for (int64_t start = lo; start < hi; start += resync) {
      const int64_t stop = std::min(start + resync, hi);
      double inner = 0.0;
      for (int64_t i = start; i < start + m; ++i) inner += d(i);
      total += inner * inner;
      for (int64_t j = start + 1; j < stop; ++j) {
        inner += d(j + m - 1) - d(j - 1);
        total += inner * inner;
      }
    }
    partial[static_cast<size_t>(t)] = total;
  });
  double sum = 0.0;
  for (double s : partial) sum += s;
  return sum;
}

// Non-overlapping Allan / Hadamard sum for one m (stride m): O(N / m).
double NonOverlappingSum(const std::vector<double>& x, int64_t m, bool hadamard) {
  const int64_t n_phase = static_cast<int64_t>(x.size());
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
  if (threads < 0) return fail("threads must be >= 0 (0 = all hardware threads)");
  return true;
}

std::vector<double> PhaseFromRate(const std::vector<double>& rate, double tau0_s,
                                  double* mean_out) {
  METRO_CHECK(tau0_s > 0.0);
  // Mean by four interleaved sums, then a Neumaier-compensated running sum: exact to a few
  // ulp of |x| without the cost of long double.
  double s4[4] = {0.0, 0.0, 0.0, 0.0};
  const size_t n = rate.size();
  size_t k = 0;
  for (; k + 4 <= n; k += 4) {
    for (size_t j = 0; j < 4; ++j) s4[j] += rate[k + j];
  }
  for (; k < n; ++k) s4[0] += rate[k];
  const double mean = n == 0 ? 0.0 : ((s4[0] + s4[1]) + (s4[2] + s4[3])) / static_cast<double>(n);
  std::vector<double> phase(n + 1);
  double x = 0.0, carry = 0.0;
  phase[0] = 0.0;
  for (k = 0; k < n; ++k) {
    const double step = (rate[k] - mean) * tau0_s;
    const double t = x + step;
    carry += std::fabs(x) >= std::fabs(step) ? (x - t) + step : (step - t) + x;
    x = t;
    phase[k + 1] = x + carry;
  }
  if (mean_out != nullptr) *mean_out = mean;
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
  METRO_CHECK(tau0_s > 0.0);
  const int64_t n_phase = static_cast<int64_t>(phase.size());
  for (int64_t mk : m) METRO_CHECK(AllanTermCount(estimator, n_phase, mk) >= 1);
  std::vector<double> sums(m.size(), 0.0);
  switch (estimator) {
    case AllanEstimator::kOadev:
    case AllanEstimator::kOhdev:
      sums = OverlappingSums(phase, m, estimator, threads);
      break;
    case AllanEstimator::kMdev:
      for (size_t k = 0; k < m.size(); ++k) sums[k] = ModifiedSum(phase, m[k], threads);
      break;
    case AllanEstimator::kAdev:
    case AllanEstimator::kHdev:
      for (size_t k = 0; k < m.size(); ++k) {
        sums[k] = NonOverlappingSum(phase, m[k], estimator == AllanEstimator::kHdev);
      }
      break;
  }
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

Result<AllanCurve> ComputeAllan(const std::vector<double>& rate, double tau0_s,
                                const AllanOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) return MakeError("Allan options: " + why);
  if (!(std::isfinite(tau0_s) && tau0_s > 0.0)) {
    return MakeError(fmt::format("sample period tau0 = {} s is not a positive number", tau0_s));
  }
  for (size_t i = 0; i < rate.size(); ++i) {
    if (!std::isfinite(rate[i])) {
      return MakeError(fmt::format("rate sample {} (0-based) is not finite ({})", i, rate[i]));
    }
  }
  const int64_t n_rate = static_cast<int64_t>(rate.size());
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
  const std::vector<double> phase = PhaseFromRate(rate, tau0_s, &curve.rate_mean);
  const std::vector<double> variance =
      AllanVariances(phase, tau0_s, m, options.estimator, options.threads);

  const EstimatorShape shape = ShapeOf(options.estimator);
  const size_t n = m.size();
  curve.m = m;
  curve.tau_s.resize(n);
  curve.dev.resize(n);
  curve.ci_low.resize(n);
  curve.ci_high.resize(n);
  curve.edf.resize(n);
  curve.n_terms.resize(n);
  curve.alpha.resize(n);
  curve.alpha_source.resize(n);
  bool have_identified = false;
  int last_alpha = 0;
  for (size_t k = 0; k < n; ++k) {
    curve.tau_s[k] = static_cast<double>(m[k]) * tau0_s;
    curve.dev[k] = std::sqrt(std::max(variance[k], 0.0));
    curve.n_terms[k] = AllanTermCount(options.estimator, n_phase, m[k]);
    if (options.noise_id == NoiseIdMethod::kFixed) {
      curve.alpha[k] = options.fixed_alpha;
      curve.alpha_source[k] = AlphaSource::kFixed;
    } else {
      Result<NoiseIdentification> id =
          (n_phase - 1) / m[k] + 1 >= options.min_points_noise_id
              ? IdentifyNoiseLag1(phase, m[k], shape.d, options.min_points_noise_id)
              : Result<NoiseIdentification>(MakeError("too few points"));
      if (id.ok()) {
        curve.alpha[k] = id.value().alpha;
        curve.alpha_source[k] = AlphaSource::kLag1Acf;
        last_alpha = id.value().alpha;
        have_identified = true;
      } else if (have_identified) {
        curve.alpha[k] = last_alpha;
        curve.alpha_source[k] = AlphaSource::kCarried;
      } else {
        curve.alpha[k] = 0;
        curve.alpha_source[k] = AlphaSource::kDefault;
      }
    }
    const Result<double> edf = GreenhallRileyEdf(curve.alpha[k], shape.d, m[k], n_phase,
                                                 shape.overlapping, shape.modified);
    const double nan = std::nan("");
    curve.edf[k] = edf.ok() ? edf.value() : nan;
    curve.ci_low[k] = nan;
    curve.ci_high[k] = nan;
    if (edf.ok()) {
      const Result<DeviationInterval> ci =
          ChiSquaredInterval(curve.dev[k], edf.value(), options.confidence);
      if (ci.ok()) {
        curve.ci_low[k] = ci.value().low;
        curve.ci_high[k] = ci.value().high;
      }
    }
  }
  return curve;
}

}  // namespace metro
