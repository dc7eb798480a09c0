// RunCapture opens the port and the output, then runs a CaptureRun through these stages:
//
//   loop     Loop: ReadOnce, Reconnect,   read until the duration ends or a stop; lines
//            Sort                         sorted, written and counted; a lost port reopened
//                                         every reconnect_interval_s; flushes and ticks
//   finish   Finish                       the drain of what already arrived, the trailer
//                                         with the counts, the summary's verdict
#include "metro/capture/capture.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <poll.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <ctime>
#include <memory>

#include "metro/core/angles.hpp"
#include "metro/core/terminal_text.hpp"
#include "metro/core/utc_time.hpp"
#include "metro/serial/serial_port.hpp"
#include "metro/stats/session_type_a.hpp"

namespace metro::capture {
namespace {

using Clock = std::chrono::steady_clock;

double SecondsSince(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// A line that is not data, shown in a `#` comment: control bytes as \xNN, at most 200 bytes.
std::string Printable(std::string_view line) {
  while (!line.empty() && (line.back() == '\n' || line.back() == '\r')) line.remove_suffix(1);
  std::string out;
  for (size_t i = 0; i < line.size() && i < 200; ++i) {
    const unsigned char c = static_cast<unsigned char>(line[i]);
    if (c >= 0x20 && c < 0x7F) {
      out += static_cast<char>(c);
    } else {
      out += fmt::format("\\x{:02x}", c);
    }
  }
  if (line.size() > 200) out += fmt::format("... ({} bytes)", line.size());
  return out;
}

// The output file: whole lines appended to a buffer, written and fdatasync'ed by Flush.
class Output {
 public:
  ~Output() {
    if (fd_ >= 0) ::close(fd_);
  }
  Status Open(const std::string& path, bool force) {
    path_ = path;
    // A device is refused before it is opened (opening a serial port moves its lines).
    if (struct stat before{}; ::stat(path.c_str(), &before) == 0 && !S_ISREG(before.st_mode)) {
      return NotRegular(KindOf(before.st_mode));
    }
    // Non-blocking, so a FIFO without a reader fails instead of waiting; nothing is truncated
    // before the file is known to be a regular file (never a device, a FIFO, the port).
    const int flags = O_WRONLY | O_CREAT | O_CLOEXEC | O_NOCTTY | O_NONBLOCK | (force ? 0 : O_EXCL);
    fd_ = ::open(path.c_str(), flags, 0644);
    if (fd_ < 0) {
      if (errno == EEXIST) {
        return MakeError(path, 0,
                         "exists: a capture is never replaced; pass --force to replace it");
      }
      if (errno == ENXIO) return NotRegular("is a FIFO (named pipe)");
      return MakeError(path, 0, fmt::format("cannot create: {}", std::strerror(errno)));
    }
    struct stat st {};
    if (::fstat(fd_, &st) != 0) {
      return MakeError(path, 0, fmt::format("cannot stat: {}", std::strerror(errno)));
    }
    if (!S_ISREG(st.st_mode)) {
      return NotRegular(KindOf(st.st_mode));
    }
    const int fl = ::fcntl(fd_, F_GETFL);
    if (fl >= 0) ::fcntl(fd_, F_SETFL, fl & ~O_NONBLOCK);
    if (force && ::ftruncate(fd_, 0) != 0) {
      return MakeError(path, 0, fmt::format("cannot truncate: {}", std::strerror(errno)));
    }
    return Status::Ok();
  }
  void Append(std::string_view text) { buf_.append(text.data(), text.size()); }
  Status Flush() {
    size_t done = 0;
    while (done < buf_.size()) {
      const ssize_t n = ::write(fd_, buf_.data() + done, buf_.size() - done);
      if (n < 0 && errno == EINTR) continue;
      if (n < 0) return MakeIoError(path_, 0, fmt::format("write: {}", std::strerror(errno)));
      done += static_cast<size_t>(n);
    }
    buf_.clear();
    if (::fdatasync(fd_) != 0 && errno != EINVAL && errno != EROFS) {
      return MakeIoError(path_, 0, fmt::format("fdatasync: {}", std::strerror(errno)));
    }
    return Status::Ok();
  }
  size_t buffered() const { return buf_.size(); }

 private:
  static const char* KindOf(mode_t mode) {
    return S_ISDIR(mode)    ? "is a directory"
           : S_ISCHR(mode)  ? "is a character device"
           : S_ISBLK(mode)  ? "is a block device"
           : S_ISFIFO(mode) ? "is a FIFO (named pipe)"
           : S_ISSOCK(mode) ? "is a socket"
                            : "is not a regular file";
  }
  Status NotRegular(const char* what) {
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
    return MakeError(
        fmt::format("{} {}: a capture is written to a regular file; name one", path_, what));
  }

  std::string path_;
  int fd_ = -1;
  std::string buf_;
};

// Sleeps up to `ms`, returning early when *stop is set (checked every 10 ms).
void SleepUnlessStopped(int ms, const volatile std::sig_atomic_t* stop) {
  for (int left = ms; left > 0 && !(stop != nullptr && *stop != 0); left -= 10) {
    ::poll(nullptr, 0, std::min(left, 10));
  }
}

}  // namespace

void LineSorter::Emit(const Sink& sink) {
  std::string_view line(pending_);
  std::string_view body = line;
  if (!body.empty() && body.back() == '\n') body.remove_suffix(1);
  if (!body.empty() && body.back() == '\r') body.remove_suffix(1);
  ReceiverLine decoded;
  ReceiverLineProblem problem;
  const bool ok = line.back() == '\n' && DecodeReceiverLine(body, &decoded, &problem);
  const bool first = first_;
  first_ = false;
  if (ok) {
    sink(Kind::kReceiver, line, decoded, "");
  } else if (first && body.size() < static_cast<size_t>(kReceiverLineHexChars) &&
             std::all_of(body.begin(), body.end(),
                         [](char c) { return std::isxdigit(static_cast<unsigned char>(c)); })) {
    sink(Kind::kCut, line, decoded, "the tail of a receiver line (the port opened mid-line)");
  } else {
    sink(Kind::kOther, line, decoded,
         line.back() == '\n' ? problem.message
                             : fmt::format("{} bytes without a line end", line.size()));
  }
  pending_.clear();
}

void LineSorter::Feed(const uint8_t* data, size_t size, const Sink& sink) {
  for (size_t i = 0; i < size; ++i) {
    pending_ += static_cast<char>(data[i]);
    if (data[i] == '\n' || pending_.size() >= kMaxLineBytes) Emit(sink);
  }
}

void CaptureTally::Add(const ReceiverLine& line) {
  if (line.sensor <= previous_sensor_) ++frame_;
  previous_sensor_ = line.sensor;
  TagSeries& t = tags_[line.sensor];
  t.sensor = line.sensor;
  ++t.counts.frames;
  if (line.flag == NewDataFlag::kStale) {
    ++t.counts.stale;
  } else if (line.flag == NewDataFlag::kNever) {
    ++t.counts.never;
  } else {
    ++t.counts.fresh;
    const EulerDeg e = EulerFromQuaternion(line.q);
    t.t_s.push_back(static_cast<double>(frame_) * frame_period_s_);
    t.yaw_deg.push_back(e.yaw_deg);
    t.pitch_deg.push_back(e.pitch_deg);
    t.roll_deg.push_back(e.roll_deg);
  }
}

Session CaptureTally::ToSession() const {
  Session s;
  s.format = SessionFormat::kReceiver;
  s.frame_period_s = frame_period_s_;
  for (const auto& [sensor, series] : tags_) {
    Tag tag;
    tag.sensor = sensor;
    tag.counts = series.counts;
    tag.t_s = series.t_s;
    tag.line.assign(series.t_s.size(), 0);
    if (!series.t_s.empty()) {
      tag.quantities.push_back(
          Quantity{"yaw_deg", "deg", QuantityOrigin::kDerived, series.yaw_deg});
      tag.quantities.push_back(
          Quantity{"pitch_deg", "deg", QuantityOrigin::kDerived, series.pitch_deg});
      tag.quantities.push_back(
          Quantity{"roll_deg", "deg", QuantityOrigin::kDerived, series.roll_deg});
    }
    s.tags.push_back(std::move(tag));
  }
  return s;
}

void FreshRates::Sample(const CaptureTally& tally, double wall_s) {
  std::map<int, int64_t> fresh;
  for (const auto& [sensor, series] : tally.tags()) fresh[sensor] = series.counts.fresh;
  samples_.emplace_back(wall_s, std::move(fresh));
  // Keep the newest sample at or before wall_s - window_s, and everything after it.
  while (samples_.size() > 2 && samples_[1].first <= wall_s - window_s_) {
    samples_.erase(samples_.begin());
  }
}

std::map<int, double> FreshRates::RatesHz() const {
  std::map<int, double> out;
  if (samples_.size() < 2) return out;
  const auto& [t1, last] = samples_.back();
  for (const auto& [sensor, n1] : last) {
    for (const auto& [t0, first] : samples_) {
      auto it = first.find(sensor);
      if (it == first.end() || t1 - t0 <= 0.0) continue;
      out[sensor] = static_cast<double>(n1 - it->second) / (t1 - t0);
      break;
    }
  }
  return out;
}

std::vector<TagLiveRow> LiveRows(const CaptureTally& tally, const std::map<int, double>& rate_hz) {
  std::vector<TagLiveRow> rows;
  const Session session = tally.ToSession();
  SessionTypeAOptions o;
  o.window.settle_auto = true;
  o.threads = 1;
  // Only tags with at least two fresh rows can be evaluated.
  for (const Tag& tag : session.tags) {
    if (tag.size() >= 2) o.sensors.push_back(tag.sensor);
  }
  std::map<int, const TagTypeA*> evaluated;
  Result<SessionTypeA> type_a = SessionTypeA{};
  if (!o.sensors.empty()) type_a = EvaluateSessionTypeA(session, o);
  if (type_a.ok()) {
    for (const TagTypeA& t : type_a.value().tags) evaluated[t.sensor] = &t;
  }
  for (const Tag& tag : session.tags) {
    TagLiveRow r;
    r.sensor = tag.sensor;
    r.counts = tag.counts;
    auto rate = rate_hz.find(tag.sensor);
    r.rate_hz = rate == rate_hz.end() ? -1.0 : rate->second;
    auto it = evaluated.find(tag.sensor);
    if (it != evaluated.end()) {
      const TagTypeA& t = *it->second;
      r.n = INT64_MAX;
      for (const QuantityTypeA& q : t.quantities) {
        const int a = q.name == "yaw_deg" ? 0 : q.name == "pitch_deg" ? 1 : 2;
        if (!q.ok) continue;
        r.evaluated[a] = true;
        r.u_available[a] = q.type_a.u_mean_available;
        r.mean_deg[a] = q.type_a.mean;
        r.u_deg[a] = q.type_a.u_mean;
        r.n = std::min(r.n, q.type_a.n);
      }
      if (r.n == INT64_MAX) r.n = 0;
      if (tag.size() < 20) {
        r.settle = "settling";
      } else if (t.window.settle_at_limit || t.window.settle_samples >= tag.size()) {
        r.settle = "settling";
      } else if (t.window.settle_samples == 0) {
        r.settle = "no transient";
      } else {
        r.settle = fmt::format("settled at t = {:.1f} s", tag.t_s[t.window.settle_samples]);
      }
    } else if (tag.size() > 0) {
      r.settle = "settling";
    }
    rows.push_back(std::move(r));
  }
  return rows;
}

namespace {

bool NeverDelivered(const TagLiveRow& r) { return r.counts.fresh == 0; }

std::string RateText(const TagLiveRow& r) {
  return r.rate_hz < 0.0 ? std::string("-") : fmt::format("{:.1f}", r.rate_hz);
}

std::string AngleText(const TagLiveRow& r, int a) {
  if (!r.evaluated[a]) return "-";
  if (!r.u_available[a]) return fmt::format("{:.3f} (constant)", r.mean_deg[a]);
  return fmt::format("{:.3f} +- {:.3f}", r.mean_deg[a], r.u_deg[a]);
}

}  // namespace

std::string FormatLiveTable(const std::vector<TagLiveRow>& rows, bool color) {
  std::vector<const TagLiveRow*> order;
  for (const TagLiveRow& r : rows) order.push_back(&r);
  std::stable_sort(order.begin(), order.end(), [](const TagLiveRow* a, const TagLiveRow* b) {
    return NeverDelivered(*a) && !NeverDelivered(*b);
  });
  std::string out = fmt::format("{:>6} {:>7} {:>8} {:>7} {:>7} {:>6} {:>22} {:>22} {:>22}  {}\n",
                                "sensor", "rate_hz", "fresh", "stale", "never", "loss_%",
                                "yaw_deg (mean +- u)", "pitch_deg", "roll_deg", "settle");
  for (const TagLiveRow* r : order) {
    const bool red = color && NeverDelivered(*r);
    out += fmt::format("{}{:>6} {:>7} {:>8} {:>7} {:>7} {:>6.1f} {:>22} {:>22} {:>22}  {}{}\n",
                       red ? "\x1b[31m" : "", r->sensor, RateText(*r), r->counts.fresh,
                       r->counts.stale, r->counts.never, 100.0 * r->counts.PacketLossRatio(),
                       AngleText(*r, 0), AngleText(*r, 1), AngleText(*r, 2),
                       NeverDelivered(*r) ? "never delivered a packet" : r->settle,
                       red ? "\x1b[0m" : "");
  }
  return out;
}

std::string FormatSummaryLines(const std::vector<TagLiveRow>& rows, double elapsed_s) {
  std::string out;
  for (const TagLiveRow& r : rows) {
    out += fmt::format(
        "capture t = {:.0f} s: sensor {}: rate {} Hz, fresh {}, stale {}, never {}, loss "
        "{:.1f} %, yaw {} deg, pitch {} deg, roll {} deg, {}\n",
        elapsed_s, r.sensor, RateText(r), r.counts.fresh, r.counts.stale, r.counts.never,
        100.0 * r.counts.PacketLossRatio(), AngleText(r, 0), AngleText(r, 1), AngleText(r, 2),
        NeverDelivered(r) ? "never delivered a packet" : r.settle);
  }
  return out;
}

bool CaptureOptions::IsValid(std::string* why) const {
  auto fail = [&](std::string m) {
    if (why) *why = std::move(m);
    return false;
  };
  if (port.empty()) return fail("no port given (--port)");
  if (output.empty()) return fail("no output file given");
  if (!(duration_s >= 0.0 && std::isfinite(duration_s))) return fail("--duration-s must be >= 0");
  if (!(frame_period_s > 0.0 && frame_period_s <= 60.0)) {
    return fail("frame_period_s must be in (0, 60] s");
  }
  if (!(flush_interval_s > 0.0 && flush_interval_s <= 1.0)) {
    return fail("flush_interval_s must be in (0, 1] s");
  }
  if (!(reconnect_interval_s > 0.0 && reconnect_interval_s <= 10.0)) {
    return fail("reconnect_interval_s must be in (0, 10] s");
  }
  return true;
}

namespace {

// ---- RunCapture's stages ------------------------------------------------------------------

// One capture from an opened port into an opened output: the read loop, its reconnects,
// flushes and ticks, the drain at the end and the trailer. The summary collects the counts.
class CaptureRun {
 public:
  CaptureRun(const CaptureOptions& options, const CaptureObserver& observer, CaptureTally* tally,
             std::unique_ptr<serial::SerialPort> port, CaptureSummary* sum)
      : options_(options), observer_(observer), tally_(tally), port_(std::move(port)), sum_(*sum) {
    sink_ = [this](LineSorter::Kind kind, std::string_view line, const ReceiverLine& decoded,
                   const std::string& what) { Sort(kind, line, decoded, what); };
  }

  Output& out() { return out_; }

  // The header comment, then lines until the duration ends, a stop or the port is lost for
  // good (or a write fails).
  void Loop() {
    t0_ = Clock::now();
    out_.Append(fmt::format(
        "# metro capture of the central receiver (docs/capture.md)\n# port: {}\n# baud: {}\n"
        "# start_utc: {}\n# version: {}\n",
        EscapeControlChars(options_.port), options_.baud, UtcIso8601Now(), options_.version));
    last_flush_ = last_tick_ = last_attempt_ = t0_;
    const auto flush_every = std::chrono::duration<double>(options_.flush_interval_s);
    for (;;) {
      const double elapsed = SecondsSince(t0_);
      if (options_.stop != nullptr && *options_.stop != 0) {
        sum_.stopped = true;
        break;
      }
      if (options_.duration_s > 0.0 && elapsed >= options_.duration_s) break;
      int wait_ms = 100;
      if (options_.duration_s > 0.0) {
        wait_ms = std::clamp(static_cast<int>(std::ceil((options_.duration_s - elapsed) * 1000.0)),
                             1, 100);
      }
      if (port_) {
        if (!ReadOnce(wait_ms)) break;
      } else {
        Reconnect(wait_ms);
      }
      const Clock::time_point now = Clock::now();
      if (now - last_flush_ >= flush_every || out_.buffered() >= (size_t{1} << 20)) {
        Flush();
        last_flush_ = now;
        if (!write_status_.ok()) break;
      }
      if (now - last_tick_ >= std::chrono::milliseconds(100)) {
        last_tick_ = now;
        if (observer_.on_tick && tally_ != nullptr) observer_.on_tick(*tally_, SecondsSince(t0_));
      }
    }
  }

  // Whatever already arrived is kept: read until the port is quiet (bounded); then the
  // trailer with the counts, and the summary's verdict.
  void Finish() {
    if (port_ && write_status_.ok()) {
      for (int i = 0; i < 50; ++i) {
        Result<size_t> got = port_->Read(buf_.data(), buf_.size(), 20);
        if (!got.ok() || got.value() == 0) break;
        sum_.bytes_read += static_cast<int64_t>(got.value());
        sorter_.Feed(buf_.data(), got.value(), sink_);
      }
    }
    sum_.elapsed_s = SecondsSince(t0_);
    out_.Append(
        fmt::format("# end_utc: {}\n# receiver_lines: {}, cut_first_lines: {}, other_lines: {}, "
                    "unfinished_line_bytes: {}, port_lost: {}, reopened: {}\n",
                    UtcIso8601Now(), sum_.receiver_lines, sum_.cut_lines, sum_.other_lines,
                    sorter_.pending_bytes(), sum_.port_lost, sum_.reopened));
    for (const auto& [sensor, c] : sum_.counts) {
      out_.Append(fmt::format("# sensor {}: frames {}, fresh {}, stale {}, never {}\n", sensor,
                              c.frames, c.fresh, c.stale, c.never));
    }
    Flush();
    if (observer_.on_tick && tally_ != nullptr) observer_.on_tick(*tally_, sum_.elapsed_s);
    if (!write_status_.ok()) {
      sum_.message = write_status_.error().ToString();
      return;
    }
    if (lost_for_good_) {
      sum_.message = fmt::format(
          "{}: the port disappeared after {:.1f} s and --no-reconnect was given; {} kept {} lines",
          options_.port, sum_.elapsed_s, options_.output, sum_.receiver_lines);
      return;
    }
    sum_.ok = true;
    sum_.message = fmt::format("{}: {} receiver lines in {:.1f} s", options_.output,
                               sum_.receiver_lines, sum_.elapsed_s);
  }

 private:
  void Event(const std::string& text) {
    if (observer_.on_event) observer_.on_event(text);
  }
  void Flush() {
    if (write_status_.ok()) write_status_ = out_.Flush();
  }

  // A sorted line: a receiver line written and counted, a cut first line counted, anything
  // else written as a comment.
  void Sort(LineSorter::Kind kind, std::string_view line, const ReceiverLine& decoded,
            const std::string& what) {
    switch (kind) {
      case LineSorter::Kind::kReceiver:
        out_.Append(line);
        ++sum_.receiver_lines;
        ++sum_.counts[decoded.sensor].frames;
        if (decoded.flag == NewDataFlag::kFresh) ++sum_.counts[decoded.sensor].fresh;
        if (decoded.flag == NewDataFlag::kStale) ++sum_.counts[decoded.sensor].stale;
        if (decoded.flag == NewDataFlag::kNever) ++sum_.counts[decoded.sensor].never;
        if (tally_ != nullptr) tally_->Add(decoded);
        break;
      case LineSorter::Kind::kCut:
        ++sum_.cut_lines;
        break;
      case LineSorter::Kind::kOther:
        ++sum_.other_lines;
        out_.Append(fmt::format("# not a receiver line ({}): {}\n", what, Printable(line)));
        break;
    }
  }

  // One read of at most wait_ms; false when the port was lost and reconnecting is off.
  bool ReadOnce(int wait_ms) {
    Result<size_t> got = port_->Read(buf_.data(), buf_.size(), wait_ms);
    if (got.ok()) {
      sum_.bytes_read += static_cast<int64_t>(got.value());
      sorter_.Feed(buf_.data(), got.value(), sink_);
      return true;
    }
    ++sum_.port_lost;
    port_.reset();
    const size_t partial = sorter_.pending_bytes();
    sorter_.Restart();
    out_.Append(fmt::format("# port lost at {}: {}{}\n", UtcIso8601Now(),
                            EscapeControlChars(got.error().message),
                            partial > 0 ? fmt::format(" ({} bytes of an unfinished line "
                                                      "dropped)",
                                                      partial)
                                        : ""));
    Flush();
    last_flush_ = Clock::now();
    Event(fmt::format("{}: the port disappeared ({}); kept the {} lines captured{}", options_.port,
                      got.error().message, sum_.receiver_lines,
                      options_.reconnect ? "; waiting for it to return" : ""));
    if (!options_.reconnect) {
      lost_for_good_ = true;
      return false;
    }
    last_attempt_ = Clock::now();
    return true;
  }

  // Without a port: wait, and every reconnect_interval_s try to open it again.
  void Reconnect(int wait_ms) {
    SleepUnlessStopped(std::min(wait_ms, 50), options_.stop);
    if (SecondsSince(last_attempt_) >= options_.reconnect_interval_s) {
      last_attempt_ = Clock::now();
      Result<std::unique_ptr<serial::SerialPort>> again =
          serial::SerialPort::Open(options_.port, options_.baud);
      if (again.ok()) {
        port_ = std::move(again).value();
        ++sum_.reopened;
        out_.Append(fmt::format("# port reopened at {}\n", UtcIso8601Now()));
        Event(fmt::format("{}: the port is back; capturing again", options_.port));
      }
    }
  }

  const CaptureOptions& options_;
  const CaptureObserver& observer_;
  CaptureTally* tally_;
  std::unique_ptr<serial::SerialPort> port_;
  CaptureSummary& sum_;
  Output out_;
  LineSorter sorter_;
  LineSorter::Sink sink_;
  Status write_status_ = Status::Ok();
  std::vector<uint8_t> buf_ = std::vector<uint8_t>(8192);
  Clock::time_point t0_, last_flush_, last_tick_, last_attempt_;
  bool lost_for_good_ = false;
};

}  // namespace

CaptureSummary RunCapture(const CaptureOptions& options, const CaptureObserver& observer,
                          CaptureTally* tally) {
  CaptureSummary sum;
  std::string why;
  if (!options.IsValid(&why)) {
    sum.message = why;
    return sum;
  }
  Result<std::unique_ptr<serial::SerialPort>> opened =
      serial::SerialPort::Open(options.port, options.baud);
  if (!opened.ok()) {
    sum.message = opened.error().ToString();
    return sum;
  }
  CaptureRun run(options, observer, tally, std::move(opened).value(), &sum);
  if (Status s = run.out().Open(options.output, options.force); !s.ok()) {
    sum.message = s.error().ToString();
    return sum;
  }
  sum.input_error = false;
  run.Loop();
  run.Finish();
  return sum;
}

}  // namespace metro::capture
