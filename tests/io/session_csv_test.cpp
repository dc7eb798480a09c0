#include <fast_float/fast_float.h>
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "io/decimal_rows.hpp"
#include "io/session_internal.hpp"
#include "metro/core/file.hpp"
#include "metro/io/session_io.hpp"
#include "support/temp_file.hpp"

namespace metro {
namespace {

using testing::TempFile;

Result<Session> Load(const std::string& text, LoadOptions options = {}) {
  TempFile file(text);
  auto r = LoadSession(file.path(), options);
  if (!r.ok()) {
    // Make messages independent of the temporary name.
    Error e = r.error();
    e.file = "session.csv";
    return e;
  }
  return r;
}

std::string ErrorOf(const std::string& text, LoadOptions options = {}) {
  auto r = Load(text, options);
  REQUIRE_FALSE(r.ok());
  return r.error().ToString();
}

TEST_CASE("session.csv loads tags, units and comments", "[io][csv]") {
  auto r = Load(
      "# a comment before the header\n"
      "t_s,sensor,pitch_deg,ax_g,ay_g,az_g,table_rate_dps\r\n"
      "0.0,2,1.5,0,0,1,\r\n"
      "  # a comment between rows\n"
      "0.0,1,2.5,0,0,1,0\r\n"
      "\n"
      "0.1,2,1.7,0,0,1,10\r\n");
  REQUIRE(r.ok());
  const Session& s = r.value();
  CHECK(s.rows == 3);
  REQUIRE(s.tags.size() == 2);
  CHECK(s.tags[0].sensor == 1);
  CHECK(s.tags[1].sensor == 2);
  const Tag& t2 = s.tags[1];
  REQUIRE(t2.size() == 2);
  CHECK(t2.line[0] == 3);
  CHECK(t2.line[1] == 7);
  const Quantity* pitch = t2.Find("pitch_deg");
  REQUIRE(pitch != nullptr);
  CHECK(pitch->unit == "deg");
  CHECK(pitch->values[1] == 1.7);
  CHECK(t2.Find("ax_g")->unit == "g");
  CHECK(std::isnan(t2.Find("table_rate_dps")->values[0]));
  CHECK(t2.Find("table_rate_dps")->values[1] == 10.0);
  CHECK(s.sha256.size() == 64);
}

TEST_CASE("session.csv without a sensor column is tag 1", "[io][csv]") {
  auto r = Load("t_s,roll_deg\n0,1\n1,2\n");
  REQUIRE(r.ok());
  REQUIRE(r.value().tags.size() == 1);
  CHECK(r.value().tags[0].sensor == 1);
}

TEST_CASE("Euler angles are derived from quaternions of thesis Listing 1", "[io][csv]") {
  auto r = Load(
      "t_s,sensor,qw,qx,qy,qz\n"
      "0,1,0.996276,0.078654,0.007692,0.034479\n"
      "0,2,0.967565,0.015171,-0.011132,0.251919\n");
  REQUIRE(r.ok());
  const Tag& s1 = r.value().tags[0];
  const Tag& s2 = r.value().tags[1];
  REQUIRE(s1.Find("yaw_deg") != nullptr);
  CHECK(s1.Find("yaw_deg")->origin == QuantityOrigin::kDerived);
  CHECK(s1.Find("yaw_deg")->values[0] == Approx(4.009102).margin(5e-4));
  CHECK(s1.Find("pitch_deg")->values[0] == Approx(0.567438).margin(5e-4));
  CHECK(s1.Find("roll_deg")->values[0] == Approx(9.047937).margin(5e-4));
  CHECK(s2.Find("yaw_deg")->values[0] == Approx(29.167585).margin(5e-4));
  CHECK(s2.Find("pitch_deg")->values[0] == Approx(-1.672434).margin(5e-4));
  CHECK(s2.Find("roll_deg")->values[0] == Approx(1.361458).margin(5e-4));
}

TEST_CASE("Quaternions far from unit norm derive their angles and warn", "[io][csv]") {
  // Row 1: thesis Listing 1's first quaternion scaled by 1e308 (its products overflowed:
  // the angles came out 0); row 2: the same in Q30 counts (2^30 per unit); row 3: unit.
  const double k = 1073741824.0;
  auto r =
      Load(fmt::format("t_s,qw,qx,qy,qz\n"
                       "0,9.96276e307,7.8654e306,7.692e305,3.4479e306\n"
                       "1,{},{},{},{}\n"
                       "2,0.996276,0.078654,0.007692,0.034479\n",
                       0.996276 * k, 0.078654 * k, 0.007692 * k, 0.034479 * k));
  REQUIRE(r.ok());
  const Tag& tag = r.value().tags[0];
  for (size_t i = 0; i < 3; ++i) {
    INFO("row " << i);
    CHECK(tag.Find("yaw_deg")->values[i] == Approx(4.009102).margin(5e-4));
    CHECK(tag.Find("pitch_deg")->values[i] == Approx(0.567438).margin(5e-4));
    CHECK(tag.Find("roll_deg")->values[i] == Approx(9.047937).margin(5e-4));
  }
  REQUIRE(r.value().input.warnings.size() == 1);
  CHECK(r.value().input.warnings[0].rfind(
            "sensor 1: 2 of 3 quaternions have a norm more than 0.01 from 1 (norms 1 to "
            "1e+308)",
            0) == 0);
}

TEST_CASE("Euler angles in the file are not replaced", "[io][csv]") {
  auto r = Load("t_s,qw,qx,qy,qz,yaw_deg\n0,1,0,0,0,5\n");
  REQUIRE(r.ok());
  CHECK(r.value().tags[0].Find("yaw_deg")->values[0] == 5.0);
  CHECK(r.value().tags[0].Find("pitch_deg") == nullptr);
}

TEST_CASE("Unknown columns are carried through and reported", "[io][csv]") {
  auto r = Load("t_s,humidity_pct,note,pressure_hpa\n0,40,start,1013\n1,41,x y,1012.5\n");
  REQUIRE(r.ok());
  const Session& s = r.value();
  CHECK(s.unknown_columns == std::vector<std::string>{"humidity_pct", "note", "pressure_hpa"});
  const Tag& t = s.tags[0];
  REQUIRE(t.Find("humidity_pct") != nullptr);
  CHECK(t.Find("humidity_pct")->origin == QuantityOrigin::kUnknown);
  CHECK(t.Find("pressure_hpa")->values[1] == 1012.5);
  REQUIRE(t.text_columns.size() == 1);
  CHECK(t.text_columns[0].name == "note");
  CHECK(t.text_columns[0].values[1] == "x y");
}

TEST_CASE("session.csv bad input: each class names file, line and what was expected", "[io][csv]") {
  CHECK(ErrorOf("t_s,pitch_deg\n0,1\n1,abc\n") ==
        "session.csv:3:2: pitch_deg: expected a finite number, found 'abc' (not a number)");
  CHECK(ErrorOf("t_s,pitch_deg,roll_deg\n0,1,2\n1,2\n") ==
        "session.csv:3:3: missing field: expected 3 fields (t_s,pitch_deg,roll_deg), found 2");
  CHECK(ErrorOf("t_s,pitch_deg\n0,1,7\n") == "session.csv:2:3: expected 2 fields, found 3");
  CHECK(ErrorOf("t_s,pitch_deg\n0,nan\n") ==
        "session.csv:2:2: pitch_deg: expected a finite number, found 'nan' (not finite)");
  CHECK(ErrorOf("t_s,pitch_deg\n0,-inf\n") ==
        "session.csv:2:2: pitch_deg: expected a finite number, found '-inf' (not finite)");
  CHECK(ErrorOf("t_s,pitch_deg\n0,\n") ==
        "session.csv:2:2: pitch_deg: expected a finite number, found '' (empty)");
  CHECK(ErrorOf("t_s,sensor,pitch_deg\n0,1,1\n1,1,1\n0.5,1,1\n") ==
        "session.csv:4:1: t_s = 0.5 is not after t_s = 1 of sensor 1 on line 3: rows must "
        "be sorted by strictly increasing time per tag");
  CHECK(ErrorOf("t_s,sensor,pitch_deg\n0,0,1\n") ==
        "session.csv:2:2: sensor: expected a tag number 1..255, found '0'");
  CHECK(ErrorOf("t_s,Pitch (deg)\n0,1\n") ==
        "session.csv:1:2: header: column 2 is 'Pitch (deg)', not a canonical column name "
        "([a-z][a-z0-9_]* with its unit, e.g. gx_dps); map it: --column 'Pitch (deg)=pitch_deg'");
  CHECK(ErrorOf("t_s,pitch_deg,pitch_deg\n0,1,1\n") ==
        "session.csv:1:3: header: column 'pitch_deg' appears twice (columns 2 and 3)");
  CHECK(ErrorOf("time,ax,ay\n0,1,1\n") ==
        "session.csv:1: header: no time column; expected t_s, t_ms, t_us or t_ns (or --rate-hz "
        "R for a file without one); 'time' names a time without its unit: map it with your "
        "clock's, --column 'time=t_s' (or t_ms, t_us, t_ns); found 'time,ax,ay'");
  CHECK(ErrorOf("Time (ms),gz_dps\n0,1\n") ==
        "session.csv:1:1: header: column 1 is 'Time (ms)', not a canonical column name "
        "([a-z][a-z0-9_]* with its unit, e.g. gx_dps); map it: --column 'Time (ms)=t_ms'");
  CHECK(ErrorOf("t_s,gz_dps,t_ms\n0,1,0\n") ==
        "session.csv:1:3: header: two time columns, 't_s' and 't_ms'; leave one out with "
        "--column 't_ms='");
  CHECK(ErrorOf("t_s,gz_dps\n0,1,2\n") == "session.csv:2:3: expected 2 fields, found 3");
  CHECK(ErrorOf("0,1\n1,2\n") ==
        "session.csv:1:1: no header: line 1 is a data row ('0,1'); expected a header line "
        "naming the columns with their units before it, e.g. t_s,gx_dps,gy_dps,gz_dps "
        "(docs/formats.md)");
  CHECK(ErrorOf("") == "session.csv: empty file: expected a session.csv or a receiver capture");
  CHECK(ErrorOf("t_s,pitch_deg\n") ==
        "session.csv:1: header only: no data rows after the header; expected one row per "
        "observation");
  CHECK(ErrorOf("# only a comment\n\n") ==
        "session.csv: no data: only blank or comment lines; expected a session.csv header or "
        "receiver lines");
  CHECK(ErrorOf(std::string("\x7f"
                            "ELF\x02\x01\x01\0\0\0",
                            10)) ==
        "session.csv: binary data (NUL bytes): expected a text session.csv, a receiver "
        "capture or a PX4 ULog (its first bytes \"ULog\" 01 12 35), an MCAP (89 \"MCAP0\" 0d "
        "0a), a ROS 1 bag (\"#ROSBAG V2.0\") or an ArduPilot DataFlash log (a3 95 80 80 59 "
        "\"FMT\")");
}

TEST_CASE("Lenient mode skips and counts malformed rows", "[io][csv]") {
  LoadOptions lenient;
  lenient.lenient = true;
  auto r = Load("t_s,pitch_deg\n0,1\n1,x\n2,3\n1.5,4\n3,,\n4,5\n", lenient);
  REQUIRE(r.ok());
  const Session& s = r.value();
  CHECK(s.rows == 6);
  CHECK(s.rejected_rows == 3);
  CHECK(s.rejected_lines == std::vector<int64_t>{3, 5, 6});
  REQUIRE(s.tags[0].size() == 3);
  CHECK(s.tags[0].Find("pitch_deg")->values[2] == 5.0);
  // All rows bad: an error even in lenient mode.
  auto all_bad = Load("t_s,pitch_deg\n0,x\n", lenient);
  REQUIRE_FALSE(all_bad.ok());
  CHECK(all_bad.error().message ==
        "no valid data rows: all 1 rows were rejected (first: line 2: pitch_deg: expected a "
        "finite number, found 'x' (not a number))");
}

TEST_CASE("Parallel parsing equals sequential parsing", "[io][csv]") {
  // ~3 MB so the file is cut into several blocks; bad rows spread through it.
  std::string text = "t_s,sensor,pitch_deg,roll_deg\n";
  for (int i = 0; i < 120000; ++i) {
    const int sensor = 1 + i % 3;
    const double t = (i / 3) * 0.01;
    if (i % 9973 == 500) {
      text += "oops,1,2,3\n";
      continue;
    }
    text += std::to_string(t) + "," + std::to_string(sensor) + "," + std::to_string(i * 1e-3) +
            "," + std::to_string(-i * 2e-3) + "\n";
  }
  LoadOptions one, two;
  one.lenient = two.lenient = true;
  one.threads = 1;
  two.threads = 2;
  TempFile file(text);
  auto a = LoadSession(file.path(), one);
  auto b = LoadSession(file.path(), two);
  REQUIRE(a.ok());
  REQUIRE(b.ok());
  CHECK(a.value().rows == 120000);
  CHECK(a.value().rejected_rows == b.value().rejected_rows);
  CHECK(a.value().rejected_lines == b.value().rejected_lines);
  REQUIRE(a.value().tags.size() == 3);
  for (size_t k = 0; k < 3; ++k) {
    CHECK(a.value().tags[k].t_s == b.value().tags[k].t_s);
    CHECK(a.value().tags[k].line == b.value().tags[k].line);
    CHECK(a.value().tags[k].Find("roll_deg")->values == b.value().tags[k].Find("roll_deg")->values);
  }
  // Strict mode reports the first bad line in file order, whatever the thread count.
  LoadOptions strict2;
  strict2.threads = 2;
  auto c = LoadSession(file.path(), strict2);
  REQUIRE_FALSE(c.ok());
  CHECK(c.error().line == 502);
}

// A clean multi-block file with comments, blank lines, CRLF endings and allowed empty
// fields: the two-pass clean path and the general loader must give identical sessions.
std::string CleanMultiBlockText(int rows) {
  std::string text = "# comment before the header\r\nt_s,sensor,pitch_deg,table_angle_deg\r\n";
  for (int i = 0; i < rows; ++i) {
    const int sensor = 1 + (i * 7) % 5;
    if (i % 5003 == 17) text += "\r\n# a comment line\r\n";
    text += fmt::format("{:.6f},{},{:.4f},{}\r\n", i * 0.001, sensor, std::sin(i * 1e-3),
                        i % 11 == 0 ? std::string() : fmt::format("{:.2f}", i * 0.01));
  }
  return text;
}

// The two loads hold the same tags, times, lines and counts, and every quantity bit for bit
// (-0.0 keeps its sign; an empty "unknown" field is NaN in both).
void CheckSameTags(const Session& a, const Session& b) {
  CHECK(a.rows == b.rows);
  REQUIRE(a.tags.size() == b.tags.size());
  for (size_t k = 0; k < a.tags.size(); ++k) {
    const Tag& ta = a.tags[k];
    const Tag& tb = b.tags[k];
    CHECK(ta.sensor == tb.sensor);
    CHECK(ta.t_s == tb.t_s);
    CHECK(ta.line == tb.line);
    CHECK(ta.counts.fresh == tb.counts.fresh);
    REQUIRE(ta.quantities.size() == tb.quantities.size());
    for (size_t q = 0; q < ta.quantities.size(); ++q) {
      const std::vector<double>& va = ta.quantities[q].values;
      const std::vector<double>& vb = tb.quantities[q].values;
      INFO(ta.quantities[q].name);
      CHECK(ta.quantities[q].name == tb.quantities[q].name);
      REQUIRE(va.size() == vb.size());
      size_t differ = 0;
      for (size_t i = 0; i < va.size(); ++i) {
        const bool both_nan = std::isnan(va[i]) && std::isnan(vb[i]);
        differ += !both_nan && std::memcmp(&va[i], &vb[i], sizeof(double)) != 0;
      }
      CHECK(differ == 0);
    }
  }
}

// Loads `path` with 1 and 2 threads through the clean path, which it must take, and
// through the general loader: both must give `tags` tags, identical (CheckSameTags).
// Returns the clean path's sessions.
std::vector<Session> CheckCleanEqualsGeneral(const std::string& path, size_t tags) {
  std::vector<Session> sessions;
  for (const int threads : {1, 2}) {
    LoadOptions options;
    options.threads = threads;
    const int64_t clean_before = internal::CleanPathLoads();
    auto fast = internal::LoadSessionCsv(path, options, true);
    CHECK(internal::CleanPathLoads() == clean_before + 1);  // It took the clean path.
    auto general = internal::LoadSessionCsv(path, options, false);
    CHECK(internal::CleanPathLoads() == clean_before + 1);
    REQUIRE(fast.ok());
    REQUIRE(general.ok());
    REQUIRE(fast.value().tags.size() == tags);
    CheckSameTags(fast.value(), general.value());
    sessions.push_back(std::move(fast).value());
  }
  return sessions;
}

// A comment line longer than a clean-path piece (512 kB) in the middle of the rows: the
// pieces' ends are placed by the workers that parse them (issue #38), so a piece inside the
// line is empty and its neighbours meet at the line's end; the rows, their times and their
// line numbers equal the general loader's.
TEST_CASE("A line longer than a clean-path piece leaves the rows as the general loader reads them",
          "[io][csv]") {
  std::string text = "t_s,sensor,ax_g,ay_g\n";
  for (int i = 0; i < 120000; ++i) {
    text += std::to_string(i) + "," + std::to_string(1 + i % 3) + ",0." + std::to_string(i % 97) +
            ",-1." + std::to_string(i % 13) + "\n";
    if (i == 60000) text += "# " + std::string(size_t{1300} << 10, 'x') + "\n";
  }
  testing::TempFile file(text);
  const std::vector<Session> sessions = CheckCleanEqualsGeneral(file.path(), 3);
  // Row 60001 (tag 60001 % 3 + 1 = 2) is the first after the comment: header + 60001 rows
  // + the comment line before it, so file line 60003 + 1.
  const Tag& tag = *sessions.front().FindTag(2);
  const auto at = std::find(tag.t_s.begin(), tag.t_s.end(), 60001.0);
  REQUIRE(at != tag.t_s.end());
  CHECK(tag.line[static_cast<size_t>(at - tag.t_s.begin())] == 60004);
}

// A logger's file (LF, fixed decimals per column, signs), as the vectorized reader takes
// it, with one comment line that sends its run to the scalar parser: the clean path and
// the general loader (fast_float on every field) must agree bit for bit.
TEST_CASE("Logger rows read four fields at a time equal the general loader", "[io][csv]") {
  std::string text = "t_s,sensor,ax_g,ay_g,az_g,temp_c\n";
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> accel(-2.0, 2.0);
  for (int i = 0; i < 60000; ++i) {  // ~2.4 MB: blocks of several 64 kB runs.
    if (i == 31000) text += "# operator note, mid-run\n";
    text += fmt::format("{:.6f},{},{:.6f},{:.6f},{:.4f},{:.3f}\n", i * 0.01, 1 + i % 3, accel(rng),
                        accel(rng), -250.0 + 500.0 * (i % 997) / 997.0, -0.0004 * (i % 5));
  }
  TempFile file(text);
  const int64_t runs_before = internal::DecimalRowsRead();
  CheckCleanEqualsGeneral(file.path(), 3);
  if (internal::DecimalRowsAvailable()) {
    CHECK(internal::DecimalRowsRead() > runs_before);  // It read runs four fields at a time.
  }
}

TEST_CASE("The clean-file path equals the general loader", "[io][csv]") {
  TempFile file(CleanMultiBlockText(90000));  // ~3 MB: several blocks.
  CheckCleanEqualsGeneral(file.path(), 5);
}

TEST_CASE("Tags whose row rates change through the file load as the general loader does",
          "[io][csv]") {
  // The clean path reserves a tag's columns from its rate in the block where it first
  // appears. Here tag 2 appears only after ~2 MB, tag 3 has one row in the first block and
  // then most of the rows (it outgrows its reservation many times over), and tag 1 stops
  // half way: every column must still hold exactly the general loader's values and lines.
  std::string text = "t_s,sensor,pitch_deg,temp_c\n";
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> accel(-2.0, 2.0);
  std::array<int, 4> count{};
  const int rows = 160000;  // ~5 MB: ten blocks of the clean path.
  for (int i = 0; i < rows; ++i) {
    int sensor = 1;
    if (i == 3) {
      sensor = 3;
    } else if (i > 50000 && i % 4 == 0) {
      sensor = 2;
    } else if (i > rows / 2) {
      sensor = 3;
    }
    const double t = 0.01 * count[static_cast<size_t>(sensor)]++;
    text += fmt::format("{:.6f},{},{:.6f},{:.3f}\n", t, sensor, accel(rng), 25.0 + 0.001 * (i % 7));
  }
  TempFile file(text);
  for (const Session& session : CheckCleanEqualsGeneral(file.path(), 3)) {
    for (size_t k = 0; k < 3; ++k) {
      CHECK(session.tags[k].size() == static_cast<size_t>(count[k + 1]));
    }
  }
}

TEST_CASE("The session's SHA-256 is the file's, on either loader path", "[io][csv][sha256]") {
  // The CSV loader hashes its own mapping of the file while it parses; the digest must be
  // the file's whatever path the parse takes (the clean path, or the general loader after
  // it gave up) and whatever pages the parser has released behind it.
  const std::string clean = CleanMultiBlockText(90000);    // ~3 MB: several blocks.
  const std::string back = clean + "0.000500,1,0.0,\r\n";  // Time going back: general loader.
  for (const std::string* text : {&clean, &back}) {
    TempFile file(*text);
    for (const int threads : {1, 2}) {
      LoadOptions options;
      options.threads = threads;
      options.lenient = true;
      auto r = LoadSession(file.path(), options);
      REQUIRE(r.ok());
      CHECK(r.value().sha256 == Sha256Hex(*text));
      CHECK(r.value().sha256 == Sha256File(file.path()).value());
    }
  }
}

TEST_CASE("Time out of order late in a clean file is reported at its line", "[io][csv]") {
  // The clean path finds the violation only after parsing everything; the general loader
  // must then name the first offending row in file order.
  std::string text = CleanMultiBlockText(60000);
  text += "0.000500,1,0.0,\r\n";  // Sensor 1 going back in time, on the last line.
  TempFile file(text);
  const int64_t clean_before = internal::CleanPathLoads();
  auto r = LoadSession(file.path(), LoadOptions{});
  CHECK(internal::CleanPathLoads() == clean_before);  // Abandoned for the general loader.
  REQUIRE_FALSE(r.ok());
  const int64_t last_line = std::count(text.begin(), text.end(), '\n');
  CHECK(r.error().line == last_line);
  CHECK_THAT(r.error().message, Catch::Contains("not after"));
}

TEST_CASE("Load progress reports every data byte once", "[io][csv]") {
  // The counts add up to the file size, header and comments included.
  const std::string clean = CleanMultiBlockText(90000);  // ~3 MB: several blocks.
  const int64_t data_bytes = static_cast<int64_t>(clean.size());
  auto load = [](const std::string& text, bool lenient, int threads, int64_t* calls) {
    TempFile file(text);
    LoadOptions options;
    options.lenient = lenient;
    options.threads = threads;
    std::atomic<int64_t> bytes{0};
    std::atomic<int64_t> n{0};
    options.on_bytes_parsed = [&](int64_t b) {
      bytes += b;
      ++n;
    };
    auto r = LoadSession(file.path(), options);
    REQUIRE(r.ok());
    *calls = n.load();
    return bytes.load();
  };
  for (const int threads : {1, 2}) {
    int64_t calls = 0;
    const int64_t clean_before = internal::CleanPathLoads();
    CHECK(load(clean, false, threads, &calls) == data_bytes);
    CHECK(internal::CleanPathLoads() == clean_before + 1);
    CHECK(calls >= 4);  // A bar that moves: header, then one report per block (>= 3).
    // Time going back on the last line: the clean path parses every block, gives up, and
    // the general loader parses them again; the bytes still count once.
    const std::string back = "0.000500,1,0.0,\r\n";
    CHECK(load(clean + back, true, threads, &calls) ==
          data_bytes + static_cast<int64_t>(back.size()));
    CHECK(internal::CleanPathLoads() == clean_before + 1);
  }
}

TEST_CASE("Decimals are parsed bit for bit as fast_float parses them", "[io][csv]") {
  // The loader's plain-decimal fast path must return the correctly rounded value, exactly
  // as fast_float (the reference) does, for every digit count and decimal-point position.
  std::mt19937_64 rng(99);
  std::string text = "t_s,sensor,x_deg\n";
  std::vector<std::string> fields;
  for (int i = 0; i < 60000; ++i) {
    const int digits = 1 + static_cast<int>(rng() % 17);  // 16 and 17 take fast_float.
    std::string d;
    for (int k = 0; k < digits; ++k) d += static_cast<char>('0' + rng() % 10);
    const size_t point = rng() % (d.size() + 1);
    std::string field =
        d.substr(0, point) + (point < d.size() || rng() % 2 ? "." : "") + d.substr(point);
    if (field == ".") field = "0";
    if (rng() % 2) field = "-" + field;
    if (i % 97 == 0) field += "e-3";
    fields.push_back(field);
    text += std::to_string(i) + ",1," + field + "\n";
  }
  TempFile file(text);
  auto r = LoadSession(file.path(), LoadOptions{});
  REQUIRE(r.ok());
  const auto& values = r.value().tags.at(0).Find("x_deg")->values;
  REQUIRE(values.size() == fields.size());
  int mismatches = 0;
  for (size_t i = 0; i < fields.size(); ++i) {
    double expected = 0.0;
    const auto res =
        fast_float::from_chars(fields[i].data(), fields[i].data() + fields[i].size(), expected);
    REQUIRE(res.ec == std::errc());
    if (std::memcmp(&expected, &values[i], sizeof(double)) != 0) ++mismatches;
  }
  CHECK(mismatches == 0);
}

TEST_CASE("Sha256File hashes a mapped file in chunks as one digest", "[io][sha256]") {
  // FIPS 180-2 Appendix B.3: SHA-256 of one million 'a'.
  TempFile million(std::string(1000000, 'a'));
  auto digest = Sha256File(million.path());
  REQUIRE(digest.ok());
  CHECK(digest.value() == "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
  // Several 4 MiB chunks and a tail that is not a whole page: the same digest as the
  // one-shot hash of the bytes in memory.
  std::mt19937_64 rng(7);
  std::string bytes((size_t{9} << 20) + 123, '\0');
  for (char& c : bytes) c = static_cast<char>(rng() & 0xFF);
  TempFile large(bytes);
  digest = Sha256File(large.path());
  REQUIRE(digest.ok());
  CHECK(digest.value() == Sha256Hex(bytes));
}

TEST_CASE("FormatSessionCsv round-trips a session", "[io][csv]") {
  const std::string text =
      "t_s,sensor,qw,qx,qy,qz,table_rate_dps,note\n"
      "0,2,0.967565,0.015171,-0.011132,0.251919,,a\n"
      "0,1,0.996276,0.078654,0.007692,0.034479,0,b\n"
      "0.1,1,1,0,0,0,5.5,c\n";
  auto first = Load(text);
  REQUIRE(first.ok());
  const std::string csv = FormatSessionCsv(first.value(), false);
  CHECK(csv ==
        "t_s,sensor,qw,qx,qy,qz,table_rate_dps,note\n"
        "0,1,0.996276,0.078654,0.007692,0.034479,0,b\n"
        "0,2,0.967565,0.015171,-0.011132,0.251919,,a\n"
        "0.1,1,1,0,0,0,5.5,c\n");
  auto second = Load(csv);
  REQUIRE(second.ok());
  CHECK(second.value().tags[0].Find("yaw_deg")->values ==
        first.value().tags[0].Find("yaw_deg")->values);
}

}  // namespace
}  // namespace metro
