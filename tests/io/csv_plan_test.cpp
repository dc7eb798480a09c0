// The tolerant session.csv dialect (src/io/csv_plan.cpp): partial axis families, BOM,
// delimiters, decimal commas, line ends, quoting, case, column mappings, time units and
// the named formats (EuRoC, raw, phyphox, Sensor Logger), each from a file the test writes,
// each asserting the numbers read. Expected values are the decimals written in the files.
#include "io/csv_plan.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <string>
#include <vector>

#include "io/session_internal.hpp"
#include "metro/io/session_io.hpp"
#include "metro/io/session_join.hpp"
#include "metro/noise/sample_period.hpp"
#include "support/temp_file.hpp"

namespace metro {
namespace {

using testing::TempFile;

Result<Session> LoadText(const std::string& text, LoadOptions options = {},
                         const std::string& suffix = ".csv") {
  TempFile file(text, suffix);
  auto r = LoadSession(file.path(), options);
  if (!r.ok()) {
    Error e = r.error();
    if (e.file == file.path()) e.file = "in.csv";
    return e;
  }
  return r;
}

std::string ErrorOf(const std::string& text, LoadOptions options = {}) {
  auto r = LoadText(text, options);
  REQUIRE_FALSE(r.ok());
  return r.error().ToString();
}

const std::vector<double>& Values(const Session& s, const std::string& name, int sensor = 1) {
  const Tag* tag = s.FindTag(sensor);
  REQUIRE(tag != nullptr);
  const Quantity* q = tag->Find(name);
  INFO(name);
  REQUIRE(q != nullptr);
  return q->values;
}

TEST_CASE("any subset of an axis family is a session", "[io][csv][dialect]") {
  auto one = LoadText("t_s,gz_dps\n0,0.5\n0.01,0.25\n0.02,-0.75\n");
  REQUIRE(one.ok());
  CHECK(Values(one.value(), "gz_dps") == std::vector<double>{0.5, 0.25, -0.75});
  CHECK(one.value().tags[0].Find("gx_dps") == nullptr);
  auto two = LoadText("t_s,ax_g,ay_g,yaw_deg\n0,0.125,-1,10\n1,0.25,-0.5,11\n");
  REQUIRE(two.ok());
  CHECK(Values(two.value(), "ay_g") == std::vector<double>{-1, -0.5});
  // Part of the quaternion: loaded, no Euler angles derived from it.
  auto quat = LoadText("t_s,qw,qx\n0,1,0\n1,0.5,0.5\n");
  REQUIRE(quat.ok());
  CHECK(quat.value().tags[0].Find("yaw_deg") == nullptr);
}

TEST_CASE("BOM, semicolons with decimal commas, CRLF, upper case", "[io][csv][dialect]") {
  auto r = LoadText("\xEF\xBB\xBFT_S;GX_DPS;Temp_C\r\n0,5;1,25;20\r\n1,5;-2,5;20,5\r\n");
  REQUIRE(r.ok());
  const Session& s = r.value();
  CHECK(s.input.bom);
  CHECK(s.input.delimiter == ';');
  CHECK(s.input.decimal_point == ',');
  CHECK(s.input.line_ends == "CRLF");
  CHECK(s.tags[0].t_s == std::vector<double>{0.5, 1.5});
  CHECK(Values(s, "gx_dps") == std::vector<double>{1.25, -2.5});
  CHECK(Values(s, "temp_c") == std::vector<double>{20, 20.5});
  // The renamings are recorded.
  REQUIRE(s.input.mapping.size() == 3);
  CHECK(s.input.mapping[0].source == "T_S");
  CHECK(s.input.mapping[0].canonical == "t_s");
}

TEST_CASE("tab separated, CR-only line ends, quoted header", "[io][csv][dialect]") {
  auto tab = LoadText("\"t_s\"\t\"ax_mps2\"\n0\t9.75\n0.5\t9.8125\n");
  REQUIRE(tab.ok());
  CHECK(tab.value().input.delimiter == '\t');
  CHECK(tab.value().input.quoted);
  CHECK(Values(tab.value(), "ax_mps2") == std::vector<double>{9.75, 9.8125});
  auto cr = LoadText("t_s,gy_dps\r0,1.5\r1,2.5\r2,3.5\r");
  REQUIRE(cr.ok());
  CHECK(cr.value().input.line_ends == "CR");
  CHECK(Values(cr.value(), "gy_dps") == std::vector<double>{1.5, 2.5, 3.5});
  CHECK(cr.value().tags[0].line == std::vector<uint32_t>{2, 3, 4});
  // A leading comment does not make the whole CR-only file one comment line.
  auto commented = LoadText("# logged by a Mac\rt_s,gy_dps\r0,1.5\r1,2.5\r2,3.5\r");
  REQUIRE(commented.ok());
  CHECK(commented.value().input.line_ends == "CR");
  CHECK(Values(commented.value(), "gy_dps") == std::vector<double>{1.5, 2.5, 3.5});
  CHECK(commented.value().tags[0].line == std::vector<uint32_t>{3, 4, 5});
}

TEST_CASE("a non-canonical header is named with the mapping it needs", "[io][csv][dialect]") {
  const std::string text = "t_s,gyro_x (deg/s)\n0,1\n1,2\n";
  // Detected, it is a phone app's spelling (--format phone); read as session.csv, it is named
  // with the mapping it needs.
  auto detected = LoadText(text);
  REQUIRE(detected.ok());
  CHECK(detected.value().format == SessionFormat::kPhone);
  CHECK(Values(detected.value(), "gx_dps") == std::vector<double>{1, 2});
  LoadOptions csv;
  csv.format = SessionFormat::kCsv;
  const std::string e = ErrorOf(text, csv);
  CHECK_THAT(e, Catch::Contains("in.csv:1:2:"));
  CHECK_THAT(e, Catch::Contains("--column 'gyro_x (deg/s)=gx_dps'"));
  LoadOptions mapped;
  mapped.column_map = {{"gyro_x (deg/s)", "gx_dps"}};
  auto r = LoadText(text, mapped);
  REQUIRE(r.ok());
  CHECK(Values(r.value(), "gx_dps") == std::vector<double>{1, 2});
  // A mapping file, and a column left out with "SRC=".
  TempFile columns("# maps\ngyro_x (deg/s)=gx_dps\n\nnoise=\n", ".txt");
  auto file_map = LoadColumnMappings(columns.path());
  REQUIRE(file_map.ok());
  LoadOptions from_file;
  from_file.column_map = file_map.value();
  auto r2 = LoadText("t_s,gyro_x (deg/s),noise\n0,1,x\n1,2,y\n", from_file);
  REQUIRE(r2.ok());
  CHECK(r2.value().tags[0].text_columns.empty());
  CHECK(r2.value().columns == std::vector<std::string>{"t_s", "gx_dps"});
  CHECK_FALSE(ParseColumnMapping("gx_dps").ok());
  CHECK_FALSE(ParseColumnMapping("a=Not Canonical").ok());
}

TEST_CASE("integer time units are exact", "[io][csv][time]") {
  // 200 Hz on an epoch nanosecond clock: as doubles of seconds the period would be
  // 0.004999876 s; from integer differences it is 0.005 s.
  std::string text = "t_ns,gx_rads\n";
  const int64_t t0 = 1403636579758555392;
  for (int i = 0; i < 50; ++i) text += fmt::format("{},{}\n", t0 + 5000000LL * i, 0.001 * i);
  auto r = LoadText(text);
  REQUIRE(r.ok());
  const Tag& tag = r.value().tags[0];
  REQUIRE(tag.t_ns.size() == 50);
  CHECK(tag.t_ns[49] - tag.t_ns[0] == 245000000);
  CHECK(r.value().input.time_origin_ns == t0);
  CHECK(tag.t_s[1] == 0.005);
  CHECK(tag.t_s[49] == 0.245);
  auto period = EstimateSamplePeriodNs(tag.t_ns, tag.line);
  REQUIRE(period.ok());
  CHECK(period.value().tau0_s == 0.005);
  CHECK(period.value().jitter_rms_s == 0.0);
  // t_ms with a fraction, t_us.
  auto ms = LoadText("t_ms,ax_g\n1000,1\n1012.5,2\n");
  REQUIRE(ms.ok());
  CHECK(ms.value().tags[0].t_ns == std::vector<int64_t>{1000000000, 1012500000});
  CHECK(ms.value().tags[0].t_s == std::vector<double>{0.0, 0.0125});
  auto us = LoadText("t_us,ax_g\n7,1\n8,2\n");
  REQUIRE(us.ok());
  CHECK(us.value().tags[0].t_ns == std::vector<int64_t>{7000, 8000});
  CHECK_THAT(ErrorOf("t_ns,ax_g\n1.5,1\n"), Catch::Contains("in.csv:2:1: t_ns:"));
  CHECK_THAT(ErrorOf("t_ms,ax_g\n2,1\n2,1\n"), Catch::Contains("t_ms = 2 is not after t_ms = 2"));
  // 1 ns apart, 1e9 s from the first time: one double of seconds; refused, never equal t_s.
  CHECK_THAT(ErrorOf("t_ns,sensor,ax_g\n0,2,1\n1000000000000000000,1,1\n"
                     "1000000000000000001,1,1\n"),
             Catch::Contains("in.csv:4: t_ns = 1000000000000000001 is 1 ns after"));
}

TEST_CASE("E-notation times are read with the resolution they have left", "[io][csv][time]") {
  int64_t ns = 0;
  int64_t resolution = 0;
  const char* why = nullptr;
  const std::string s = "1.40363657975856E+018";
  REQUIRE(internal::ParseExactTimeNs(s.data(), s.data() + s.size(), 1, &ns, &resolution, &why));
  CHECK(ns == 1403636579758560000);
  CHECK(resolution == 10000);
  const std::string plain = "1403636579758555392";
  REQUIRE(internal::ParseExactTimeNs(plain.data(), plain.data() + plain.size(), 1, &ns, &resolution,
                                     &why));
  CHECK(ns == 1403636579758555392);
  CHECK(resolution == 0);
  const std::string too_big = "9.3e18";
  CHECK_FALSE(internal::ParseExactTimeNs(too_big.data(), too_big.data() + too_big.size(), 1, &ns,
                                         &resolution, &why));
}

// EuRoC's imu0/data.csv: "#timestamp [ns],w_RS_S_x [rad s^-1],...", 200 Hz.
std::string Euroc(int rows, bool spreadsheet) {
  std::string text =
      "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],"
      "a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]\n";
  for (int i = 0; i < rows; ++i) {
    const int64_t t = 1403636579758555392 + 5000000LL * i;
    const std::string ts =
        spreadsheet ? fmt::format("{:.14E}", static_cast<double>(t)) : std::to_string(t);
    text += fmt::format("{},{},{},{},{},{},{}\n", ts, -0.0991 + 0.001 * i, 0.1334, 0.0830, 8.1476,
                        -0.3759, -2.4447);
  }
  if (spreadsheet) text += ",,,,,,\nStep: 0.005 = 1/200,,,,,,\n";
  return text;
}

TEST_CASE("EuRoC imu0/data.csv is detected and mapped", "[io][csv][formats]") {
  auto r = LoadText(Euroc(10, false));
  REQUIRE(r.ok());
  const Session& s = r.value();
  CHECK(s.format == SessionFormat::kEuroc);
  CHECK(s.input.header_in_comment);
  CHECK(s.columns == std::vector<std::string>{"t_ns", "gx_rads", "gy_rads", "gz_rads", "ax_mps2",
                                              "ay_mps2", "az_mps2"});
  CHECK(Values(s, "gx_rads")[2] == -0.0991 + 0.002);
  CHECK(Values(s, "az_mps2")[0] == -2.4447);
  CHECK(s.tags[0].line[0] == 2);
  auto period = EstimateSamplePeriodNs(s.tags[0].t_ns, s.tags[0].line);
  REQUIRE(period.ok());
  CHECK(period.value().tau0_s == 0.005);
  // Forced to plain csv: the error is on the header line and names the format.
  LoadOptions csv;
  csv.format = SessionFormat::kCsv;
  const std::string e = ErrorOf(Euroc(3, false), csv);
  CHECK_THAT(e, Catch::Contains("in.csv:1:1:"));
  CHECK_THAT(e, Catch::Contains("pass --format euroc"));
  CHECK_THAT(e, Catch::Contains("--column 'timestamp [ns]=t_ns'"));
}

TEST_CASE("t_s in E-notation says the resolution it has left", "[io][csv][time]") {
  // 1.40363657975856E+09 s: the last written digit is the 1e-5 s place.
  auto r = LoadText("t_s,gz_dps\n1.40363657975856E+09,1\n1.40363657976356E+09,2\n");
  REQUIRE(r.ok());
  CHECK(r.value().input.time_resolution_s == 1e-5);
  REQUIRE(r.value().input.warnings.size() == 1);
  CHECK_THAT(r.value().input.warnings[0], Catch::Contains("line 2"));
  auto plain = LoadText("t_s,gz_dps\n0.005,1\n0.010,2\n");
  REQUIRE(plain.ok());
  CHECK(plain.value().input.warnings.empty());
}

TEST_CASE("EuRoC after a spreadsheet round trip", "[io][csv][formats]") {
  auto r = LoadText(Euroc(20, true));
  REQUIRE(r.ok());
  const Session& s = r.value();
  CHECK(s.tags[0].size() == 20);
  CHECK(s.input.time_resolution_s == 1e-5);
  REQUIRE(s.input.warnings.size() == 1);
  CHECK_THAT(s.input.warnings[0], Catch::Contains("10000 ns"));
  REQUIRE_FALSE(s.input.notes.empty());
  CHECK_THAT(s.input.notes.back(), Catch::Contains("Step: 0.005 = 1/200"));
  // 15 significant digits of 1.4e18 ns: each time within 5 us of the truth.
  for (size_t i = 0; i < s.tags[0].size(); ++i) {
    const int64_t truth = 1403636579758555392 + 5000000LL * static_cast<int64_t>(i);
    CHECK(std::llabs(s.tags[0].t_ns[i] - truth) <= 5000);
  }
}

TEST_CASE("a receiver capture opened mid-line", "[io][receiver][formats]") {
  // Two whole frames of sensor 1 after the tail of a line.
  const std::string whole =
      "0101"
      "0000803f"
      "00000000"
      "00000000"
      "00000000"
      "000000000000000000";
  REQUIRE(whole.size() == 54);
  const std::string text = "00000000000000\n" + whole + "\n" + whole + "\n" + whole + "\n";
  TempFile file(text, ".txt");
  auto format = DetectSessionFormat(file.path());
  REQUIRE(format.ok());
  CHECK(format.value() == SessionFormat::kReceiver);
  auto r = LoadSession(file.path());
  REQUIRE(r.ok());
  CHECK(r.value().tags[0].counts.fresh == 3);
  REQUIRE(r.value().input.notes.size() == 1);
  CHECK_THAT(r.value().input.notes[0], Catch::Contains("line 1: 14 hex characters"));
}

TEST_CASE("phyphox exports in each delimiter and decimal choice", "[io][csv][formats]") {
  const std::vector<std::string> texts = {
      "\"Time (s)\",\"Gyroscope x (rad/s)\",\"Gyroscope y (rad/s)\",\"Gyroscope z (rad/s)\","
      "\"Absolute (rad/s)\"\n"
      "2.350000000E-2,1.250000000E-1,-5.000000000E-1,0.000000000E0,5.153882032E-1\n"
      "3.350000000E-2,2.500000000E-1,-2.500000000E-1,1.000000000E0,1.060660172E0\n",
      "\"Time (s)\";\"Gyroscope x (rad/s)\";\"Gyroscope y (rad/s)\";\"Gyroscope z (rad/s)\";"
      "\"Absolute (rad/s)\"\n"
      "2,350000000E-2;1,250000000E-1;-5,000000000E-1;0,000000000E0;5,153882032E-1\n"
      "3,350000000E-2;2,500000000E-1;-2,500000000E-1;1,000000000E0;1,060660172E0\n",
      "\"Time (s)\"\t\"Gyroscope x (rad/s)\"\t\"Gyroscope y (rad/s)\"\t\"Gyroscope z (rad/s)\"\t"
      "\"Absolute (rad/s)\"\n"
      "2.350000000E-2\t1.250000000E-1\t-5.000000000E-1\t0.000000000E0\t5.153882032E-1\n"
      "3.350000000E-2\t2.500000000E-1\t-2.500000000E-1\t1.000000000E0\t1.060660172E0\n"};
  for (const std::string& text : texts) {
    auto r = LoadText(text);
    INFO(text.substr(0, 30));
    REQUIRE(r.ok());
    CHECK(r.value().format == SessionFormat::kPhyphox);
    CHECK(r.value().tags[0].t_s == std::vector<double>{0.0235, 0.0335});
    CHECK(Values(r.value(), "gx_rads") == std::vector<double>{0.125, 0.25});
    CHECK(Values(r.value(), "gy_rads") == std::vector<double>{-0.5, -0.25});
    CHECK(Values(r.value(), "gz_rads") == std::vector<double>{0.0, 1.0});
  }
  auto deg = LoadText("Time (s),Gyroscope x (deg/s)\n0,1.5\n0.01,2.5\n");
  REQUIRE(deg.ok());
  CHECK(Values(deg.value(), "gx_dps") == std::vector<double>{1.5, 2.5});
}

TEST_CASE("Phone apps' spellings of a sensor axis with its unit (--format phone)",
          "[io][csv][formats]") {
  // Each header spells the accelerometer (or gyroscope) axes its own way, with a unit; the
  // values are the decimals written, under the canonical name of that sensor, axis and unit.
  struct Case {
    std::string header, time, x, y, z;
  };
  const std::vector<Case> cases = {
      {"Time (s),Accel_X (m/s^2),Accel_Y (m/s^2),Accel_Z (m/s^2)", "t_s", "ax_mps2", "ay_mps2",
       "az_mps2"},
      {"Time (s),Acc X (m/s^2),Acc Y (m/s^2),Acc Z (m/s^2)", "t_s", "ax_mps2", "ay_mps2",
       "az_mps2"},
      {"Time [s],accX [g],accY [g],accZ [g]", "t_s", "ax_g", "ay_g", "az_g"},
      {"time_ms,accelerometer_x_g,accelerometer_y_g,accelerometer_z_g", "t_ms", "ax_g", "ay_g",
       "az_g"},
      {"Time (s),Gyro_X (rad/s),Gyro_Y (rad/s),Gyro_Z (rad/s)", "t_s", "gx_rads", "gy_rads",
       "gz_rads"},
      {"Time (s),gyroX (deg/s),gyroY (deg/s),gyroZ (deg/s)", "t_s", "gx_dps", "gy_dps", "gz_dps"},
  };
  for (const Case& c : cases) {
    INFO(c.header);
    auto r = LoadText(c.header + "\n0,0.125,-0.5,9.75\n10,0.25,-0.25,9.5\n");
    REQUIRE(r.ok());
    CHECK(r.value().format == SessionFormat::kPhone);
    CHECK(r.value().columns == std::vector<std::string>{c.time, c.x, c.y, c.z});
    CHECK(Values(r.value(), c.x) == std::vector<double>{0.125, 0.25});
    CHECK(Values(r.value(), c.y) == std::vector<double>{-0.5, -0.25});
    CHECK(Values(r.value(), c.z) == std::vector<double>{9.75, 9.5});
  }
  // A session.csv naming a canonical quantity stays one, with its spelled extra column
  // carried as an unknown column.
  auto canonical = LoadText("t_s,ax_g,acc_x_raw_lsb\n0,1,2\n0.01,1,2\n");
  REQUIRE(canonical.ok());
  CHECK(canonical.value().format == SessionFormat::kCsv);
  // Forced as csv, the error proposes --format phone.
  LoadOptions csv;
  csv.format = SessionFormat::kCsv;
  CHECK_THAT(ErrorOf("Time (s),Accel_X (m/s^2)\n0,1\n", csv),
             Catch::Contains("pass --format phone"));
}

TEST_CASE("A sensor axis or time spelled without its unit is named, with the mappings to choose",
          "[io][csv][formats]") {
  // No time unit: the error names the column and the time units to choose from.
  CHECK_THAT(ErrorOf("timestamp,accelerometer_x\n0,1\n"),
             Catch::Contains("'timestamp' names a time without its unit") &&
                 Catch::Contains("--column 'timestamp=t_s'"));
  // An axis without a unit is carried as a unit-less unknown column, with a warning at its
  // file:line:column proposing the mappings.
  auto r = LoadText("t_s,accX,gyroZ\n0,1,2\n0.01,1,2\n");
  REQUIRE(r.ok());
  const std::string warnings = fmt::format("{}", fmt::join(r.value().input.warnings, "\n"));
  CHECK_THAT(warnings, Catch::Contains(":1:2: column 'accX'") &&
                           Catch::Contains("--column 'accX=ax_mps2' (m/s^2) or --column "
                                           "'accX=ax_g' (g)"));
  CHECK_THAT(warnings, Catch::Contains(":1:3: column 'gyroZ'") &&
                           Catch::Contains("--column 'gyroZ=gz_rads'"));
}

TEST_CASE("Sensor Logger per-sensor files, and joining them on time", "[io][csv][formats]") {
  // Gyroscope at 100 Hz, accelerometer at 100 Hz offset by 2 ms, one extra accelerometer
  // sample at the end; epoch ns.
  const int64_t t0 = 1700000000000000000;
  std::string gyro = "time,seconds_elapsed,z,y,x\n";
  std::string accel = "time,seconds_elapsed,z,y,x\n";
  for (int i = 0; i < 10; ++i) {
    gyro += fmt::format("{},{},{},{},{}\n", t0 + 10000000LL * i, 0.01 * i, 0.3, 0.2, 0.1 * i);
    accel += fmt::format("{},{},{},{},{}\n", t0 + 2000000 + 10000000LL * i, 0.01 * i + 0.002, 9.8,
                         0.0, -0.5 * i);
  }
  accel += fmt::format("{},{},{},{},{}\n", t0 + 2000000 + 10000000LL * 10, 0.102, 9.8, 0.0, 5.0);
  TempFile g(gyro, "_Gyroscope.csv");
  TempFile a(accel, "_Accelerometer.csv");
  auto gs = LoadSession(g.path());
  REQUIRE(gs.ok());
  CHECK(gs.value().format == SessionFormat::kSensorLogger);
  CHECK(gs.value().columns == std::vector<std::string>{"t_ns", "gz_rads", "gy_rads", "gx_rads"});
  CHECK(Values(gs.value(), "gx_rads")[3] == 0.1 * 3);
  CHECK(gs.value().tags[0].t_ns[1] - gs.value().tags[0].t_ns[0] == 10000000);
  auto as = LoadSession(a.path());
  REQUIRE(as.ok());
  CHECK(Values(as.value(), "az_mps2")[0] == 9.8);
  JoinSummary summary;
  auto joined = JoinSessionsOnTime({gs.value(), as.value()}, &summary);
  REQUIRE(joined.ok());
  const Tag& tag = joined.value().tags[0];
  REQUIRE(tag.size() == 10);
  CHECK(tag.Find("ax_mps2")->values[4] == -0.5 * 4);
  CHECK(tag.Find("gx_rads")->values[4] == 0.1 * 4);
  CHECK(summary.unmatched == std::vector<int64_t>{0, 1});
  // A Sensor Logger file whose name does not say the sensor.
  auto unnamed = LoadText(gyro);
  REQUIRE_FALSE(unnamed.ok());
  CHECK_THAT(unnamed.error().message, Catch::Contains("--column x=gx_rads"));
  CHECK(unnamed.error().line == 1);
}

TEST_CASE("raw-count logger prints", "[io][csv][formats]") {
  const std::string text =
      "Fs,100\nLogging Type,1\nInitialization time,-1\nWaiting time,-1\n"
      "ax,ay,az,gx,gy,gz\n"
      "2508,-604,14684,-429,140,-53\n2744,-692,14772,-433,168,-75\n"
      "2616,-692,14872,-439,130,-63\n";
  auto r = LoadText(text);
  REQUIRE(r.ok());
  const Session& s = r.value();
  CHECK(s.format == SessionFormat::kRaw);
  CHECK(s.input.rate_hz == 100);
  CHECK(s.tags[0].t_s == std::vector<double>{0.0, 0.01, 0.02});
  CHECK(s.tags[0].line == std::vector<uint32_t>{6, 7, 8});
  CHECK(Values(s, "az_lsb") == std::vector<double>{14684, 14772, 14872});
  CHECK(s.tags[0].Find("az_g") == nullptr);
  LoadOptions scaled;
  scaled.accel_fs_g = 2.0;
  scaled.gyro_fs_dps = 250.0;
  scaled.rate_hz = 50.0;  // Overrides the file's Fs line.
  auto r2 = LoadText(text, scaled);
  REQUIRE(r2.ok());
  CHECK(r2.value().tags[0].t_s == std::vector<double>{0.0, 0.02, 0.04});
  CHECK(Values(r2.value(), "az_g")[0] == 14684.0 / 16384.0);
  CHECK(Values(r2.value(), "gx_dps")[0] == -429.0 * 250.0 / 32768.0);
  CHECK(r2.value().tags[0].Find("az_g")->origin == QuantityOrigin::kDerived);
}

TEST_CASE("a raw logger's sample-rate line that gives no rate is refused at its value",
          "[io][csv][formats]") {
  const std::string rows = "ax,ay,az,gx,gy,gz\n1,2,3,4,5,6\n2,3,4,5,6,7\n3,4,5,6,7,8\n";
  for (const std::string bad : {"abc", "", "-5", "0", "1e400", "100x"}) {
    auto r = LoadText("Logging Type,1\nFs," + bad + "\n" + rows);
    REQUIRE_FALSE(r.ok());
    CHECK(r.error().line == 2);
    CHECK(r.error().column == 4);  // "Fs," is three characters: the value starts at column 4.
    CHECK_THAT(r.error().message, Catch::Contains("expected a positive number of hertz"));
  }
  // --rate-hz still overrides a good line, and says so.
  LoadOptions rate;
  rate.rate_hz = 50.0;
  auto r = LoadText("Fs,100\n" + rows, rate);
  REQUIRE(r.ok());
  CHECK(r.value().tags[0].t_s == std::vector<double>{0.0, 0.02, 0.04});
  const std::vector<std::string>& notes = r.value().input.notes;
  CHECK(std::any_of(notes.begin(), notes.end(), [](const std::string& n) {
    return n.find("--rate-hz 50 overrides the metadata 'Fs,100' (line 1)") != std::string::npos;
  }));
}

TEST_CASE("a file without a time column is timed by --rate-hz", "[io][csv][time]") {
  LoadOptions rate;
  rate.rate_hz = 4.0;
  auto r = LoadText("gz_dps\n1\n2\n3\n", rate);
  REQUIRE(r.ok());
  CHECK(r.value().tags[0].t_s == std::vector<double>{0.0, 0.25, 0.5});
  CHECK(r.value().input.time_unit == "rate");
  CHECK_THAT(ErrorOf("gz_dps\n1\n2\n"), Catch::Contains("no time column; expected t_s, t_ms"));
  CHECK_THAT(ErrorOf("t_s,gz_dps\n0,1\n", rate), Catch::Contains("--rate-hz is for a file"));
  // Lenient: a rejected row of a one-tag file still advances the clock.
  rate.lenient = true;
  auto l = LoadText("gz_dps\n1\nx\n3\n", rate);
  REQUIRE(l.ok());
  CHECK(l.value().tags[0].t_s == std::vector<double>{0.0, 0.5});
}

TEST_CASE("EuRoC and raw round-trip through session.csv", "[io][csv][formats]") {
  for (const std::string& text :
       {Euroc(12, false), std::string("Fs,200\nax,gz\n1,2\n3,4\n5,6\n")}) {
    auto first = LoadText(text);
    REQUIRE(first.ok());
    const std::string csv = FormatSessionCsv(first.value(), true);
    auto second = LoadText(csv);
    REQUIRE(second.ok());
    const Tag& a = first.value().tags[0];
    const Tag& b = second.value().tags[0];
    CHECK(a.t_s == b.t_s);
    CHECK(a.t_ns == b.t_ns);
    REQUIRE(a.quantities.size() == b.quantities.size());
    for (size_t q = 0; q < a.quantities.size(); ++q) {
      CHECK(a.quantities[q].name == b.quantities[q].name);
      CHECK(a.quantities[q].values == b.quantities[q].values);
    }
  }
}

TEST_CASE("header names are inferred only when evident", "[io][csv][dialect]") {
  CHECK(internal::InferCanonicalName("gyro_x (deg/s)") == "gx_dps");
  CHECK(internal::InferCanonicalName("Gyroscope z (rad/s)") == "gz_rads");
  CHECK(internal::InferCanonicalName("w_RS_S_y [rad s^-1]") == "gy_rads");
  CHECK(internal::InferCanonicalName("a_RS_S_z [m s^-2]") == "az_mps2");
  CHECK(internal::InferCanonicalName("Acceleration x (m/s^2)") == "ax_mps2");
  CHECK(internal::InferCanonicalName("timestamp [ns]") == "t_ns");
  CHECK(internal::InferCanonicalName("Time (s)") == "t_s");
  CHECK(internal::InferCanonicalName("Pitch (deg)") == "pitch_deg");
  CHECK(internal::InferCanonicalName("Temperature (\xC2\xB0"
                                     "C)") == "temp_c");
  CHECK(internal::InferCanonicalName("gyro_x") == "");
  CHECK(internal::InferCanonicalName("gyro_x (m/s^2)") == "");  // Unit of another sensor.
}

TEST_CASE("A header of more than 10000 columns is refused", "[io][csv]") {
  // issue #20: load and report grew quadratically (40,000 columns took 71 s).
  auto text = [](int columns) {
    std::string header = "t_s";
    std::string row = "0";
    for (int i = 1; i < columns; ++i) {
      header += fmt::format(",c{}", i);
      row += fmt::format(",{}", i);
    }
    return header + "\n" + row + "\n";
  };
  CHECK(ErrorOf(text(10001)) ==
        "in.csv:1: 10001 columns; metro reads at most 10000 (docs/formats.md, \"Limits\"): "
        "write the columns you need to a new file, or split it");
  auto most = LoadText(text(10000));
  REQUIRE(most.ok());
  CHECK(most.value().tags[0].quantities.size() == 9999);
  CHECK(Values(most.value(), "c9999")[0] == 9999.0);
}

}  // namespace
}  // namespace metro
