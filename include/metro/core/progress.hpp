// A progress bar on stderr for long work (batch runs, big files, Monte Carlo).
//
// The bar is drawn only when the stream is a terminal (isatty), so logs and pipes stay
// quiet; ProgressMode::kAlways / kNever override that. Advance() may be called from any
// thread; the line is redrawn at most every `min_redraw_s` seconds, with "\r" and no
// newline until Finish().
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

namespace metro {

enum class ProgressMode { kAuto, kAlways, kNever };

struct ProgressOptions {
  ProgressMode mode = ProgressMode::kAuto;
  double min_redraw_s = 0.1;  // Redraw at most this often.
  int bar_width = 30;         // Characters of the bar itself.
  // Counts are shown as count / unit_divisor followed by `unit` ("12.3/388.7 MB" with
  // unit "MB" and divisor 1e6; whole counts when the divisor is 1).
  std::string unit;
  double unit_divisor = 1.0;
  // Nothing is drawn until the work has run this long, so quick work leaves no line.
  double delay_s = 0.0;

  bool IsValid(std::string* why) const;
};

// One progress line: "label [#####.....] done/total  40 %  12.3 s  31.6 MB/s  18 s left":
// the count, the time so far, the rate so far (once something is done) and the time left at
// that rate. `total` 0 gives no bar, no percentage and no time left. Exposed for tests.
std::string FormatProgressLine(const std::string& label, int64_t done, int64_t total,
                               double elapsed_s, int bar_width, const std::string& unit = "",
                               double unit_divisor = 1.0);

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
  bool drawn_ = false;
  std::mutex mutex_;
  std::chrono::steady_clock::time_point start_;
  std::chrono::steady_clock::time_point last_draw_;
};

// "label ...  12.3 s": work whose progress cannot be observed shows only that it runs and
// for how long (no invented fraction). Exposed for tests.
std::string FormatElapsedLine(const std::string& label, double elapsed_s);

// A line with the elapsed time, redrawn every `min_redraw_s` (at least 0.05 s) by a
// background thread until Finish(); drawn only under the same rule as ProgressBar (a
// terminal, or kAlways). `SetLabel` names the current phase (e.g. "load", "budget").
class ElapsedTicker {
 public:
  // `stream` is not owned. Options must be valid (METRO_CHECK).
  explicit ElapsedTicker(std::string label, std::FILE* stream = stderr,
                         const ProgressOptions& options = {});
  ElapsedTicker(const ElapsedTicker&) = delete;
  ElapsedTicker& operator=(const ElapsedTicker&) = delete;
  ~ElapsedTicker();  // Finish()es.

  bool enabled() const { return enabled_; }
  // Thread-safe.
  void SetLabel(std::string label);
  // Stops the thread, draws the final line and ends it (once; later calls do nothing).
  void Finish();

 private:
  void DrawLocked();
  bool Due() const;  // Past options_.delay_s.

  std::string label_;
  std::FILE* stream_ = nullptr;
  ProgressOptions options_;
  bool enabled_ = false;
  bool finished_ = false;
  bool drawn_ = false;
  std::mutex mutex_;
  std::condition_variable wake_;
  std::chrono::steady_clock::time_point start_;
  std::thread thread_;
};

// Where long library calls report how far they are: a sequence of phases ("load", "Monte
// Carlo"), each with its planned amount of work in counts (kUncountedWork when the work
// cannot be counted; 0 when the total is unknown but counts are), then increments. A phase
// begins only after every Advance of the previous one has returned; Advance may be called
// from any thread and must be cheap.
constexpr int64_t kUncountedWork = -1;

class ProgressSink {
 public:
  virtual ~ProgressSink() = default;
  virtual void BeginPhase(const std::string& label, int64_t total, const std::string& unit = "",
                          double unit_divisor = 1.0) = 0;
  virtual void Advance(int64_t n) = 0;
  // The work is over: the last phase's line is ended.
  virtual void Finish() = 0;
};

// Begins the phase "load FILE" (the file name without its directories), counted in MB of
// the file's size (0, no total, if the size cannot be read): the loaders' on_bytes_parsed
// counts go to it.
void BeginLoadPhase(ProgressSink* progress, const std::string& path);

// Draws each phase on its own line of `stream`: a ProgressBar for counted work, an
// ElapsedTicker for uncounted work, each under `options` (mode, delay_s, redraw period).
class TerminalProgress : public ProgressSink {
 public:
  // `stream` is not owned. Options must be valid (METRO_CHECK).
  explicit TerminalProgress(std::FILE* stream = stderr, const ProgressOptions& options = {});
  ~TerminalProgress() override;  // Finish()es.
  void BeginPhase(const std::string& label, int64_t total, const std::string& unit = "",
                  double unit_divisor = 1.0) override;
  void Advance(int64_t n) override;
  void Finish() override;

 private:
  std::FILE* stream_ = nullptr;
  ProgressOptions options_;
  std::unique_ptr<ProgressBar> bar_;
  std::unique_ptr<ElapsedTicker> ticker_;
};

}  // namespace metro
