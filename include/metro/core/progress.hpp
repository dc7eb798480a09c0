// A progress bar on stderr for long work (batch runs, big files, Monte Carlo).
//
// The bar is drawn only when the stream is a terminal (isatty), so logs and pipes stay
// quiet; ProgressMode::kAlways / kNever override that. Advance() may be called from any
// thread; the line is redrawn at most every `min_redraw_s` seconds, with "\r" and no
// newline until Finish().
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <mutex>
#include <string>

namespace metro {

enum class ProgressMode { kAuto, kAlways, kNever };

struct ProgressOptions {
  ProgressMode mode = ProgressMode::kAuto;
  double min_redraw_s = 0.1;  // Redraw at most this often.
  int bar_width = 30;         // Characters of the bar itself.

  bool IsValid(std::string* why) const;
};

// One progress line: "label [#####.....] done/total  40 %  12.3 s". `total` 0 gives no bar
// and no percentage. Exposed for tests.
std::string FormatProgressLine(const std::string& label, int64_t done, int64_t total,
                               double elapsed_s, int bar_width);

// True when `stream` is a terminal.
bool IsTerminal(std::FILE* stream);

class ProgressBar {
 public:
  // `stream` is not owned. Options must be valid (METRO_CHECK).
  ProgressBar(std::string label, int64_t total, std::FILE* stream = stderr,
              const ProgressOptions& options = {});
  ProgressBar(const ProgressBar&) = delete;
  ProgressBar& operator=(const ProgressBar&) = delete;
  ~ProgressBar();  // Finish()es.

  bool enabled() const { return enabled_; }
  int64_t done() const { return done_.load(); }

  // Thread-safe.
  void Advance(int64_t n = 1);
  // Draws the final state and ends the line (once; later calls do nothing).
  void Finish();

 private:
  void Draw(bool force);

  std::string label_;
  int64_t total_ = 0;
  std::FILE* stream_ = nullptr;
  ProgressOptions options_;
  bool enabled_ = false;
  bool finished_ = false;
  std::atomic<int64_t> done_{0};
  std::mutex mutex_;
  std::chrono::steady_clock::time_point start_;
  std::chrono::steady_clock::time_point last_draw_;
};

}  // namespace metro
