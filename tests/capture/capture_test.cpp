// The capture's pieces without a port: receiver line decoding, the line sorter (whole lines,
// cut first line, non-receiver lines), the per-tag tally, fresh rates and the live rows.
#include "metro/capture/capture.hpp"

#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "metro/core/angles.hpp"
#include "metro/stats/type_a.hpp"
#include "support/temp_file.hpp"

namespace metro::capture {
namespace {

std::string Line(int sensor, NewDataFlag flag, const EulerDeg& e = {}) {
  ReceiverPayload p{};
  if (flag == NewDataFlag::kFresh) EncodeQuaternion(QuaternionFromEuler(e), &p);
  return FormatReceiverLine(sensor, flag, p);
}

struct Sorted {
  std::vector<LineSorter::Kind> kinds;
  std::vector<std::string> lines;
  std::vector<int> sensors;
  std::vector<std::string> why;
};

Sorted FeedInChunks(LineSorter& sorter, const std::string& bytes, size_t chunk) {
  Sorted s;
  const LineSorter::Sink sink = [&](LineSorter::Kind k, std::string_view line,
                                    const ReceiverLine& d, const std::string& why) {
    s.kinds.push_back(k);
    s.lines.emplace_back(line);
    s.sensors.push_back(k == LineSorter::Kind::kReceiver ? d.sensor : 0);
    s.why.push_back(why);
  };
  for (size_t pos = 0; pos < bytes.size(); pos += chunk) {
    const size_t n = std::min(chunk, bytes.size() - pos);
    sorter.Feed(reinterpret_cast<const uint8_t*>(bytes.data() + pos), n, sink);
  }
  return s;
}

}  // namespace

TEST_CASE("capture: DecodeReceiverLine reads what FormatReceiverLine wrote", "[capture]") {
  const EulerDeg e{30.0, -10.0, 5.0};
  const Quaternion q = QuaternionFromEuler(e);
  ReceiverLine r;
  ReceiverLineProblem p;
  REQUIRE(DecodeReceiverLine(Line(12, NewDataFlag::kFresh, e), &r, &p));
  CHECK(r.sensor == 12);
  CHECK(r.flag == NewDataFlag::kFresh);
  // binary32 on the wire: equal to the float of each component.
  CHECK(r.q.w == static_cast<double>(static_cast<float>(q.w)));
  CHECK(r.q.z == static_cast<double>(static_cast<float>(q.z)));
  REQUIRE(DecodeReceiverLine(Line(255, NewDataFlag::kNever), &r, &p));
  CHECK(r.flag == NewDataFlag::kNever);
}

TEST_CASE("capture: DecodeReceiverLine names each class of bad line", "[capture]") {
  ReceiverLine r;
  ReceiverLineProblem p;
  const std::string good = Line(3, NewDataFlag::kFresh);
  CHECK_FALSE(DecodeReceiverLine(good.substr(1), &r, &p));
  CHECK(p.column == 0);
  CHECK(p.message.rfind("receiver line has 53 characters: expected 54", 0) == 0);
  std::string bad = good;
  bad[9] = 'g';
  CHECK_FALSE(DecodeReceiverLine(bad, &r, &p));
  CHECK(p.column == 10);
  CHECK(p.message == "non-hex character 'g' at column 10: expected 0-9 or a-f");
  bad = good;
  bad[0] = bad[1] = '0';
  CHECK_FALSE(DecodeReceiverLine(bad, &r, &p));
  CHECK(p.message == "sensor number 00: expected a tag number 01..ff");
  bad = good;
  bad[3] = '2';
  CHECK_FALSE(DecodeReceiverLine(bad, &r, &p));
  CHECK(p.column == 3);
  CHECK(p.message.rfind("NewData flag 02:", 0) == 0);
  // w = 2 (0x40000000 little-endian): norm 2.
  bad = good;
  bad.replace(4, 8, "00000040");
  bad.replace(12, 24, std::string(24, '0'));
  CHECK_FALSE(DecodeReceiverLine(bad, &r, &p));
  CHECK(p.column == 5);
  CHECK(p.message.rfind("fresh row with quaternion norm 2:", 0) == 0);
}

TEST_CASE("capture: the sorter keeps whole lines unchanged in any chunking", "[capture]") {
  const std::string l1 = Line(1, NewDataFlag::kFresh) + "\n";
  const std::string l2 = Line(2, NewDataFlag::kStale) + "\r\n";
  const std::string l3 = Line(3, NewDataFlag::kNever) + "\n";
  const std::string tail = l1.substr(30);  // the port opened mid-line: 25 chars + LF
  const std::string banner = "nRF52840 central ready\r\n";
  const std::string torn = l1.substr(0, 20) + "\n";  // a line torn by a reset
  const std::string bytes = tail + banner + l1 + l2 + torn + l3 + l2.substr(0, 10);
  for (size_t chunk : {size_t{1}, size_t{7}, size_t{55}, bytes.size()}) {
    LineSorter sorter;
    const Sorted s = FeedInChunks(sorter, bytes, chunk);
    using K = LineSorter::Kind;
    REQUIRE(s.kinds == std::vector<K>{K::kCut, K::kOther, K::kReceiver, K::kReceiver, K::kOther,
                                      K::kReceiver});
    CHECK(s.lines[0] == tail);
    CHECK(s.lines[1] == banner);
    CHECK(s.lines[2] == l1);
    CHECK(s.lines[3] == l2);  // CR LF kept
    CHECK(s.lines[5] == l3);
    CHECK(s.sensors[3] == 2);
    CHECK(s.why[4].rfind("receiver line has 20 characters", 0) == 0);
    CHECK(sorter.pending_bytes() == 10);  // the unfinished last line is not passed on
  }
}

TEST_CASE("capture: a first line that is whole is kept; after a restart the next is cut",
          "[capture]") {
  const std::string l1 = Line(1, NewDataFlag::kFresh) + "\n";
  LineSorter sorter;
  Sorted s = FeedInChunks(sorter, l1 + l1.substr(5), 1000);
  REQUIRE(s.kinds.size() == 2);
  CHECK(s.kinds[0] == LineSorter::Kind::kReceiver);
  // A tail later than the first line is not a cut: it is a torn line.
  CHECK(s.kinds[1] == LineSorter::Kind::kOther);
  sorter.Restart();
  s = FeedInChunks(sorter, "\n" + l1, 1000);  // opened just before a LF
  REQUIRE(s.kinds.size() == 2);
  CHECK(s.kinds[0] == LineSorter::Kind::kCut);
  CHECK(s.kinds[1] == LineSorter::Kind::kReceiver);
}

TEST_CASE("capture: the tally counts frames per tag as the loader does", "[capture]") {
  CaptureTally tally(0.1);
  ReceiverLine r;
  auto add = [&](int sensor, NewDataFlag f) {
    REQUIRE(DecodeReceiverLine(Line(sensor, f, {10.0 * sensor, 0, 0}), &r, nullptr));
    tally.Add(r);
  };
  // Frame 0: 1 fresh, 2 never; frame 1: 1 stale, 2 fresh; frame 2: 2 fresh (1 missing).
  add(1, NewDataFlag::kFresh);
  add(2, NewDataFlag::kNever);
  add(1, NewDataFlag::kStale);
  add(2, NewDataFlag::kFresh);
  add(2, NewDataFlag::kFresh);
  CHECK(tally.frames() == 3);
  const TagSeries& t1 = tally.tags().at(1);
  const TagSeries& t2 = tally.tags().at(2);
  CHECK(t1.counts.frames == 2);
  CHECK(t1.counts.fresh == 1);
  CHECK(t1.counts.stale == 1);
  CHECK(t2.counts.never == 1);
  CHECK(t2.counts.fresh == 2);
  REQUIRE(t2.t_s.size() == 2);
  CHECK(t2.t_s[0] == Approx(0.1));
  CHECK(t2.t_s[1] == Approx(0.2));
  CHECK(t2.yaw_deg[0] == Approx(20.0).margin(1e-4));
}

TEST_CASE("capture: fresh rates over the last seconds", "[capture]") {
  CaptureTally tally(0.1);
  FreshRates rates(5.0);
  ReceiverLine r;
  REQUIRE(DecodeReceiverLine(Line(4, NewDataFlag::kFresh), &r, nullptr));
  for (int second = 0; second <= 10; ++second) {
    rates.Sample(tally, static_cast<double>(second));
    // 10 packets per second for 6 s, then 4 per second.
    for (int k = 0; k < (second < 6 ? 10 : 4); ++k) tally.Add(r);
  }
  // Samples at 5..10 s: fresh 50, 60, 64, 68, 72, 76 -> (76 - 50) / 5 s.
  CHECK(rates.RatesHz().at(4) == Approx(26.0 / 5.0));
}

TEST_CASE("capture: live rows give the settled mean and u of each angle", "[capture]") {
  CaptureTally tally(0.1);
  ReceiverLine r;
  // Tag 1: pitch 5 deg with a +-0.2 deg square wave (period 2 samples), no transient; tag 2:
  // never connected.
  std::vector<double> pitch;
  for (int k = 0; k < 400; ++k) {
    const double p = 5.0 + (k % 2 == 0 ? 0.2 : -0.2);
    REQUIRE(DecodeReceiverLine(Line(1, NewDataFlag::kFresh, {0.0, p, 0.0}), &r, nullptr));
    tally.Add(r);
    pitch.push_back(tally.tags().at(1).pitch_deg.back());
    REQUIRE(DecodeReceiverLine(Line(2, NewDataFlag::kNever), &r, nullptr));
    tally.Add(r);
  }
  const std::vector<TagLiveRow> rows = LiveRows(tally, {{1, 9.9}});
  REQUIRE(rows.size() == 2);
  CHECK(rows[0].sensor == 1);
  REQUIRE(rows[0].evaluated[1]);
  CHECK(rows[0].u_available[1]);
  CHECK(rows[0].settle == "no transient");
  double sum = 0;
  for (double p : pitch) sum += p;
  CHECK(rows[0].mean_deg[1] == Approx(sum / 400.0).epsilon(1e-12));
  CHECK(rows[0].mean_deg[1] == Approx(5.0).margin(1e-4));
  Result<TypeAResult> direct = EvaluateTypeA(pitch.data(), pitch.size());
  REQUIRE(direct.ok());
  CHECK(rows[0].u_deg[1] == Approx(direct.value().u_mean));
  CHECK(rows[0].n == 400);
  CHECK(rows[1].counts.never == 400);
  CHECK_FALSE(rows[1].evaluated[0]);
  const std::string table = FormatLiveTable(rows, true);
  // The never-connected tag comes first, in red.
  const size_t red = table.find("\x1b[31m");
  REQUIRE(red != std::string::npos);
  CHECK(table.find("never delivered a packet") < table.find("no transient"));
  CHECK(table.find("\x1b[31m     2") == red);
  CHECK(FormatLiveTable(rows, false).find("\x1b[") == std::string::npos);
  const std::string lines = FormatSummaryLines(rows, 20.0);
  CHECK(lines.find("capture t = 20 s: sensor 1: rate 9.9 Hz, fresh 400, stale 0, never 0, loss "
                   "0.0 %") != std::string::npos);
  CHECK(lines.find("sensor 2: rate - Hz, fresh 0, stale 0, never 400, loss 100.0 %") !=
        std::string::npos);
}

TEST_CASE("capture: a start-up transient is cut before the mean", "[capture]") {
  CaptureTally tally(0.1);
  ReceiverLine r;
  // roll = 3 + 4 exp(-k / 30) + a +-0.05 square wave: the transient is gone (below 1e-4 deg)
  // after about 30 ln(4e4) = 318 samples; the settled mean is 3 within the square wave's
  // 0.05 / n and the transient's tail.
  for (int k = 0; k < 1200; ++k) {
    const double roll = 3.0 + 4.0 * std::exp(-k / 30.0) + (k % 2 == 0 ? 0.05 : -0.05);
    REQUIRE(DecodeReceiverLine(Line(5, NewDataFlag::kFresh, {0.0, 0.0, roll}), &r, nullptr));
    tally.Add(r);
  }
  const std::vector<TagLiveRow> rows = LiveRows(tally, {});
  REQUIRE(rows.size() == 1);
  REQUIRE(rows[0].evaluated[2]);
  CHECK(rows[0].settle.rfind("settled at t = ", 0) == 0);
  CHECK(rows[0].mean_deg[2] == Approx(3.0).margin(0.01));
  CHECK(rows[0].rate_hz < 0);
}

TEST_CASE("capture: a missing port and an existing output are input errors", "[capture]") {
  CaptureOptions o;
  o.port = "metro_capture_no_such_port";
  o.output = "metro_capture_unused.txt";
  std::remove(o.output.c_str());
  CaptureSummary s = RunCapture(o, {}, nullptr);
  CHECK_FALSE(s.ok);
  CHECK(s.input_error);
  CHECK(s.message == "metro_capture_no_such_port: cannot open: No such file or directory");
  std::FILE* f = std::fopen(o.output.c_str(), "r");
  CHECK(f == nullptr);  // nothing created
  if (f != nullptr) std::fclose(f);
  testing::TempFile plain("x", ".txt");
  o.port = plain.path();
  s = RunCapture(o, {}, nullptr);
  CHECK(s.input_error);
  CHECK(s.message.find("not a serial port") != std::string::npos);
  o.port = "";
  s = RunCapture(o, {}, nullptr);
  CHECK(s.message == "no port given (--port)");
}

}  // namespace metro::capture
