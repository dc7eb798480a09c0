#include "metro/noise/sample_period.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

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
  if (!(max_relative_jitter > 0.0)) {
    if (why != nullptr) {
      *why = fmt::format("max_relative_jitter {} must be above 0", max_relative_jitter);
    }
    return false;
  }
  return true;
}

Result<SamplePeriod> EstimateSamplePeriod(const std::vector<double>& t_s,
                                          const std::vector<uint32_t>& line,
                                          const SamplePeriodOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) return MakeError("sample period options: " + why);
  if (t_s.size() != line.size()) {
    return MakeError(
        fmt::format("sample period: {} timestamps but {} line numbers", t_s.size(), line.size()));
  }
  if (t_s.size() < 3) {
    return MakeError(fmt::format("sample period: {} timestamps are too few (at least 3 are needed)",
                                 t_s.size()));
  }
  for (size_t i = 0; i < t_s.size(); ++i) {
    if (!std::isfinite(t_s[i])) {
      return MakeError("", line[i], fmt::format("timestamp {} is not finite", t_s[i]));
    }
  }
  const size_t n = t_s.size();
  std::vector<double> dt(n - 1);
  std::vector<uint32_t> reset_lines;
  for (size_t i = 0; i + 1 < n; ++i) {
    dt[i] = t_s[i + 1] - t_s[i];
    if (!(dt[i] > 0.0)) reset_lines.push_back(line[i + 1]);
  }
  if (!reset_lines.empty()) {
    return MakeError("", reset_lines.front(),
                     fmt::format("time does not increase at {} ({} resets): the Allan "
                                 "estimators need one uniformly sampled run; split the log there",
                                 LineList(reset_lines), reset_lines.size()));
  }
  std::vector<double> sorted = dt;
  const size_t mid = sorted.size() / 2;
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(mid), sorted.end());
  double median = sorted[mid];
  if (sorted.size() % 2 == 0) {
    const double below =
        *std::max_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(mid));
    median = 0.5 * (median + below);
  }

  SamplePeriod period;
  period.tau0_s = median;
  period.rate_hz = 1.0 / median;
  period.n_samples = static_cast<int64_t>(n);
  period.mean_dt_s = (t_s.back() - t_s.front()) / static_cast<double>(n - 1);
  std::vector<uint32_t> gap_lines;
  double sum_sq = 0.0;
  int64_t regular = 0;
  for (size_t i = 0; i + 1 < n; ++i) {
    if (dt[i] > options.gap_factor * median) {
      TimingGap gap;
      gap.line = line[i + 1];
      gap.dt_s = dt[i];
      gap.missing_samples = std::max<int64_t>(1, std::llround(dt[i] / median) - 1);
      period.missing_samples += gap.missing_samples;
      period.gaps.push_back(gap);
      gap_lines.push_back(gap.line);
      continue;
    }
    const double e = dt[i] - median;
    sum_sq += e * e;
    period.max_abs_jitter_s = std::max(period.max_abs_jitter_s, std::fabs(e));
    ++regular;
  }
  period.jitter_rms_s = regular > 0 ? std::sqrt(sum_sq / static_cast<double>(regular)) : 0.0;
  if (!gap_lines.empty() && !options.allow_gaps) {
    return MakeError("", gap_lines.front(),
                     fmt::format("{} gaps longer than {} x the median interval {:.6g} s at {} "
                                 "({} samples missing): the Allan estimators need uniform "
                                 "sampling; analyse the runs between gaps separately",
                                 gap_lines.size(), options.gap_factor, median, LineList(gap_lines),
                                 period.missing_samples));
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

}  // namespace metro
