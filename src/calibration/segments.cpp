// DetectSegments runs these stages, in this order (the method: segments.hpp):
//
//   signals     Signals, MeasureNoise        checked input; dt, gaps, windowed variances,
//                                            noise floors
//   poses       ChoosePoses, PosesFor        still periods grouped into poses at the
//                                            automatic threshold factor
//   steady      SplitSteady, SteadyNote      poses the gyroscope says turn (bias line)
//   segments    StaticAndRotationSegments,   static, rotation and table segments
//               TableSegments
//   short       CountShortPoses              still periods too short for a pose, counted
//
// Then the segments are ordered by their first sample and counted.
#include "metro/calibration/segments.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "metro/core/check.hpp"

namespace metro {

const char* SegmentKindName(SegmentKind kind) {
  switch (kind) {
    case SegmentKind::kStatic:
      return "static";
    case SegmentKind::kTable:
      return "table";
    case SegmentKind::kRotation:
      return "rotation";
    case SegmentKind::kSteady:
      return "steady_rotation";
  }
  return "static";
}

bool SegmentationOptions::IsValid(std::string* why) const {
  auto fail = [why](const char* message) {
    if (why != nullptr) *why = message;
    return false;
  };
  if (!(window_s > 0)) return fail("window_s must be > 0");
  if (!(min_static_s > 0)) return fail("min_static_s must be > 0");
  if (threshold_factors.empty()) return fail("threshold_factors must not be empty");
  for (double c : threshold_factors) {
    if (!(c > 1)) return fail("every threshold factor must be > 1");
  }
  if (!(table_settle_s >= 0)) return fail("table_settle_s must be >= 0");
  if (!(min_table_s > 0)) return fail("min_table_s must be > 0");
  if (!(max_gap_factor > 1)) return fail("max_gap_factor must be > 1");
  return true;
}

namespace {

// Sum over the axes of the sample variance in the window [k - h, k + h] (clipped).
std::vector<double> WindowVariance(const std::vector<Eigen::Vector3d>& x, size_t h) {
  const size_t n = x.size();
  const Eigen::Vector3d x0 = x[n / 2];  // Centring keeps the prefix sums well conditioned.
  std::vector<Eigen::Vector3d> s1(n + 1, Eigen::Vector3d::Zero());
  std::vector<Eigen::Vector3d> s2(n + 1, Eigen::Vector3d::Zero());
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d d = x[i] - x0;
    s1[i + 1] = s1[i] + d;
    s2[i + 1] = s2[i] + d.cwiseProduct(d);
  }
  std::vector<double> v(n, 0.0);
  for (size_t k = 0; k < n; ++k) {
    const size_t lo = k >= h ? k - h : 0;
    const size_t hi = std::min(n, k + h + 1);
    const double m = static_cast<double>(hi - lo);
    if (m < 2) continue;
    const Eigen::Vector3d sum = s1[hi] - s1[lo];
    const Eigen::Vector3d sum2 = s2[hi] - s2[lo];
    const Eigen::Vector3d var = (sum2 - sum.cwiseProduct(sum) / m) / (m - 1);
    v[k] = std::max(0.0, var.sum());
  }
  return v;
}

double Percentile(std::vector<double> v, double p) {
  METRO_CHECK(!v.empty());
  const size_t i = std::min(v.size() - 1, static_cast<size_t>(p * static_cast<double>(v.size())));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(i), v.end());
  return v[i];
}

struct Run {
  size_t begin, end;
};

template <typename Mask>
Eigen::Vector3d MeanOf(const std::vector<Eigen::Vector3d>& x, const Run& r, const Mask& skip) {
  Eigen::Vector3d s = Eigen::Vector3d::Zero();
  size_t n = 0;
  for (size_t i = r.begin; i < r.end; ++i) {
    if (skip(i)) continue;
    s += x[i];
    ++n;
  }
  return n > 0 ? Eigen::Vector3d(s / static_cast<double>(n)) : s;
}

Eigen::Vector3d MeanOfRuns(const std::vector<Eigen::Vector3d>& x, const std::vector<Run>& runs) {
  Eigen::Vector3d s = Eigen::Vector3d::Zero();
  size_t n = 0;
  for (const Run& r : runs) {
    for (size_t i = r.begin; i < r.end; ++i) s += x[i];
    n += r.end - r.begin;
  }
  return n > 0 ? Eigen::Vector3d(s / static_cast<double>(n)) : s;
}

double Median(std::vector<double> v) {
  METRO_CHECK(!v.empty());
  const size_t mid = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(mid), v.end());
  double m = v[mid];
  if (v.size() % 2 == 0) {
    m = 0.5 * (m + *std::max_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(mid)));
  }
  return m;
}

// Maximal runs of samples for which still(k) holds, not crossing a time gap, at least min_n
// samples long.
template <typename Still>
std::vector<Run> StillRuns(size_t n, const Still& still,
                           const std::vector<unsigned char>& gap_before, size_t min_n) {
  std::vector<Run> runs;
  size_t k = 0;
  while (k < n) {
    if (!still(k)) {
      ++k;
      continue;
    }
    size_t e = k + 1;
    while (e < n && still(e) && !gap_before[e]) ++e;
    if (e - k >= min_n) runs.push_back({k, e});
    k = e;
  }
  return runs;
}

// The gyroscope bias the still periods see, bias(T) = b0 + b1 (T - t_ref_c) per axis, and the
// standard uncertainty of its value at T (segments.hpp, "Steady rotations").
struct BiasLine {
  bool temperature = false;  // False: b1 = 0, b0 the per-axis median.
  Eigen::Vector3d b0 = Eigen::Vector3d::Zero();
  Eigen::Vector3d b1 = Eigen::Vector3d::Zero();
  double t_ref_c = 0;
  Eigen::Vector3d scatter = Eigen::Vector3d::Zero();  // s = 1.4826 median |residual|, per axis.
  double count = 0;
  double t_mean_c = 0;
  double t_sxx = 0;  // sum (T_i - mean T)^2

  Eigen::Vector3d At(double temp_c) const {
    return temperature ? Eigen::Vector3d(b0 + b1 * (temp_c - t_ref_c)) : b0;
  }
  // |m - bias(T)|: the rate of a still period of mean m at temperature T (norm, input units).
  double Deviation(const Eigen::Vector3d& m, double temp_c) const {
    return (m - At(temp_c)).norm();
  }
  // u(bias(T)) as a norm over the axes: the least-squares form with the median's efficiency
  // factor sqrt(pi/2) = 1.2533.
  double U(double temp_c) const {
    double f = 1.0 / count;
    if (temperature) f += (temp_c - t_mean_c) * (temp_c - t_mean_c) / t_sxx;
    return 1.2533 * scatter.norm() * std::sqrt(f);
  }
};

// Fits the line to the still periods' mean rates and mean temperatures (temps_c empty or with
// a NaN: no temperature) by Siegel's repeated median; without two distinct temperatures b1 = 0.
BiasLine FitBiasLine(const std::vector<Eigen::Vector3d>& means,
                     const std::vector<double>& temps_c) {
  METRO_CHECK(!means.empty());
  BiasLine line;
  const size_t p = means.size();
  line.count = static_cast<double>(p);
  bool temperature = temps_c.size() == p && std::all_of(temps_c.begin(), temps_c.end(),
                                                        [](double t) { return std::isfinite(t); });
  if (temperature) {
    line.t_ref_c = Median(temps_c);
    for (double t : temps_c) line.t_mean_c += t / line.count;
    for (double t : temps_c) line.t_sxx += (t - line.t_mean_c) * (t - line.t_mean_c);
    temperature = line.t_sxx > 0;
  }
  line.temperature = temperature;
  for (int a = 0; a < 3; ++a) {
    if (temperature) {
      // Siegel (1982): b1 = med_i med_{j: T_j != T_i} (m_j - m_i) / (T_j - T_i).
      std::vector<double> outer;
      for (size_t i = 0; i < p; ++i) {
        std::vector<double> slopes;
        for (size_t j = 0; j < p; ++j) {
          if (temps_c[j] == temps_c[i]) continue;
          slopes.push_back((means[j][a] - means[i][a]) / (temps_c[j] - temps_c[i]));
        }
        if (!slopes.empty()) outer.push_back(Median(std::move(slopes)));
      }
      line.b1[a] = Median(std::move(outer));
    }
    std::vector<double> level;
    for (size_t i = 0; i < p; ++i) {
      level.push_back(means[i][a] - (temperature ? line.b1[a] * (temps_c[i] - line.t_ref_c) : 0));
    }
    line.b0[a] = Median(level);
    std::vector<double> residual;
    for (double v : level) residual.push_back(std::abs(v - line.b0[a]));
    line.scatter[a] = 1.4826 * Median(std::move(residual));
  }
  return line;
}

// ---- signals ------------------------------------------------------------------------------

const std::vector<double>& CheckedTimes(const SegmentationInput& input) {
  METRO_CHECK(input.t_s != nullptr && input.accel != nullptr);
  return *input.t_s;
}

// The input, checked, and what every stage reads from it (set by MeasureNoise).
struct Signals {
  explicit Signals(const SegmentationInput& in)
      : input(in), t(CheckedTimes(in)), accel(*in.accel), n(t.size()) {
    METRO_CHECK(n > 0 && accel.size() == n);
    has_gyro = input.gyro != nullptr && !input.gyro->empty();
    if (has_gyro) METRO_CHECK(input.gyro->size() == n);
    has_table = input.table_rate_dps != nullptr && !input.table_rate_dps->empty();
    if (has_table) METRO_CHECK(input.table_rate_dps->size() == n);
    has_sat = input.saturated != nullptr && !input.saturated->empty();
    if (has_sat) METRO_CHECK(input.saturated->size() == n);
    has_temp = input.temp_c != nullptr && !input.temp_c->empty();
    if (has_temp) METRO_CHECK(input.temp_c->size() == n);
  }

  const SegmentationInput& input;
  const std::vector<double>& t;
  const std::vector<Eigen::Vector3d>& accel;
  const size_t n;
  bool has_gyro = false, has_table = false, has_sat = false, has_temp = false;

  double dt_median = 0;
  std::vector<unsigned char> gap_before;  // gap_before[k]: a time gap between k-1 and k.
  double window_s = 0;                    // The variance window, shrunk to min_static_s.
  size_t h = 0;                           // Its half-width in samples.
  std::vector<double> va, vg;             // Window variances (vg empty without gyroscope).
  size_t min_static_n = 0;

  bool TableTurning(size_t k) const {
    if (!has_table) return false;
    const double r = (*input.table_rate_dps)[k];
    return std::isfinite(r) && r != 0.0;
  }
  bool Saturated(size_t k) const { return has_sat && (*input.saturated)[k] != 0; }
  Eigen::Vector3d MeanAccel(const Run& r) const {
    return MeanOf(accel, r, [this](size_t k) { return Saturated(k); });
  }
  Eigen::Vector3d MeanGyro(const Run& r) const {
    return MeanOf(*input.gyro, r, [this](size_t k) { return Saturated(k); });
  }
  // Mean of the finite temperatures of the runs (NaN when none is, or without temp_c).
  double MeanTempC(const std::vector<Run>& runs) const {
    double sum = 0;
    size_t count = 0;
    for (const Run& r : runs) {
      for (size_t i = r.begin; i < r.end && has_temp; ++i) {
        const double v = (*input.temp_c)[i];
        if (!std::isfinite(v)) continue;
        sum += v;
        ++count;
      }
    }
    return count > 0 ? sum / static_cast<double>(count) : std::nan("");
  }
  Segment Make(SegmentKind kind, size_t b, size_t e) const {
    Segment s;
    s.kind = kind;
    s.piece = input.piece;
    s.begin = b;
    s.end = e;
    s.start_s = t[b];
    s.end_s = t[e - 1];
    return s;
  }
};

// The sampling step, the time gaps, the window and its variances, and the noise floors
// (summary->accel_floor, gyro_floor). Needs n >= 3.
void MeasureNoise(const SegmentationOptions& options, Signals* sig, SegmentationSummary* summary) {
  const size_t n = sig->n;
  std::vector<double> dt(n - 1);
  for (size_t i = 0; i + 1 < n; ++i) dt[i] = sig->t[i + 1] - sig->t[i];
  sig->dt_median = std::max(Percentile(dt, 0.5), 1e-9);
  const double gap_s = options.max_gap_factor * sig->dt_median;
  sig->gap_before.assign(n, 0);
  for (size_t i = 1; i < n; ++i) sig->gap_before[i] = dt[i - 1] > gap_s ? 1 : 0;

  // A minimum pose shorter than the window shrinks the window with it (--min-static-s).
  sig->window_s = std::min(options.window_s, options.min_static_s);
  sig->h =
      std::max<size_t>(2, static_cast<size_t>(std::lround(0.5 * sig->window_s / sig->dt_median)));
  sig->va = WindowVariance(sig->accel, sig->h);
  summary->accel_floor = Percentile(sig->va, 0.05);
  if (sig->has_gyro) {
    sig->vg = WindowVariance(*sig->input.gyro, sig->h);
    summary->gyro_floor = Percentile(sig->vg, 0.05);
  }
  sig->min_static_n = static_cast<size_t>(std::ceil(options.min_static_s / sig->dt_median));
}

// ---- poses --------------------------------------------------------------------------------

// Still periods for factor c, grouped into poses: neighbours with the same accelerometer
// and gyroscope means and no table turn or time gap between them are one pose.
std::vector<std::vector<Run>> PosesFor(const Signals& sig, const SegmentationSummary& summary,
                                       double c) {
  const double same_accel = 3.0 * std::sqrt(summary.accel_floor);
  const double same_rate = 3.0 * std::sqrt(summary.gyro_floor);
  // A floor of exactly 0 (quantised, perfectly still data) still admits equal samples.
  const double ta = std::max(c * summary.accel_floor, 1e-300);
  const double tg = sig.has_gyro ? std::max(c * summary.gyro_floor, 1e-300) : 0.0;
  auto still = [&](size_t i) {
    if (sig.va[i] >= ta) return false;
    if (sig.has_gyro && sig.vg[i] >= tg) return false;
    return !sig.Saturated(i) && !sig.TableTurning(i);
  };
  const std::vector<Run> runs = StillRuns(sig.n, still, sig.gap_before, sig.min_static_n);
  std::vector<std::vector<Run>> poses;
  for (const Run& r : runs) {
    if (!poses.empty()) {
      const Run& last = poses.back().back();
      bool clean = !sig.gap_before[r.begin];
      for (size_t i = last.end; i < r.begin && clean; ++i) {
        if (sig.TableTurning(i) || sig.gap_before[i]) clean = false;
      }
      if (clean && (sig.MeanAccel(last) - sig.MeanAccel(r)).norm() < same_accel &&
          (!sig.has_gyro || (sig.MeanGyro(last) - sig.MeanGyro(r)).norm() < same_rate)) {
        poses.back().push_back(r);
        continue;
      }
    }
    poses.push_back({r});
  }
  return poses;
}

// Automatic threshold (summary->threshold_factor): the factors reaching the most poses, median
// of them; the poses at it.
std::vector<std::vector<Run>> ChoosePoses(const Signals& sig, const SegmentationOptions& options,
                                          SegmentationSummary* summary) {
  std::vector<std::pair<double, size_t>> counts;
  size_t best = 0;
  for (double c : options.threshold_factors) {
    const size_t count = PosesFor(sig, *summary, c).size();
    counts.push_back({c, count});
    best = std::max(best, count);
  }
  std::vector<double> best_factors;
  for (const auto& [c, count] : counts) {
    if (count == best) best_factors.push_back(c);
  }
  std::sort(best_factors.begin(), best_factors.end());
  summary->threshold_factor = best_factors[(best_factors.size() - 1) / 2];
  return PosesFor(sig, *summary, summary->threshold_factor);
}

// ---- steady rotations ---------------------------------------------------------------------

struct SteadyRotations {
  double rate_limit = 0;  // 0: no test (no gyroscope or fewer than 2 poses).
  BiasLine bias;
  std::vector<std::vector<Run>> kept;  // The poses that are not steady rotations.
  // Beyond the limit by more than 3 u of the bias there (segments.hpp).
  bool Turning(double dev, double temp_c) const { return dev > rate_limit + 3.0 * bias.U(temp_c); }
};

// The note of a steady rotation at pose temperature temp_c.
std::string SteadyNote(const Signals& sig, const SegmentationOptions& options, const Segment& s,
                       double deviation, const BiasLine& bias, double temp_c) {
  const size_t mid = (s.begin + s.end) / 2;
  const char* table_word = !sig.has_table ? " (its rate is unknown: no table_rate_dps); excluded"
                           : std::isfinite((*sig.input.table_rate_dps)[mid])
                               ? " although table_rate_dps is 0 there; excluded"
                               : " (its rate is unknown: table_rate_dps is empty there); excluded";
  return fmt::format(
      "steady rotation at {} ({} s): the accelerometer is still but the gyroscope turns{}; "
      "not a static pose{}",
      options.gyro_units_per_dps > 0 ? fmt::format("{:.3g} deg/s", s.steady_rate_dps)
                                     : fmt::format("{:.4g} input units", deviation),
      fmt::format("{:.1f}", s.end_s - s.start_s),
      bias.temperature ? fmt::format(" (against the bias at {:.1f} degC of the still periods' "
                                     "bias-temperature line)",
                                     temp_c)
                       : "",
      table_word);
}

// Steady rotations: poses whose gyroscope mean is not the bias at their temperature, as
// unused kSteady segments; the others are kept.
SteadyRotations SplitSteady(const Signals& sig, const SegmentationOptions& options,
                            const std::vector<std::vector<Run>>& poses,
                            SegmentationSummary* summary, std::vector<Segment>* segments) {
  SteadyRotations steady;
  std::vector<double> deviation, pose_temp_c;
  if (sig.has_gyro && poses.size() >= 2) {
    std::vector<Eigen::Vector3d> means;
    for (const auto& p : poses) means.push_back(MeanOfRuns(*sig.input.gyro, p));
    if (sig.has_temp) {
      for (const auto& p : poses) pose_temp_c.push_back(sig.MeanTempC(p));
    }
    steady.bias = FitBiasLine(means, pose_temp_c);
    for (size_t p = 0; p < poses.size(); ++p) {
      deviation.push_back(steady.bias.Deviation(means[p], sig.has_temp ? pose_temp_c[p] : 0.0));
    }
    steady.rate_limit =
        options.gyro_units_per_dps > 0
            ? options.max_static_rate_dps * options.gyro_units_per_dps
            : std::max(10.0 * Median(deviation), 30.0 * std::sqrt(summary->gyro_floor / 3));
    summary->gyro_bias_temperature = steady.bias.temperature;
    summary->gyro_bias = steady.bias.b0;
    summary->gyro_bias_per_c = steady.bias.b1;
    summary->gyro_bias_t_ref_c = steady.bias.t_ref_c;
  }
  for (size_t p = 0; p < poses.size(); ++p) {
    const double temp_c = pose_temp_c.empty() ? 0.0 : pose_temp_c[p];
    if (steady.rate_limit > 0 && steady.Turning(deviation[p], temp_c)) {
      Segment s = sig.Make(SegmentKind::kSteady, poses[p].front().begin, poses[p].back().end);
      s.used = false;
      s.steady_rate = deviation[p];
      s.steady_rate_dps =
          options.gyro_units_per_dps > 0 ? deviation[p] / options.gyro_units_per_dps : std::nan("");
      s.note = SteadyNote(sig, options, s, deviation[p], steady.bias, temp_c);
      segments->push_back(s);
      ++summary->steady_count;
      continue;
    }
    steady.kept.push_back(poses[p]);
  }
  return steady;
}

// ---- static, rotation and table segments --------------------------------------------------

// Static segments (one per still period) and what lies between consecutive ones.
void StaticAndRotationSegments(const Signals& sig, const std::vector<std::vector<Run>>& kept,
                               SegmentationSummary* summary, std::vector<Segment>* segments) {
  std::vector<Run> statics;
  std::vector<int> pose_of;
  for (size_t p = 0; p < kept.size(); ++p) {
    for (const Run& r : kept[p]) {
      Segment s = sig.Make(SegmentKind::kStatic, r.begin, r.end);
      s.pose = static_cast<int>(p);
      segments->push_back(s);
      statics.push_back(r);
      pose_of.push_back(static_cast<int>(p));
    }
    if (kept[p].size() > 1) ++summary->disturbed_poses;
  }
  summary->pose_count = static_cast<int>(kept.size());
  for (size_t i = 0; i + 1 < statics.size(); ++i) {
    const size_t b = statics[i].end;
    const size_t e = statics[i + 1].begin;
    if (e <= b) continue;
    Segment s = sig.Make(SegmentKind::kRotation, b, e);
    if (pose_of[i] == pose_of[i + 1]) {
      s.note = fmt::format(
          "disturbance inside pose {} ({:.2f} s: a knock, a saturated burst or a shift between "
          "two still periods of one orientation); not averaged into the pose",
          pose_of[i] + 1, sig.t[e] - sig.t[b - 1]);
    }
    for (size_t k = b; k <= e && k < sig.n; ++k) {
      if (sig.gap_before[k]) {
        s.used = false;
        s.note = "time gap inside the rotation";
        break;
      }
    }
    segments->push_back(s);
  }
}

// Table segments: constant table rates, less table_settle_s at each end.
void TableSegments(const Signals& sig, const SegmentationOptions& options,
                   std::vector<Segment>* segments) {
  if (!sig.has_table) return;
  const std::vector<double>& rate = *sig.input.table_rate_dps;
  const size_t settle_n = static_cast<size_t>(std::lround(options.table_settle_s / sig.dt_median));
  const size_t min_table_n = static_cast<size_t>(std::ceil(options.min_table_s / sig.dt_median));
  size_t k = 0;
  while (k < sig.n) {
    if (!sig.TableTurning(k)) {
      ++k;
      continue;
    }
    size_t e = k + 1;
    while (e < sig.n && rate[e] == rate[k] && !sig.gap_before[e]) ++e;
    if (e - k > 2 * settle_n && e - k - 2 * settle_n >= min_table_n) {
      Segment s = sig.Make(SegmentKind::kTable, k + settle_n, e - settle_n);
      s.table_rate_dps = rate[k];
      segments->push_back(s);
    }
    k = e;
  }
}

// ---- short poses --------------------------------------------------------------------------

// Short poses: still periods the window and min_static_s left out, found with a short
// window away from every pose and steady rotation found above (counted in the summary).
void CountShortPoses(const Signals& sig, const SteadyRotations& steady,
                     const std::vector<Segment>& segments, SegmentationSummary* summary) {
  const size_t n = sig.n;
  const double dt_median = sig.dt_median;
  const double short_window_s = std::min(0.25, sig.window_s / 4.0);
  const size_t hs =
      std::max<size_t>(1, static_cast<size_t>(std::lround(0.5 * short_window_s / dt_median)));
  const std::vector<double> vas = WindowVariance(sig.accel, hs);
  std::vector<double> vgs;
  const double fa = Percentile(vas, 0.05);
  double fg = 0;
  if (sig.has_gyro) {
    vgs = WindowVariance(*sig.input.gyro, hs);
    fg = Percentile(vgs, 0.05);
  }
  std::vector<unsigned char> taken(n, 0);
  for (const Segment& s : segments) {
    if (s.kind != SegmentKind::kStatic && s.kind != SegmentKind::kSteady) continue;
    const size_t lo = s.begin >= sig.h ? s.begin - sig.h : 0;
    for (size_t i = lo; i < std::min(n, s.end + sig.h); ++i) taken[i] = 1;
  }
  const double c = summary->threshold_factor;
  auto still = [&](size_t i) {
    if (taken[i] || vas[i] >= std::max(c * fa, 1e-300)) return false;
    if (sig.has_gyro && vgs[i] >= std::max(c * fg, 1e-300)) return false;
    return !sig.Saturated(i) && !sig.TableTurning(i);
  };
  const std::vector<Run> shorts = StillRuns(n, still, sig.gap_before, 4 * hs + 1);
  const BiasLine& bias = steady.bias;
  for (const Run& r : shorts) {
    if (r.end - r.begin >= sig.min_static_n) continue;
    if (steady.rate_limit > 0) {
      // Not a steady rotation either: the rate against the poses' bias at its temperature.
      const double temp_c = bias.temperature ? sig.MeanTempC({r}) : 0.0;
      const double at_c = std::isfinite(temp_c) ? temp_c : bias.t_ref_c;
      if (steady.Turning(bias.Deviation(sig.MeanGyro(r), at_c), at_c)) continue;
    }
    // The window shortens a still stretch by a window: its dwell is about run + window.
    const double dwell_s =
        sig.t[r.end - 1] - sig.t[r.begin] + dt_median + 2.0 * static_cast<double>(hs) * dt_median;
    summary->short_static_min_s =
        summary->short_static_count == 0 ? dwell_s : std::min(summary->short_static_min_s, dwell_s);
    summary->short_static_max_s = std::max(summary->short_static_max_s, dwell_s);
    ++summary->short_static_count;
  }
  if (summary->short_static_count > 0) {
    // With min_static_s = S (and the window shrunk to S) a pose of dwell D leaves a still run
    // of about D - S, which must be >= S: S <= D / 2, in steps of 0.05 s.
    summary->suggested_min_static_s =
        std::max(0.05, std::floor(summary->short_static_min_s / 2.0 / 0.05) * 0.05);
  }
}

}  // namespace

SegmentationSummary DetectSegments(const SegmentationInput& input,
                                   const SegmentationOptions& options) {
  METRO_CHECK(options.IsValid(nullptr));
  SegmentationSummary summary;
  Signals signals(input);
  if (signals.n < 3) return summary;
  MeasureNoise(options, &signals, &summary);
  const std::vector<std::vector<Run>> poses = ChoosePoses(signals, options, &summary);
  std::vector<Segment> segments;
  const SteadyRotations steady = SplitSteady(signals, options, poses, &summary, &segments);
  StaticAndRotationSegments(signals, steady.kept, &summary, &segments);
  TableSegments(signals, options, &segments);
  CountShortPoses(signals, steady, segments, &summary);

  std::sort(segments.begin(), segments.end(),
            [](const Segment& a, const Segment& b) { return a.begin < b.begin; });
  for (const Segment& s : segments) {
    if (s.kind == SegmentKind::kStatic) ++summary.static_count;
    if (s.kind == SegmentKind::kTable) ++summary.table_count;
    if (s.kind == SegmentKind::kRotation) ++summary.rotation_count;
  }
  summary.segments = std::move(segments);
  return summary;
}

}  // namespace metro
