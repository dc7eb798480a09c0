#include "metro/core/progress.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <system_error>

#include "metro/core/check.hpp"
#include "metro/core/terminal_text.hpp"

namespace metro {

bool ProgressOptions::IsValid(std::string* why) const {
  if (!(min_redraw_s >= 0.0)) {
    *why = "progress: min_redraw_s must be >= 0";
    return false;
  }
  if (bar_width < 1 || bar_width > 200) {
    *why = "progress: bar_width must be in [1, 200]";
    return false;
  }
  if (!(unit_divisor > 0.0) || !std::isfinite(unit_divisor)) {
    *why = "progress: unit_divisor must be finite and > 0";
    return false;
  }
  if (!(delay_s >= 0.0)) {
    *why = "progress: delay_s must be >= 0";
    return false;
  }
  return true;
}

std::string FormatProgressLine(const std::string& label, int64_t done, int64_t total,
                               double elapsed_s, int bar_width, const std::string& unit,
                               double unit_divisor) {
  const auto count = [unit_divisor](int64_t n) {
    return unit_divisor == 1.0 ? fmt::format("{}", n)
                               : fmt::format("{:.1f}", static_cast<double>(n) / unit_divisor);
  };
  const std::string suffix = unit.empty() ? std::string() : " " + unit;
  // The rate so far and, with a total, the time left at that rate.
  std::string pace;
  if (elapsed_s > 0.0 && done > 0) {
    const double per_s = static_cast<double>(done) / elapsed_s;
    pace = unit_divisor == 1.0 ? fmt::format("  {:.0f}{}/s", per_s, suffix)
                               : fmt::format("  {:.1f}{}/s", per_s / unit_divisor, suffix);
    if (total > done) {
      pace += fmt::format("  {:.0f} s left", static_cast<double>(total - done) / per_s);
    }
  }
  if (total <= 0) {
    return fmt::format("{} {}{}  {:.1f} s{}", label, count(done), suffix, elapsed_s, pace);
  }
  const int64_t clamped = std::clamp<int64_t>(done, 0, total);
  const double fraction = static_cast<double>(clamped) / static_cast<double>(total);
  const int filled = static_cast<int>(fraction * bar_width);
  return fmt::format("{} [{}{}] {}/{}{} {:3d} %  {:.1f} s{}", label, std::string(filled, '#'),
                     std::string(bar_width - filled, '.'), count(done), count(total), suffix,
                     static_cast<int>(fraction * 100.0), elapsed_s, pace);
}

bool IsTerminal(std::FILE* stream) { return stream != nullptr && ::isatty(::fileno(stream)) == 1; }

ProgressBar::ProgressBar(std::string label, int64_t total, std::FILE* stream,
                         const ProgressOptions& options)
    : label_(std::move(label)), total_(total), stream_(stream), options_(options) {
  std::string why;
  METRO_CHECK(options_.IsValid(&why));
  enabled_ = stream_ != nullptr && (options_.mode == ProgressMode::kAlways ||
                                    (options_.mode == ProgressMode::kAuto && IsTerminal(stream_)));
  start_ = std::chrono::steady_clock::now();
  last_draw_ = start_;
  if (enabled_ && options_.delay_s == 0.0) Draw(true);
}

ProgressBar::~ProgressBar() { Finish(); }

void ProgressBar::Advance(int64_t n) {
  done_.fetch_add(n);
  if (enabled_) Draw(false);
}

void ProgressBar::Finish() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (finished_) return;
  finished_ = true;
  if (!enabled_) return;
  const double elapsed_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  // Work that ended within delay_s and was never drawn leaves no line.
  if (!drawn_ && elapsed_s < options_.delay_s) return;
  fmt::print(stream_, "\r{}\n",
             FormatProgressLine(label_, done_.load(), total_, elapsed_s, options_.bar_width,
                                options_.unit, options_.unit_divisor));
  std::fflush(stream_);
}

void ProgressBar::Draw(bool force) {
  std::unique_lock<std::mutex> lock(mutex_, std::try_to_lock);
  if (!lock.owns_lock() || finished_) return;  // Another thread is drawing.
  const auto now = std::chrono::steady_clock::now();
  if (!force && std::chrono::duration<double>(now - last_draw_).count() < options_.min_redraw_s) {
    return;
  }
  const double elapsed_s = std::chrono::duration<double>(now - start_).count();
  if (elapsed_s < options_.delay_s) return;
  last_draw_ = now;
  drawn_ = true;
  // "\r" returns to the line start; the trailing blanks clear a longer previous line.
  fmt::print(stream_, "\r{}  ",
             FormatProgressLine(label_, done_.load(), total_, elapsed_s, options_.bar_width,
                                options_.unit, options_.unit_divisor));
  std::fflush(stream_);
}

std::string FormatElapsedLine(const std::string& label, double elapsed_s) {
  return fmt::format("{} ...  {:.1f} s", label, elapsed_s);
}

ElapsedTicker::ElapsedTicker(std::string label, std::FILE* stream, const ProgressOptions& options)
    : label_(std::move(label)), stream_(stream), options_(options) {
  std::string why;
  METRO_CHECK(options_.IsValid(&why));
  enabled_ = stream_ != nullptr && (options_.mode == ProgressMode::kAlways ||
                                    (options_.mode == ProgressMode::kAuto && IsTerminal(stream_)));
  start_ = std::chrono::steady_clock::now();
  if (!enabled_) return;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (Due()) DrawLocked();
  }
  const auto period = std::chrono::duration<double>(std::max(0.05, options_.min_redraw_s));
  thread_ = std::thread([this, period] {
    std::unique_lock<std::mutex> lock(mutex_);
    while (!finished_) {
      wake_.wait_for(lock, period);
      if (!finished_ && Due()) DrawLocked();
    }
  });
}

ElapsedTicker::~ElapsedTicker() { Finish(); }

void ElapsedTicker::SetLabel(std::string label) {
  std::lock_guard<std::mutex> lock(mutex_);
  label_ = std::move(label);
  if (enabled_ && !finished_ && Due()) DrawLocked();
}

void ElapsedTicker::Finish() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (finished_) return;
    finished_ = true;
    if (enabled_ && (drawn_ || Due())) {
      DrawLocked();
      fmt::print(stream_, "\n");
      std::fflush(stream_);
    }
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
}

bool ElapsedTicker::Due() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count() >=
         options_.delay_s;
}

void ElapsedTicker::DrawLocked() {
  drawn_ = true;
  const double elapsed_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  // "\r" returns to the line start; the trailing blanks clear a longer previous line.
  fmt::print(stream_, "\r{}  ", FormatElapsedLine(label_, elapsed_s));
  std::fflush(stream_);
}

void BeginLoadPhase(ProgressSink* progress, const std::string& path) {
  std::error_code ec;
  const auto bytes = std::filesystem::file_size(path, ec);
  // The file name is data: escaped before it reaches the terminal.
  progress->BeginPhase(
      "load " + EscapeControlChars(std::filesystem::path(path).filename().string()),
      ec ? 0 : static_cast<int64_t>(bytes), "MB", 1e6);
}

TerminalProgress::TerminalProgress(std::FILE* stream, const ProgressOptions& options)
    : stream_(stream), options_(options) {
  std::string why;
  METRO_CHECK(options_.IsValid(&why));
}

TerminalProgress::~TerminalProgress() { Finish(); }

void TerminalProgress::BeginPhase(const std::string& label, int64_t total, const std::string& unit,
                                  double unit_divisor) {
  Finish();
  ProgressOptions o = options_;
  o.unit = unit;
  o.unit_divisor = unit_divisor;
  if (total == kUncountedWork) {
    ticker_ = std::make_unique<ElapsedTicker>(label, stream_, o);
  } else {
    bar_ = std::make_unique<ProgressBar>(label, total, stream_, o);
  }
}

void TerminalProgress::Advance(int64_t n) {
  if (bar_) bar_->Advance(n);
}

void TerminalProgress::Finish() {
  if (bar_) bar_->Finish();
  if (ticker_) ticker_->Finish();
  bar_.reset();
  ticker_.reset();
}

}  // namespace metro
