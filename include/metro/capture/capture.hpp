// Live capture of the central receiver's serial stream (docs/capture.md).
//
// The nRF52840 central prints one 54-hex-character line per tag per frame (docs/formats.md,
// "Receiver capture"). A capture keeps whole lines only, with the receiver's bytes unchanged:
//   - the first line after the port was opened (or reopened) is dropped and counted as cut
//     when it is not a whole receiver line (the port opened mid-line);
//   - any other line that is not a receiver line (DecodeReceiverLine: a banner, noise after a
//     reset, a garbled line) is counted and written as a `#` comment, never as data;
//   - `#` lines at the top name the port, baud, start time (UTC) and the metro version; `#`
//     lines mark a lost and a reopened port and close the file with per-tag counts. The
//     receiver loader skips `#` lines, so the file loads as a receiver capture.
// The file is flushed to disk (write + fdatasync) at least once a second.
#pragma once

#include <csignal>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "metro/core/status.hpp"
#include "metro/io/receiver.hpp"
#include "metro/io/session.hpp"

namespace metro::capture {

// Splits a byte stream into lines and sorts them. Lines end at LF; the bytes of a line,
// terminator included (CR LF stays CR LF), are passed on unchanged.
class LineSorter {
 public:
  enum class Kind { kReceiver, kCut, kOther };
  // `line` holds the line's bytes with its terminator; `decoded` is valid for kReceiver;
  // `why` says what a kOther line is not.
  using Sink = std::function<void(Kind kind, std::string_view line, const ReceiverLine& decoded,
                                  const std::string& why)>;

  // Lines longer than this without a LF are passed on as kOther in pieces of this size.
  static constexpr size_t kMaxLineBytes = 4096;

  void Feed(const uint8_t* data, size_t size, const Sink& sink);
  // The port was (re)opened: the next line may be the tail of a line.
  void Restart() {
    pending_.clear();
    first_ = true;
  }
  // Bytes of an unfinished line (dropped when the port is lost or the capture ends).
  size_t pending_bytes() const { return pending_.size(); }

 private:
  void Emit(const Sink& sink);
  std::string pending_;
  bool first_ = true;
};

// Per-tag counts and the decoded attitude of the fresh rows, as the loader would read them:
// a new frame starts when the sensor number does not increase; frame k is at
// t_s = k * frame_period_s.
struct TagSeries {
  int sensor = 0;
  FrameCounts counts;
  std::vector<double> t_s;
  std::vector<double> yaw_deg, pitch_deg, roll_deg;
};

class CaptureTally {
 public:
  explicit CaptureTally(double frame_period_s) : frame_period_s_(frame_period_s) {}
  void Add(const ReceiverLine& line);
  const std::map<int, TagSeries>& tags() const { return tags_; }
  double frame_period_s() const { return frame_period_s_; }
  int64_t frames() const { return frame_ + 1; }
  // The fresh rows as a receiver session (quantities yaw_deg, pitch_deg, roll_deg), for the
  // session Type A (stats/session_type_a.hpp).
  Session ToSession() const;

 private:
  double frame_period_s_;
  int64_t frame_ = -1;
  int previous_sensor_ = 256;
  std::map<int, TagSeries> tags_;
};

// Fresh packets per second of wall time per tag, over the last window_s seconds.
class FreshRates {
 public:
  explicit FreshRates(double window_s = 5.0) : window_s_(window_s) {}
  void Sample(const CaptureTally& tally, double wall_s);
  // By sensor; a tag seen in fewer than two samples is missing.
  std::map<int, double> RatesHz() const;

 private:
  double window_s_;
  std::vector<std::pair<double, std::map<int, int64_t>>> samples_;  // oldest first
};

// One row of the live view and of the final table.
struct TagLiveRow {
  int sensor = 0;
  FrameCounts counts;
  double rate_hz = 0.0;  // Fresh packets per second of wall time, recent; < 0: unknown yet.
  // Per angle (yaw, pitch, roll): evaluated (enough fresh rows), the mean over the settled
  // window and its u_mean (docs/type-a.md; not available for a constant series).
  bool evaluated[3] = {false, false, false};
  bool u_available[3] = {false, false, false};
  double mean_deg[3] = {0, 0, 0};
  double u_deg[3] = {0, 0, 0};
  int64_t n = 0;  // Observations in the settled window (the smallest of the three).
  // "settling" (transient still running, or too few rows), "settled at t = 12.3 s", or
  // "no transient" ("" for a tag without fresh rows).
  std::string settle;
};

// The rows for `tally` with --settle auto (DetectSettleTransient) and the Type A u_mean of
// what remains, from EvaluateSessionTypeA (one thread). `rate_hz` by sensor (missing: -1).
std::vector<TagLiveRow> LiveRows(const CaptureTally& tally, const std::map<int, double>& rate_hz);

// The per-tag table, tags that never delivered a packet first. `color`: those rows in red
// (ANSI), for a terminal.
std::string FormatLiveTable(const std::vector<TagLiveRow>& rows, bool color);
// One plain line per tag, "capture t = 20 s: sensor 3: ...", for a log (not a terminal).
std::string FormatSummaryLines(const std::vector<TagLiveRow>& rows, double elapsed_s);

struct CaptureOptions {
  std::string port;
  int baud = 230400;
  double duration_s = 0.0;  // 0: until stopped.
  std::string output;
  bool force = false;  // Replace an existing output file.
  bool reconnect = true;
  double frame_period_s = kReceiverFramePeriodS;
  double flush_interval_s = 1.0;       // At most this long between flushes to disk, (0, 1].
  double reconnect_interval_s = 0.25;  // Between attempts to reopen a lost port.
  std::string version;                 // "metro 0.1.0", for the header.
  // Set (by a signal handler) to end the capture cleanly. Not owned; may be null.
  const volatile std::sig_atomic_t* stop = nullptr;

  bool IsValid(std::string* why) const;
};

// What RunCapture reports. The defaults read as failure.
struct CaptureSummary {
  bool ok = false;
  bool input_error = true;  // The port or the output could not be opened (exit 2).
  std::string message;
  int64_t receiver_lines = 0;  // Written to the body.
  int64_t cut_lines = 0;       // First lines dropped after an open (port opened mid-line).
  int64_t other_lines = 0;     // Not receiver lines: written as `#` comments.
  int64_t bytes_read = 0;
  int64_t port_lost = 0;  // Times the port disappeared.
  int64_t reopened = 0;   // Times it was reopened.
  double elapsed_s = 0.0;
  bool stopped = false;  // Ended by options.stop.
  std::map<int, FrameCounts> counts;
};

// Called about every 100 ms while capturing (and once at the end) with the tally and the
// seconds since the start; and with one line for each event (port lost, reopened).
struct CaptureObserver {
  std::function<void(const CaptureTally& tally, double elapsed_s)> on_tick;
  std::function<void(const std::string& event)> on_event;
};

// Opens the port (SerialPort: raw 8N1, exclusive lock), creates the output (never replacing
// a file unless options.force), and captures until options.duration_s, options.stop, or the
// port is lost without options.reconnect. `tally` (not owned, may be null) receives every
// receiver line. A missing, busy or non-serial port and an existing or uncreatable output
// are input errors; a write that fails ends the capture with !ok.
CaptureSummary RunCapture(const CaptureOptions& options, const CaptureObserver& observer,
                          CaptureTally* tally);

}  // namespace metro::capture
