// ComputeAllanWithGaps: the Allan family on a regular grid with missing samples, terms that
// read a missing sample left out (NIST SP 1065 5.15; allan.hpp).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "metro/noise/allan.hpp"
#include "metro/noise/noise_id.hpp"
#include "noise/allan_internal.hpp"

namespace metro {
namespace {

// Where the terms of one estimator read the rate samples: the term at phase index i reads
// y[i, i + span(m)), and the terms run over i = 0, stride, 2 stride, ... below count.
struct TermLayout {
  int64_t span = 0;
  int64_t stride = 1;
  int64_t count = 0;  // Terms of the gap-free record (AllanTermCount).
};

TermLayout LayoutOf(AllanEstimator estimator, int64_t n_phase, int64_t m) {
  TermLayout t;
  t.count = AllanTermCount(estimator, n_phase, m);
  switch (estimator) {
    case AllanEstimator::kOadev:
      t.span = 2 * m;
      break;
    case AllanEstimator::kAdev:
      t.span = 2 * m;
      t.stride = m;
      break;
    case AllanEstimator::kOhdev:
      t.span = 3 * m;
      break;
    case AllanEstimator::kHdev:
      t.span = 3 * m;
      t.stride = m;
      break;
    case AllanEstimator::kMdev:
      t.span = 3 * m - 1;
      break;
  }
  return t;
}

// Phase points of a gap-free record with n_valid terms (the EDF's N, allan.hpp).
int64_t EquivalentPhasePoints(AllanEstimator estimator, int64_t n_valid, int64_t m) {
  switch (estimator) {
    case AllanEstimator::kOadev:
      return n_valid + 2 * m;
    case AllanEstimator::kOhdev:
      return n_valid + 3 * m;
    case AllanEstimator::kMdev:
      return n_valid + 3 * m - 1;
    case AllanEstimator::kAdev:
      return (n_valid + 1) * m + 1;
    case AllanEstimator::kHdev:
      return (n_valid + 2) * m + 1;
  }
  return 0;
}

// Normalisation of the sums (NIST SP 1065 5.2.2-5.2.9), per term.
double Norm(AllanEstimator estimator, int64_t m, double tau0_s) {
  const double md = static_cast<double>(m);
  const double tau = md * tau0_s;
  switch (estimator) {
    case AllanEstimator::kOadev:
    case AllanEstimator::kAdev:
      return 2.0 * tau * tau;
    case AllanEstimator::kMdev:
      return 2.0 * md * md * tau * tau;
    case AllanEstimator::kOhdev:
    case AllanEstimator::kHdev:
      return 6.0 * tau * tau;
  }
  return 1.0;
}

struct GapSum {
  double sum = 0.0;
  int64_t valid = 0;
  // Lengths of the runs of consecutive valid terms (in term index), in order: terms of
  // different runs read disjoint sample sets, so each run is a gap-free record of its own.
  std::vector<int64_t> runs;
};

// Appends the validity of the next term to the runs.
void CountRun(bool valid, bool* in_run, GapSum* out) {
  if (!valid) {
    *in_run = false;
    return;
  }
  if (*in_run) {
    ++out->runs.back();
  } else {
    out->runs.push_back(1);
    *in_run = true;
  }
}

// The sum over the valid terms at m. `missing` is the prefix count of missing samples
// (missing[k] = missing samples among y[0, k)), so y[a, b) is complete when
// missing[b] == missing[a].
GapSum SumValidTerms(const std::vector<double>& x, const std::vector<int64_t>& missing,
                     AllanEstimator estimator, int64_t m) {
  const int64_t n_phase = static_cast<int64_t>(x.size());
  const TermLayout layout = LayoutOf(estimator, n_phase, m);
  auto complete = [&](int64_t i) { return missing[i + layout.span] == missing[i]; };
  auto second = [&](int64_t i) { return (x[i + 2 * m] - 2.0 * x[i + m]) + x[i]; };
  GapSum out;
  bool in_run = false;
  if (estimator == AllanEstimator::kMdev) {
    // sum_j (sum_{i=j}^{j+m-1} d_i)^2 over complete j; the inner sum slides, recomputed every
    // `resync` steps so rounding cannot accumulate (as ModifiedSum in allan.cpp).
    const int64_t resync = std::max<int64_t>(int64_t{1} << 16, 16 * m);
    for (int64_t start = 0; start < layout.count; start += resync) {
      const int64_t stop = std::min(start + resync, layout.count);
      double inner = 0.0;
      for (int64_t i = start; i < start + m; ++i) inner += second(i);
      for (int64_t j = start; j < stop; ++j) {
        if (j > start) inner += second(j + m - 1) - second(j - 1);
        const bool valid = complete(j);
        CountRun(valid, &in_run, &out);
        if (valid) {
          out.sum += inner * inner;
          ++out.valid;
        }
      }
    }
    return out;
  }
  const bool hadamard = estimator == AllanEstimator::kOhdev || estimator == AllanEstimator::kHdev;
  for (int64_t k = 0; k < layout.count; ++k) {
    const int64_t i = k * layout.stride;
    const bool valid = complete(i);
    CountRun(valid, &in_run, &out);
    if (!valid) continue;
    const double v = hadamard ? (x[i + 3 * m] - x[i]) - 3.0 * (x[i + 2 * m] - x[i + m]) : second(i);
    out.sum += v * v;
    ++out.valid;
  }
  return out;
}

}  // namespace

Result<AllanCurve> ComputeAllanWithGaps(const std::vector<double>& rate,
                                        const std::vector<uint8_t>& present, double tau0_s,
                                        const AllanOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) return MakeError("Allan options: " + why);
  if (!(std::isfinite(tau0_s) && tau0_s > 0.0)) {
    return MakeError(fmt::format("sample period tau0 = {} s is not a positive number", tau0_s));
  }
  if (rate.size() != present.size()) {
    return MakeError(
        fmt::format("{} rate samples but {} presence flags", rate.size(), present.size()));
  }
  const int64_t n_rate = static_cast<int64_t>(rate.size());
  const int64_t n_phase = n_rate + 1;
  // Mean of the present samples (compensated), the prefix count of missing ones.
  std::vector<int64_t> missing(static_cast<size_t>(n_phase), 0);
  double total = 0.0, carry = 0.0;
  int64_t n_present = 0;
  for (int64_t k = 0; k < n_rate; ++k) {
    const size_t ks = static_cast<size_t>(k);
    missing[ks + 1] = missing[ks] + (present[ks] ? 0 : 1);
    if (!present[ks]) continue;
    if (!std::isfinite(rate[ks])) {
      return MakeError(fmt::format("rate sample {} (0-based) is not finite ({})", k, rate[ks]));
    }
    const double t = total + rate[ks];
    carry +=
        std::fabs(total) >= std::fabs(rate[ks]) ? (total - t) + rate[ks] : (rate[ks] - t) + total;
    total = t;
    ++n_present;
  }
  if (n_present < 2) {
    return MakeError(
        fmt::format("{} of {} samples are present: at least 2 are needed", n_present, n_rate));
  }
  const double mean = (total + carry) / static_cast<double>(n_present);
  // Phase x_{k+1} = x_k + (y_k - mean) tau0 over present samples; a missing sample adds
  // nothing (no term that reads it is used, so its value never matters).
  std::vector<double> x(static_cast<size_t>(n_phase), 0.0);
  double xs = 0.0, xc = 0.0;
  for (int64_t k = 0; k < n_rate; ++k) {
    const size_t ks = static_cast<size_t>(k);
    if (present[ks]) {
      const double v = (rate[ks] - mean) * tau0_s;
      const double t = xs + v;
      xc += std::fabs(xs) >= std::fabs(v) ? (xs - t) + v : (v - t) + xs;
      xs = t;
    }
    x[ks + 1] = xs + xc;
  }

  std::vector<int64_t> m;
  if (!options.m_list.empty()) {
    m = options.m_list;
    std::sort(m.begin(), m.end());
    m.erase(std::unique(m.begin(), m.end()), m.end());
  } else {
    Result<std::vector<int64_t>> factors =
        AveragingFactors(options.estimator, options.taus, n_rate, options.max_m);
    if (!factors.ok()) return factors.error();
    m = std::move(factors).value();
  }
  std::vector<GapSum> sums(m.size());
  internal::RunAllanTasks(options.threads, static_cast<int64_t>(m.size()), [&](int64_t k) {
    const size_t ks = static_cast<size_t>(k);
    if (AllanTermCount(options.estimator, n_phase, m[ks]) >= 1) {
      sums[ks] = SumValidTerms(x, missing, options.estimator, m[ks]);
    }
  });

  // The longest gap-free stretch of samples [run_begin, run_begin + run_length), for the
  // noise identification.
  int64_t run_begin = 0, run_length = 0;
  for (int64_t k = 0, begin = 0; k <= n_rate; ++k) {
    if (k == n_rate || !present[static_cast<size_t>(k)]) {
      if (k - begin > run_length) {
        run_begin = begin;
        run_length = k - begin;
      }
      begin = k + 1;
    }
  }
  const int64_t run_phase = run_length + 1;
  const int d_max = ShapeOf(options.estimator).d;

  AllanCurve curve;
  curve.estimator = options.estimator;
  curve.tau0_s = tau0_s;
  curve.n_rate_samples = n_rate;
  curve.n_missing_samples = missing.back();
  curve.confidence = options.confidence;
  curve.rate_mean = mean;
  std::vector<char> identified;
  std::vector<int> identified_alpha;
  std::vector<internal::EdfRecords> records;
  for (size_t k = 0; k < m.size(); ++k) {
    if (sums[k].valid < 1) continue;  // Every term reads a gap: no estimate at this tau.
    curve.m.push_back(m[k]);
    curve.tau_s.push_back(static_cast<double>(m[k]) * tau0_s);
    const double variance =
        sums[k].sum / (Norm(options.estimator, m[k], tau0_s) * static_cast<double>(sums[k].valid));
    curve.dev.push_back(std::sqrt(std::max(variance, 0.0)));
    curve.n_terms.push_back(sums[k].valid);
    curve.n_terms_gap_free.push_back(AllanTermCount(options.estimator, n_phase, m[k]));
    internal::EdfRecords record;
    for (int64_t run : sums[k].runs) {
      record.run_phase_points.push_back(EquivalentPhasePoints(options.estimator, run, m[k]));
    }
    record.whole_phase_points = n_phase;
    records.push_back(std::move(record));
    bool ok = false;
    int alpha = 0;
    if (options.noise_id != NoiseIdMethod::kFixed &&
        (run_phase - 1) / m[k] + 1 >= options.min_points_noise_id) {
      const Result<NoiseIdentification> id =
          IdentifyNoiseLag1(x.data() + run_begin, run_phase, m[k], d_max,
                            options.min_points_noise_id, options.max_points_noise_id);
      ok = id.ok();
      if (ok) alpha = id.value().alpha;
    }
    identified.push_back(ok ? 1 : 0);
    identified_alpha.push_back(alpha);
  }
  if (curve.m.empty()) {
    return MakeError(
        fmt::format("every {} term at every tau reads a missing sample ({} of {} samples missing)",
                    AllanEstimatorName(options.estimator), curve.n_missing_samples, n_rate));
  }
  internal::FillAlphaAndIntervals(identified, identified_alpha, records, options, &curve);
  return curve;
}

}  // namespace metro
