// Sample period of a logged series from its timestamps, with jitter, gaps and resets.
//
// tau0 is the median of the intervals dt_i = t_{i+1} - t_i (robust against a few gaps).
// An interval is a gap when dt > gap_factor * tau0 (about round(dt / tau0) - 1 samples are
// missing there) and a reset when dt <= 0 (time stands still or runs backwards). Jitter is the
// RMS of dt - tau0 over the intervals that are not gaps. The Allan estimators need uniformly
// spaced samples, so resets always refuse, gaps refuse unless allowed, and jitter above
// max_relative_jitter * tau0 refuses. Every event names the 1-based source line of the sample
// that ends the interval (line[i + 1]).
//
// Drift: the median interval of each tenth of the record (gaps left out); when these range
// over more than max_relative_drift * tau0 a warning names the range and the first and last
// tenths (a clock running slow or fast through the log: the Allan taus assume one tau0).
// Records of fewer than 101 samples are not checked.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "metro/core/status.hpp"

namespace metro {

struct SamplePeriodOptions {
  double gap_factor = 1.5;           // > 1.
  bool allow_gaps = false;           // false: any gap refuses.
  double max_relative_jitter = 0.1;  // RMS jitter / tau0 above this refuses; > 0.
  double max_relative_drift = 0.01;  // Range of the tenths' medians / tau0 that warns; > 0.

  bool IsValid(std::string* why) const;
};

struct TimingGap {
  uint32_t line = 0;            // Source line of the sample after the gap.
  double dt_s = 0.0;            // The interval.
  int64_t missing_samples = 0;  // round(dt / tau0) - 1.
};

struct SamplePeriod {
  double tau0_s = 0.0;        // Median interval.
  double rate_hz = 0.0;       // 1 / tau0.
  double mean_dt_s = 0.0;     // (t_last - t_first) / (n - 1), gaps included.
  double jitter_rms_s = 0.0;  // RMS of dt - tau0 over regular intervals.
  double max_abs_jitter_s = 0.0;
  int64_t n_samples = 0;
  int64_t missing_samples = 0;  // Sum over gaps.
  // Median interval of the first and last tenths and the range over all tenths [s]
  // (0 when the record has fewer than 101 samples).
  double drift_first_dt_s = 0.0;
  double drift_last_dt_s = 0.0;
  double drift_min_dt_s = 0.0;
  double drift_max_dt_s = 0.0;
  std::vector<TimingGap> gaps;        // Only filled when gaps are allowed.
  std::vector<std::string> warnings;  // Human-readable, one per gap (with its line).
};

// Errors: sizes differ, fewer than 3 samples, a non-finite time, a reset, a gap (unless
// allowed) or too much jitter; each names the source lines (the first five, then a count).
Result<SamplePeriod> EstimateSamplePeriod(const std::vector<double>& t_s,
                                          const std::vector<uint32_t>& line,
                                          const SamplePeriodOptions& options = {});

// The same from exact integer times [ns] (Tag::t_ns): intervals are integer differences,
// so an epoch-nanosecond clock keeps its sample period (200 Hz: tau0 = 0.005 s, not the
// 0.004999876 s that doubles of 1.4e18 ns give).
Result<SamplePeriod> EstimateSamplePeriodNs(const std::vector<int64_t>& t_ns,
                                            const std::vector<uint32_t>& line,
                                            const SamplePeriodOptions& options = {});

// The same over n timestamps at t_s[0..n) (or t_ns) and their lines, read in place: a window
// of a tag's columns needs no copy (10^7 samples: the copies and the interval array were
// 280 MB of characterize --allan's peak).
Result<SamplePeriod> EstimateSamplePeriod(const double* t_s, const uint32_t* line, size_t n,
                                          const SamplePeriodOptions& options = {});
Result<SamplePeriod> EstimateSamplePeriodNs(const int64_t* t_ns, const uint32_t* line, size_t n,
                                            const SamplePeriodOptions& options = {});

// The times of a record in a spill file (the streaming mode): exact integer times when the
// session has them (t_ns set), else seconds (t_s set).
struct TimeColumnReader {
  std::function<Status(size_t begin, size_t count, double* out)> t_s;
  std::function<Status(size_t begin, size_t count, int64_t* out)> t_ns;
};
using LineColumnReader = std::function<Status(size_t begin, size_t count, uint32_t* out)>;

// The same estimate from columns read in order, in memory independent of n: the medians
// from counts of the distinct intervals (a clock's intervals take few values). The same
// result as EstimateSamplePeriod(Ns) on the same times, except that intervals taking more
// than 65536 distinct values give an Error that names the streaming mode.
Result<SamplePeriod> EstimateSamplePeriodChunked(const TimeColumnReader& time,
                                                 const LineColumnReader& line, size_t n,
                                                 const SamplePeriodOptions& options = {});

}  // namespace metro
