#include "metro/noise/sample_period.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

namespace metro {
namespace {

// "lines 12, 40, 77, 90, 102 and 31 more".
std::string LineList(const std::vector<uint32_t>& lines) {
  constexpr size_t kShown = 5;
  std::string text = lines.size() == 1 ? "line " : "lines ";
  for (size_t i = 0; i < std::min(lines.size(), kShown); ++i) {
    if (i > 0) text += ", ";
    text += std::to_string(lines[i]);
  }
  if (lines.size() > kShown) text += fmt::format(" and {} more", lines.size() - kShown);
  return text;
}

}  // namespace

bool SamplePeriodOptions::IsValid(std::string* why) const {
  if (!(gap_factor > 1.0 && std::isfinite(gap_factor))) {
    if (why != nullptr) *why = fmt::format("gap_factor {} must be a number above 1", gap_factor);
    return false;
  }
  if (!(max_relative_drift > 0.0)) {
    if (why != nullptr) {
      *why = fmt::format("max_relative_drift {} must be above 0", max_relative_drift);
    }
    return false;
  }
  if (!(max_relative_jitter > 0.0)) {
    if (why != nullptr) {
      *why = fmt::format("max_relative_jitter {} must be above 0", max_relative_jitter);
    }
    return false;
  }
  return true;
}

namespace {

// The medians FromIntervals takes, for intervals in memory: of all n - 1 intervals (the
// mean of the two middle ones for an even count), and the upper median of those of
// [begin, end) at most `limit`, both by nth_element on a copy.
struct InMemoryMedians {
  template <typename Interval>
  double Whole(const Interval& dt, size_t count) const {
    std::vector<double> sorted(count);
    for (size_t i = 0; i < count; ++i) sorted[i] = dt(i);
    const size_t mid = sorted.size() / 2;
    std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(mid),
                     sorted.end());
    double median = sorted[mid];
    if (sorted.size() % 2 == 0) {
      const double below =
          *std::max_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(mid));
      median = 0.5 * (median + below);
    }
    return median;
  }
  // NaN when no interval qualifies.
  template <typename Interval>
  double Part(const Interval& dt, size_t begin, size_t end, double limit) const {
    std::vector<double> piece;
    for (size_t i = begin; i < end; ++i) {
      if (dt(i) <= limit) piece.push_back(dt(i));
    }
    if (piece.empty()) return std::nan("");
    std::nth_element(piece.begin(), piece.begin() + static_cast<std::ptrdiff_t>(piece.size() / 2),
                     piece.end());
    return piece[piece.size() / 2];
  }
};

// The same medians from counts of the distinct interval values (a clock's intervals take
// few): memory independent of n, for intervals read in order from a spill file. More than
// kMaxDistinctIntervals distinct values make it give up (NaN, and `failed` set).
struct CountingMedians {
  static constexpr size_t kMaxDistinctIntervals = size_t{1} << 16;

  template <typename Interval>
  double Whole(const Interval& dt, size_t count) const {
    if (!Count(dt, 0, count, HUGE_VAL)) return std::nan("");
    const size_t mid = total_ / 2;
    return total_ % 2 == 0 ? 0.5 * (Kth(mid) + Kth(mid - 1)) : Kth(mid);
  }
  template <typename Interval>
  double Part(const Interval& dt, size_t begin, size_t end, double limit) const {
    if (!Count(dt, begin, end, limit) || total_ == 0) return std::nan("");
    return Kth(total_ / 2);
  }

 private:
  // Counts the distinct dt(i) <= limit of [begin, end); false past kMaxDistinctIntervals.
  template <typename Interval>
  bool Count(const Interval& dt, size_t begin, size_t end, double limit) const {
    counts_.clear();
    total_ = 0;
    for (size_t i = begin; i < end; ++i) {
      const double v = dt(i);
      if (!(v <= limit)) continue;
      ++counts_[v];
      ++total_;
      if (counts_.size() > kMaxDistinctIntervals) return false;
    }
    return true;
  }
  // The k-th smallest (0-based) of the counted values.
  double Kth(size_t k) const {
    size_t seen = 0;
    for (const auto& [value, c] : counts_) {
      seen += c;
      if (k < seen) return value;
    }
    return std::nan("");
  }
  mutable std::map<double, size_t> counts_;
  mutable size_t total_ = 0;
};

// The estimate from the n - 1 intervals dt(i) = t[i + 1] - t[i] [s] (computed when asked,
// so no array of them is kept beside the times) and the whole span t[n - 1] - t[0] [s];
// line(i) is the source line of timestamp i; `medians` forms the medians (InMemoryMedians
// or CountingMedians). dt and line are read in increasing i, pass after pass.
template <typename Interval, typename Line, typename Medians>
Result<SamplePeriod> FromIntervals(const Interval& dt, size_t n, double span_s, const Line& line,
                                   const SamplePeriodOptions& options, const Medians& medians) {
  std::vector<uint32_t> reset_lines;
  for (size_t i = 0; i + 1 < n; ++i) {
    if (!(dt(i) > 0.0)) reset_lines.push_back(line(i + 1));
  }
  if (!reset_lines.empty()) {
    return MakeError("", reset_lines.front(),
                     fmt::format("time does not increase at {} ({} resets): the Allan "
                                 "estimators need one uniformly sampled run; split the log there",
                                 LineList(reset_lines), reset_lines.size()));
  }
  const double median = medians.Whole(dt, n - 1);
  if (std::isnan(median)) {
    return MakeError(fmt::format(
        "sample period: the {} intervals take more than {} distinct values: their median is not "
        "available in streaming mode (run without --stream)",
        n - 1, CountingMedians::kMaxDistinctIntervals));
  }

  SamplePeriod period;
  period.tau0_s = median;
  period.rate_hz = 1.0 / median;
  period.n_samples = static_cast<int64_t>(n);
  period.mean_dt_s = span_s / static_cast<double>(n - 1);
  std::vector<uint32_t> gap_lines;
  double sum_sq = 0.0;
  int64_t regular = 0;
  for (size_t i = 0; i + 1 < n; ++i) {
    if (dt(i) > options.gap_factor * median) {
      TimingGap gap;
      gap.line = line(i + 1);
      gap.dt_s = dt(i);
      // Counted in double and saturated: a gap of 1e300 s (a corrupt timestamp) must not
      // overflow the int64 count (UBSan: signed overflow, issue #20).
      constexpr double kMaxCount = 1e18;
      const double missing = std::min(kMaxCount, std::max(1.0, std::round(dt(i) / median) - 1.0));
      gap.missing_samples = static_cast<int64_t>(missing);
      period.missing_samples = static_cast<int64_t>(
          std::min(kMaxCount, static_cast<double>(period.missing_samples) + missing));
      period.gaps.push_back(gap);
      gap_lines.push_back(gap.line);
      continue;
    }
    const double e = dt(i) - median;
    sum_sq += e * e;
    period.max_abs_jitter_s = std::max(period.max_abs_jitter_s, std::fabs(e));
    ++regular;
  }
  period.jitter_rms_s = regular > 0 ? std::sqrt(sum_sq / static_cast<double>(regular)) : 0.0;
  // Drift: the median interval of each tenth of the record (gaps left out). A clock that
  // runs slow or fast through the log changes tau0 under the Allan taus, which assume one.
  constexpr size_t kParts = 10;
  if (n - 1 >= 10 * kParts) {
    const size_t per = (n - 1) / kParts;
    period.drift_min_dt_s = std::numeric_limits<double>::infinity();
    period.drift_max_dt_s = -std::numeric_limits<double>::infinity();
    for (size_t part = 0; part < kParts; ++part) {
      const size_t end = part + 1 == kParts ? n - 1 : (part + 1) * per;
      const double part_median = medians.Part(dt, part * per, end, options.gap_factor * median);
      if (std::isnan(part_median)) continue;
      if (part == 0) period.drift_first_dt_s = part_median;
      if (part + 1 == kParts) period.drift_last_dt_s = part_median;
      period.drift_min_dt_s = std::min(period.drift_min_dt_s, part_median);
      period.drift_max_dt_s = std::max(period.drift_max_dt_s, part_median);
    }
    if (period.drift_max_dt_s - period.drift_min_dt_s > options.max_relative_drift * median) {
      period.warnings.push_back(fmt::format(
          "sample interval drifts: the median interval of tenths of the record ranges from "
          "{:.6g} s to {:.6g} s ({:.6g} s in the first tenth, lines {}-{}, {:.6g} s in the "
          "last, lines {}-{}); the Allan taus assume one tau0 = {:.6g} s",
          period.drift_min_dt_s, period.drift_max_dt_s, period.drift_first_dt_s, line(0), line(per),
          period.drift_last_dt_s, line((kParts - 1) * per), line(n - 1), median));
    }
  }
  if (!gap_lines.empty() && !options.allow_gaps) {
    return MakeError(
        "", gap_lines.front(),
        fmt::format("{} {} longer than {} x the median interval {:.6g} s at {} "
                    "({} samples missing): the Allan estimators need uniform "
                    "sampling; analyse the runs between gaps separately",
                    gap_lines.size(), gap_lines.size() == 1 ? "gap" : "gaps", options.gap_factor,
                    median, LineList(gap_lines), period.missing_samples));
  }
  for (const TimingGap& gap : period.gaps) {
    period.warnings.push_back(fmt::format("line {}: gap of {:.6g} s (about {} samples missing)",
                                          gap.line, gap.dt_s, gap.missing_samples));
  }
  if (period.jitter_rms_s > options.max_relative_jitter * median) {
    return MakeError(
        fmt::format("sample period: RMS jitter {:.6g} s is more than {} x the median interval "
                    "{:.6g} s; the samples "
                    "are not uniformly spaced",
                    period.jitter_rms_s, options.max_relative_jitter, median));
  }
  return period;
}

Status CheckSizes(size_t times, size_t lines) {
  if (times != lines) {
    return MakeError(fmt::format("sample period: {} timestamps but {} line numbers", times, lines));
  }
  if (times < 3) {
    return MakeError(
        fmt::format("sample period: {} timestamps are too few (at least 3 are needed)", times));
  }
  return Status::Ok();
}

}  // namespace

Result<SamplePeriod> EstimateSamplePeriod(const std::vector<double>& t_s,
                                          const std::vector<uint32_t>& line,
                                          const SamplePeriodOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) return MakeError("sample period options: " + why);
  if (Status s = CheckSizes(t_s.size(), line.size()); !s.ok()) return s.error();
  return EstimateSamplePeriod(t_s.data(), line.data(), t_s.size(), options);
}

Result<SamplePeriod> EstimateSamplePeriod(const double* t_s, const uint32_t* line, size_t n,
                                          const SamplePeriodOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) return MakeError("sample period options: " + why);
  if (Status s = CheckSizes(n, n); !s.ok()) return s.error();
  for (size_t i = 0; i < n; ++i) {
    if (!std::isfinite(t_s[i])) {
      return MakeError("", line[i], fmt::format("timestamp {} is not finite", t_s[i]));
    }
  }
  return FromIntervals([t_s](size_t i) { return t_s[i + 1] - t_s[i]; }, n, t_s[n - 1] - t_s[0],
                       [line](size_t i) { return line[i]; }, options, InMemoryMedians());
}

Result<SamplePeriod> EstimateSamplePeriodNs(const std::vector<int64_t>& t_ns,
                                            const std::vector<uint32_t>& line,
                                            const SamplePeriodOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) return MakeError("sample period options: " + why);
  if (Status s = CheckSizes(t_ns.size(), line.size()); !s.ok()) return s.error();
  return EstimateSamplePeriodNs(t_ns.data(), line.data(), t_ns.size(), options);
}

Result<SamplePeriod> EstimateSamplePeriodNs(const int64_t* t_ns, const uint32_t* line, size_t n,
                                            const SamplePeriodOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) return MakeError("sample period options: " + why);
  if (Status s = CheckSizes(n, n); !s.ok()) return s.error();
  // Differences of integers, exact (saturated where they would overflow: a time reset that
  // large is refused as a reset either way); each converted once, correctly rounded.
  const auto dt = [t_ns](size_t i) {
    int64_t d = 0;
    if (__builtin_sub_overflow(t_ns[i + 1], t_ns[i], &d)) {
      d = t_ns[i + 1] > t_ns[i] ? INT64_MAX : INT64_MIN;
    }
    return static_cast<double>(d) / 1e9;
  };
  int64_t span = 0;
  if (__builtin_sub_overflow(t_ns[n - 1], t_ns[0], &span)) span = INT64_MAX;
  return FromIntervals(
      dt, n, static_cast<double>(span) / 1e9, [line](size_t i) { return line[i]; }, options,
      InMemoryMedians());
}

namespace {

// Values i, i + 1 of a column read in order through a window of kWindow values, reloaded
// when i leaves it (FromIntervals reads pass after pass in increasing i). A failed read
// leaves zeros and keeps the first error.
template <typename T>
class Sequential {
 public:
  static constexpr size_t kWindow = size_t{1} << 16;
  Sequential(const std::function<Status(size_t, size_t, T*)>& read, size_t n)
      : read_(read), n_(n), window_(kWindow) {}
  T operator()(size_t i) const {
    if (i < begin_ || i >= begin_ + count_) Load(i);
    return window_[i - begin_];
  }
  Status status() const { return status_; }

 private:
  void Load(size_t i) const {
    begin_ = i;
    count_ = std::min(kWindow, n_ - i);
    Status s = read_(begin_, count_, window_.data());
    if (!s.ok() && status_.ok()) status_ = s;
  }
  const std::function<Status(size_t, size_t, T*)>& read_;
  size_t n_;
  mutable std::vector<T> window_;
  mutable size_t begin_ = 0, count_ = 0;
  mutable Status status_ = Status::Ok();
};

}  // namespace

Result<SamplePeriod> EstimateSamplePeriodChunked(const TimeColumnReader& time,
                                                 const LineColumnReader& line, size_t n,
                                                 const SamplePeriodOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) return MakeError("sample period options: " + why);
  if (Status s = CheckSizes(n, n); !s.ok()) return s.error();
  Sequential<uint32_t> lines(line, n);
  const auto line_of = [&lines](size_t i) { return lines(i); };
  Result<SamplePeriod> period = MakeError("not estimated");
  if (time.t_ns) {
    Sequential<int64_t> t(time.t_ns, n);
    const auto dt = [&t](size_t i) {
      const int64_t a = t(i), b = t(i + 1);
      int64_t d = 0;
      if (__builtin_sub_overflow(b, a, &d)) d = b > a ? INT64_MAX : INT64_MIN;
      return static_cast<double>(d) / 1e9;
    };
    int64_t span = 0;
    if (__builtin_sub_overflow(t(n - 1), t(0), &span)) span = INT64_MAX;
    period =
        FromIntervals(dt, n, static_cast<double>(span) / 1e9, line_of, options, CountingMedians());
    if (!t.status().ok()) return t.status().error();
  } else {
    Sequential<double> t(time.t_s, n);
    for (size_t i = 0; i < n; ++i) {
      if (!std::isfinite(t(i))) {
        return MakeError("", lines(i), fmt::format("timestamp {} is not finite", t(i)));
      }
    }
    const auto dt = [&t](size_t i) {
      const double a = t(i);
      return t(i + 1) - a;
    };
    period = FromIntervals(dt, n, t(n - 1) - t(0), line_of, options, CountingMedians());
    if (!t.status().ok()) return t.status().error();
  }
  if (!lines.status().ok()) return lines.status().error();
  return period;
}

}  // namespace metro
