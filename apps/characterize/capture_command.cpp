// characterize capture --port DEV [--baud 230400] [--duration-s S] -o capture.txt [--force]
//   [--reconnect|--no-reconnect] [--analyze -o REPORT.json --capture capture.txt] [--tags FILE]
// Records the central receiver's serial stream (docs/capture.md).
#include "capture_command.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "analysis_options.hpp"
#include "metro/capture/capture.hpp"
#include "metro/core/version.hpp"
#include "metro/io/tag_registry.hpp"
#include "metro/report/session_analysis.hpp"
#include "unix_cli.hpp"

namespace metro::apps {
namespace {

volatile std::sig_atomic_t g_capture_stop = 0;
void OnCaptureSignal(int) { g_capture_stop = 1; }

// "names (tags.json): 1 Forehead, 2 Chest" for the sensors of `rows`, or "" without a tags
// file. The capture's table keeps its columns; the names go below it.
std::string NamesFooter(const std::vector<capture::TagLiveRow>& rows, const TagRegistry* tags,
                        const std::string& tags_path) {
  if (tags == nullptr || rows.empty()) return "";
  std::vector<int> sensors;
  for (const capture::TagLiveRow& r : rows) sensors.push_back(r.sensor);
  std::sort(sensors.begin(), sensors.end());
  // One line: the names and the file name are data (escaped).
  std::string out = fmt::format("names ({}):", EscapeControlChars(tags_path));
  for (size_t i = 0; i < sensors.size(); ++i) {
    out += fmt::format("{} {} {}", i == 0 ? "" : ",", sensors[i],
                       EscapeControlChars(tags->Name(sensors[i])));
  }
  return out + "\n";
}

// The live view (a terminal) or a plain summary every 10 s (a log), on stderr. Counts and
// rates are fresh on every drawing; the settle and Type A statistics are recomputed when
// their last computation took less than 5 % of the time since (a long capture's series
// grow, so they are redone less often rather than costing more of the core).
class LiveView {
 public:
  LiveView(const TagRegistry* tags, std::string tags_path)
      : terminal_(::isatty(STDERR_FILENO) == 1 && !Quiet()),
        tags_(tags),
        tags_path_(std::move(tags_path)) {}
  void Tick(const capture::CaptureTally& tally, double elapsed_s) {
    rates_.Sample(tally, elapsed_s);
    if (Quiet()) return;
    const double every_s = terminal_ ? 0.5 : 10.0;
    if (elapsed_s - last_draw_s_ < every_s) return;
    last_draw_s_ = elapsed_s;
    const std::vector<capture::TagLiveRow>& rows = Rows(tally, elapsed_s);
    if (!terminal_) {
      PrintText(stderr, capture::FormatSummaryLines(rows, elapsed_s) +
                            NamesFooter(rows, tags_, tags_path_));
      std::fflush(stderr);
      return;
    }
    const std::string table =
        fmt::format("capture {:.0f} s, {} frames\n", elapsed_s, tally.frames()) +
        capture::FormatLiveTable(rows, true) + NamesFooter(rows, tags_, tags_path_);
    std::string out;
    if (drawn_lines_ > 0) out = fmt::format("\x1b[{}A\x1b[J", drawn_lines_);
    out += table;
    drawn_lines_ = static_cast<int>(std::count(table.begin(), table.end(), '\n'));
    std::fwrite(out.data(), 1, out.size(), stderr);
    std::fflush(stderr);
  }
  void Event(const std::string& text) {
    drawn_lines_ = 0;  // The event stays above the next drawing.
    PrintText(stderr, "note: " + EscapeControlChars(text) + "\n");  // One event, one line.
  }
  std::map<int, double> rates() const { return rates_.RatesHz(); }

 private:
  const std::vector<capture::TagLiveRow>& Rows(const capture::CaptureTally& tally,
                                               double elapsed_s) {
    const std::map<int, double> rates = rates_.RatesHz();
    if (elapsed_s >= stats_due_s_ || rows_.size() != tally.tags().size()) {
      const auto t0 = std::chrono::steady_clock::now();
      rows_ = capture::LiveRows(tally, rates);
      const double cost_s =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      stats_due_s_ = elapsed_s + 20.0 * cost_s;
      return rows_;
    }
    for (capture::TagLiveRow& r : rows_) {
      r.counts = tally.tags().at(r.sensor).counts;
      auto it = rates.find(r.sensor);
      r.rate_hz = it == rates.end() ? -1.0 : it->second;
    }
    return rows_;
  }

  bool terminal_;
  const TagRegistry* tags_;  // nullptr: no --tags.
  std::string tags_path_;
  double last_draw_s_ = 0.0;
  double stats_due_s_ = 0.0;
  int drawn_lines_ = 0;
  capture::FreshRates rates_;
  std::vector<capture::TagLiveRow> rows_;
};

// The capture's file: --capture with --analyze (-o then names the report), else -o or
// --capture; checked before the port is opened (docs/unix.md "Outputs never destroy"): a
// regular file (never a device, the port itself, a FIFO), not the tags file, not the report,
// never replaced without --force.
Result<std::string> CapturePath(const CaptureCliOptions& c) {
  const std::string capture_path =
      c.analyze ? c.capture : (c.output.empty() ? c.capture : c.output);
  if (c.analyze && c.capture.empty()) {
    return MakeError("--analyze: name the capture with --capture FILE (-o then names the report)");
  }
  if (!c.analyze && !c.output.empty() && !c.capture.empty()) {
    return MakeError("-o and --capture both name the capture; give one (or add --analyze)");
  }
  if (capture_path.empty() || IsStdio(capture_path)) {
    return MakeError("capture: name the capture file with -o FILE");
  }
  const char* capture_option = !c.analyze && capture_path == c.output ? "-o" : "--capture";
  if (Status s = CheckOutputs(
          {{capture_option, capture_path}, {"-o", c.analyze ? c.output : std::string()}},
          {{"--port", c.port}, {"--tags", c.tags}});
      !s.ok()) {
    return s.error();
  }
  if (OutputExists(capture_path) && !c.force) {
    return MakeError(fmt::format(
        "{}: exists: a capture is never replaced; pass --force to replace it", capture_path));
  }
  return capture_path;
}

// The library's capture options from the flags, checked.
Result<capture::CaptureOptions> MakeCaptureOptions(const CaptureCliOptions& c,
                                                   const std::string& capture_path) {
  capture::CaptureOptions o;
  o.port = c.port;
  o.baud = c.baud;
  o.duration_s = c.duration_s;
  o.output = capture_path;
  o.force = c.force;
  o.reconnect = c.reconnect || (!c.no_reconnect && c.duration_s == 0.0);
  o.frame_period_s = c.frame_period_s;
  o.version = fmt::format("metro characterize {}", kVersion);
  o.stop = &g_capture_stop;
  if (std::string why; !o.IsValid(&why)) return MakeError(why);
  return o;
}

// SIGINT and SIGTERM end the capture (the file is kept, complete to its last line).
void StopCaptureOnSignals() {
  struct sigaction sa {};
  sa.sa_handler = OnCaptureSignal;
  sigemptyset(&sa.sa_mask);
  ::sigaction(SIGINT, &sa, nullptr);
  ::sigaction(SIGTERM, &sa, nullptr);
}

// The summary line and the final per-tag table (not under --quiet).
std::string CaptureNotes(const capture::CaptureSummary& sum) {
  return fmt::format(
      "{}{}{}\n", sum.message,
      sum.cut_lines > 0 ? fmt::format(", {} cut first line(s) dropped", sum.cut_lines) : "",
      sum.other_lines > 0
          ? fmt::format(", {} line(s) that are not receiver lines kept as # comments",
                        sum.other_lines)
          : "");
}

// --analyze: the capture analysed as `analyze --settle auto --tags` would, the report to -o.
int AnalyzeCapture(const CaptureCliOptions& c, const std::string& capture_path) {
  AnalysisCliOptions a;
  a.window.settle_auto = true;
  a.load.library.frame_period_s = c.frame_period_s;
  a.tag_registry = c.tags;  // The report names the tags as `analyze --tags` does.
  SessionAnalysisOptions options;
  if (Status s = MakeSessionAnalysisOptions(a, 0, &options); !s.ok()) {
    return PrintErrorExit(s.error());
  }
  SessionAnalysis analysis = AnalyzeSession(capture_path, options);
  if (!analysis.ok) return PrintErrorExit(analysis.error);
  const std::string json = ToJson(analysis.report) + "\n";
  if (Status s = WriteOutputs({{c.output.empty() ? "-" : c.output, json}}); !s.ok()) {
    return PrintErrorExit(s.error());
  }
  if (!c.output.empty()) PrintTable(analysis.table, c.output);
  return kExitOk;
}

}  // namespace

int RunCaptureCommand(const CaptureCliOptions& c) {
  Result<std::string> capture_path = CapturePath(c);
  if (!capture_path.ok()) return PrintErrorExit(capture_path.error());
  const bool replacing = c.force && OutputExists(capture_path.value());
  Result<capture::CaptureOptions> o = MakeCaptureOptions(c, capture_path.value());
  if (!o.ok()) return PrintErrorExit(o.error());
  // The tags file is read before the port is opened: a bad one records nothing.
  std::optional<TagRegistry> tags;
  if (!c.tags.empty()) {
    Result<TagRegistry> loaded = TagRegistry::Load(c.tags);
    if (!loaded.ok()) return PrintErrorExit(loaded.error());
    tags = std::move(loaded).value();
  }
  const TagRegistry* names = tags ? &*tags : nullptr;
  StopCaptureOnSignals();
  Note(fmt::format("capturing {} at {} baud to {}{}{}; Ctrl-C ends the capture\n", c.port, c.baud,
                   capture_path.value(), replacing ? " (--force: replacing the existing file)" : "",
                   c.duration_s > 0 ? fmt::format(" for {:g} s", c.duration_s) : ""));
  LiveView view(names, c.tags);
  capture::CaptureObserver observer;
  observer.on_tick = [&](const capture::CaptureTally& t, double s) { view.Tick(t, s); };
  observer.on_event = [&](const std::string& e) { view.Event(e); };
  capture::CaptureTally tally(c.frame_period_s);
  const capture::CaptureSummary sum = capture::RunCapture(o.value(), observer, &tally);
  // The capture has ended: a signal now interrupts the report being written (its temporary
  // removed, docs/unix.md).
  InstallInterruptCleanup();
  if (sum.input_error) return PrintErrorExit(MakeError(sum.message));
  if (!Quiet()) {
    const std::vector<capture::TagLiveRow> rows = capture::LiveRows(tally, view.rates());
    PrintText(stdout, capture::FormatLiveTable(rows, false) + NamesFooter(rows, names, c.tags));
    std::fflush(stdout);
  }
  if (!sum.ok) {
    PrintErrorText(sum.message);
    return kExitFailed;
  }
  Note("wrote " + CaptureNotes(sum));
  return c.analyze ? AnalyzeCapture(c, capture_path.value()) : kExitOk;
}

}  // namespace metro::apps
