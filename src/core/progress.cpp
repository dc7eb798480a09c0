#include "metro/core/progress.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <system_error>

#include "metro/core/check.hpp"

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
  return true;
}

std::string FormatProgressLine(const std::string& label, int64_t done, int64_t total,
                               double elapsed_s, int bar_width) {
  if (total <= 0) return fmt::format("{} {}  {:.1f} s", label, done, elapsed_s);
  const int64_t clamped = std::clamp<int64_t>(done, 0, total);
  const double fraction = static_cast<double>(clamped) / static_cast<double>(total);
  const int filled = static_cast<int>(fraction * bar_width);
  return fmt::format("{} [{}{}] {}/{} {:3d} %  {:.1f} s", label, std::string(filled, '#'),
                     std::string(bar_width - filled, '.'), done, total,
                     static_cast<int>(fraction * 100.0), elapsed_s);
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
  if (enabled_) Draw(true);
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
  fmt::print(stream_, "\r{}\n",
             FormatProgressLine(label_, done_.load(), total_, elapsed_s, options_.bar_width));
  std::fflush(stream_);
}

void ProgressBar::Draw(bool force) {
  std::unique_lock<std::mutex> lock(mutex_, std::try_to_lock);
  if (!lock.owns_lock() || finished_) return;  // Another thread is drawing.
  const auto now = std::chrono::steady_clock::now();
  if (!force && std::chrono::duration<double>(now - last_draw_).count() < options_.min_redraw_s) {
    return;
  }
  last_draw_ = now;
  const double elapsed_s = std::chrono::duration<double>(now - start_).count();
  // "\r" returns to the line start; the trailing blanks clear a longer previous line.
  fmt::print(stream_, "\r{}  ",
             FormatProgressLine(label_, done_.load(), total_, elapsed_s, options_.bar_width));
  std::fflush(stream_);
}

bool IsBigInput(const std::string& path, int64_t threshold_bytes) {
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  return !ec && static_cast<int64_t>(size) >= threshold_bytes;
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
    DrawLocked();
  }
  const auto period = std::chrono::duration<double>(std::max(0.05, options_.min_redraw_s));
  thread_ = std::thread([this, period] {
    std::unique_lock<std::mutex> lock(mutex_);
    while (!finished_) {
      wake_.wait_for(lock, period);
      if (!finished_) DrawLocked();
    }
  });
}

ElapsedTicker::~ElapsedTicker() { Finish(); }

void ElapsedTicker::SetLabel(std::string label) {
  std::lock_guard<std::mutex> lock(mutex_);
  label_ = std::move(label);
  if (enabled_ && !finished_) DrawLocked();
}

void ElapsedTicker::Finish() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (finished_) return;
    finished_ = true;
    if (enabled_) {
      DrawLocked();
      fmt::print(stream_, "\n");
      std::fflush(stream_);
    }
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
}

void ElapsedTicker::DrawLocked() {
  const double elapsed_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  // "\r" returns to the line start; the trailing blanks clear a longer previous line.
  fmt::print(stream_, "\r{}  ", FormatElapsedLine(label_, elapsed_s));
  std::fflush(stream_);
}

}  // namespace metro
