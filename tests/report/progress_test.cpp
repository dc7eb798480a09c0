// The progress bar: its line format, and silence when stderr is not a terminal.
#include "metro/core/progress.hpp"

#include <algorithm>
#include <catch2/catch.hpp>
#include <chrono>
#include <cstdio>
#include <functional>
#include <string>
#include <thread>
#include <vector>

namespace metro {
namespace {

// Drawn whatever the stream, every time it is asked.
ProgressOptions AlwaysDrawn(double min_redraw_s = 0.0) {
  ProgressOptions o;
  o.mode = ProgressMode::kAlways;
  o.min_redraw_s = min_redraw_s;
  return o;
}

// What `draw` writes to a temporary stream (its progress objects end inside it).
std::string Drawn(const std::function<void(std::FILE*)>& draw) {
  std::FILE* f = std::tmpfile();
  REQUIRE(f != nullptr);
  draw(f);
  std::rewind(f);
  std::string out;
  char buf[256];
  size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) out.append(buf, n);
  std::fclose(f);
  return out;
}

// Runs `work` on `threads` threads at once.
void OnThreads(int threads, const std::function<void()>& work) {
  std::vector<std::thread> pool;
  for (int t = 0; t < threads; ++t) pool.emplace_back(work);
  for (std::thread& t : pool) t.join();
}

TEST_CASE("Progress line shows the bar the count and the percentage", "[report][progress]") {
  CHECK(FormatProgressLine("batch", 2, 4, 1.25, 10) ==
        "batch [#####.....] 2/4  50 %  1.2 s  2/s  1 s left");
  CHECK(FormatProgressLine("batch", 4, 4, 3.0, 4) == "batch [####] 4/4 100 %  3.0 s  1/s");
  CHECK(FormatProgressLine("batch", 0, 3, 0.0, 3) == "batch [...] 0/3   0 %  0.0 s");
  // More than the total is drawn as full; an unknown total has no bar.
  CHECK(FormatProgressLine("x", 9, 3, 0.0, 3) == "x [###] 9/3 100 %  0.0 s");
  CHECK(FormatProgressLine("rows", 17, 0, 2.0, 10) == "rows 17  2.0 s  8/s");
}

TEST_CASE("Progress bar is quiet when the stream is not a terminal", "[report][progress]") {
  const std::string text = Drawn([](std::FILE* f) {
    CHECK_FALSE(IsTerminal(f));
    ProgressBar bar("batch", 3, f);
    CHECK_FALSE(bar.enabled());
    bar.Advance();
    bar.Advance(2);
    CHECK(bar.done() == 3);
  });
  CHECK(text.empty());
}

TEST_CASE("Progress bar forced on ends with the final count", "[report][progress]") {
  const std::string text = Drawn([](std::FILE* f) {
    ProgressBar bar("work", 40, f, AlwaysDrawn());
    OnThreads(4, [&bar] {
      for (int i = 0; i < 10; ++i) bar.Advance();
    });
    bar.Finish();
    bar.Finish();  // Once only.
  });
  CHECK(text.find("work [") == 1);  // After the first "\r".
  CHECK(text.find("40/40 100 %") != std::string::npos);
  CHECK(text.back() == '\n');
  CHECK(std::count(text.begin(), text.end(), '\n') == 1);
}

TEST_CASE("Elapsed ticker is quiet when the stream is not a terminal", "[report][progress]") {
  const std::string text = Drawn([](std::FILE* f) {
    ProgressOptions o;
    o.min_redraw_s = 0.0;
    ElapsedTicker ticker("analyse big.csv", f, o);
    CHECK_FALSE(ticker.enabled());
    ticker.SetLabel("budget");
    std::this_thread::sleep_for(std::chrono::milliseconds(120));
  });
  CHECK(text.empty());
}

TEST_CASE("Elapsed ticker forced on redraws until finished", "[report][progress]") {
  CHECK(FormatElapsedLine("load", 2.25) == "load ...  2.2 s");
  const std::string text = Drawn([](std::FILE* f) {
    ElapsedTicker ticker("load", f, AlwaysDrawn(0.05));
    CHECK(ticker.enabled());
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    ticker.SetLabel("evaluate");
    ticker.Finish();
    ticker.Finish();  // Once only.
  });
  CHECK(text.find("\rload ...  0.") == 0);
  // Redrawn by the thread while running: several "\r" lines before the last one.
  CHECK(std::count(text.begin(), text.end(), '\r') >= 4);
  CHECK(text.find("\revaluate ...  0.") != std::string::npos);
  CHECK(text.back() == '\n');
  CHECK(std::count(text.begin(), text.end(), '\n') == 1);
}

TEST_CASE("Progress line shows counts in units", "[report][progress]") {
  CHECK(FormatProgressLine("load a.csv", 12345678, 388672119, 0.5, 4, "MB", 1e6) ==
        "load a.csv [....] 12.3/388.7 MB   3 %  0.5 s  24.7 MB/s  15 s left");
  CHECK(FormatProgressLine("Monte Carlo", 500000, 1000000, 1.0, 2, "trials") ==
        "Monte Carlo [#.] 500000/1000000 trials  50 %  1.0 s  500000 trials/s  1 s left");
  CHECK(FormatProgressLine("Monte Carlo", 70000, 0, 2.0, 2, "trials") ==
        "Monte Carlo 70000 trials  2.0 s  35000 trials/s");
}

TEST_CASE("Quick work under the delay leaves no line", "[report][progress]") {
  const std::string text = Drawn([](std::FILE* f) {
    ProgressOptions o = AlwaysDrawn();
    o.delay_s = 60.0;
    ProgressBar bar("quick", 10, f, o);
    bar.Advance(10);
    ElapsedTicker ticker("quick too", f, o);
  });
  CHECK(text.empty());
}

TEST_CASE("Terminal progress draws one line per phase", "[report][progress]") {
  const std::string text = Drawn([](std::FILE* f) {
    TerminalProgress progress(f, AlwaysDrawn());
    progress.BeginPhase("load x.csv", 2000000, "MB", 1e6);
    OnThreads(2, [&progress] {
      for (int i = 0; i < 10; ++i) progress.Advance(100000);
    });
    progress.BeginPhase("Type A", kUncountedWork);
    progress.BeginPhase("Monte Carlo", 0, "trials");
    progress.Advance(70000);
  });  // The destructor ends the last line.
  CHECK(std::count(text.begin(), text.end(), '\n') == 3);
  CHECK(text.find("\rload x.csv [##############################] 2.0/2.0 MB 100 %") !=
        std::string::npos);
  CHECK(text.find("\rType A ...") != std::string::npos);
  CHECK(text.find("\rMonte Carlo 70000 trials") != std::string::npos);
  CHECK(text.back() == '\n');
}

TEST_CASE("Progress options are validated", "[report][progress]") {
  std::string why;
  CHECK(ProgressOptions{}.IsValid(&why));
  // Each bad value alone is refused with a message naming it.
  auto refused = [](const std::function<void(ProgressOptions*)>& spoil) {
    ProgressOptions o;
    spoil(&o);
    std::string message;
    CHECK_FALSE(o.IsValid(&message));
    return message;
  };
  CHECK(refused([](ProgressOptions* o) { o->bar_width = 0; }) ==
        "progress: bar_width must be in [1, 200]");
  CHECK(refused([](ProgressOptions* o) { o->min_redraw_s = -1.0; }) ==
        "progress: min_redraw_s must be >= 0");
  CHECK(refused([](ProgressOptions* o) { o->unit_divisor = 0.0; }) ==
        "progress: unit_divisor must be finite and > 0");
  CHECK(refused([](ProgressOptions* o) { o->delay_s = -0.1; }) == "progress: delay_s must be >= 0");
}

}  // namespace
}  // namespace metro
