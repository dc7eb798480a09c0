// Batch: a broken file among good ones, output names that never collide, the summary.
#include "metro/report/batch.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <string>

#include "metro/core/file.hpp"

namespace metro {
namespace {

namespace fs = std::filesystem;
using nlohmann::ordered_json;

const std::string kDatasets = std::string(METRO_SOURCE_DIR) + "/datasets/";

// A fresh directory under the build's working directory, removed at the end.
struct TempDir {
  TempDir() {
    static int counter = 0;
    path = fs::path("metro_batch_test_" + std::to_string(::getpid()) + "_" +
                    std::to_string(counter++));
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~TempDir() { fs::remove_all(path); }
  fs::path path;
};

ordered_json ReadJson(const fs::path& p) {
  std::ifstream in(p);
  return ordered_json::parse(in);
}

TEST_CASE("Batch goes on past a broken session and names it", "[report][batch]") {
  TempDir in, out;
  fs::create_directories(in.path / "a");
  fs::create_directories(in.path / "b");
  // Two copies of one session under the same name in different directories, another
  // session, and a broken file.
  fs::copy_file(kDatasets + "static_chest.csv", in.path / "a" / "session.csv");
  fs::copy_file(kDatasets + "static_chest.csv", in.path / "b" / "session.csv");
  fs::copy_file(kDatasets + "static_imu_100hz.csv", in.path / "a" / "imu.csv");
  { std::ofstream(in.path / "a" / "broken.csv") << "t_s,sensor,pitch_deg\n0.0,1,0.5\nnot,a,row\n"; }

  Result<std::vector<std::string>> inputs =
      ExpandBatchInputs({(in.path / "a").string(), (in.path / "b" / "*.csv").string()});
  REQUIRE(inputs.ok());
  REQUIRE(inputs.value().size() == 4);

  BatchOptions o;
  o.output_dir = (out.path / "reports").string();
  o.jobs = 2;
  size_t progress_calls = 0;
  o.on_progress = [&](size_t done, size_t total) {
    ++progress_calls;
    CHECK(done <= total);
  };
  const BatchSummary summary = RunBatch(inputs.value(), o);
  CHECK_FALSE(summary.ok);
  CHECK(summary.failed == 1);
  CHECK(progress_calls == 4);
  for (const BatchItem& item : summary.items) {
    if (item.input.find("broken.csv") != std::string::npos) {
      CHECK_FALSE(item.ok);
      INFO(item.error.ToString());
      CHECK(item.error.file == item.input);
      CHECK(item.error.line == 3);
    } else {
      CHECK(item.ok);
      CHECK(fs::exists(item.report_path));
    }
  }
  // Three reports with distinct names, the summary and its table.
  size_t reports = 0;
  for (const auto& e : fs::directory_iterator(o.output_dir)) {
    if (e.path().string().find(".report.json") != std::string::npos) ++reports;
  }
  CHECK(reports == 3);
  const ordered_json s = ReadJson(fs::path(o.output_dir) / "summary.json");
  CHECK(s["schema"] == "metro.batch-summary/1");
  CHECK(s["sessions_total"] == 4);
  CHECK(s["sessions_failed"] == 1);
  bool named = false;
  for (const auto& item : s["sessions"]) {
    if (!item["ok"].get<bool>()) {
      INFO(item["error"].get<std::string>());
      named = item["error"].get<std::string>().find("broken.csv:3") != std::string::npos;
    }
  }
  CHECK(named);
  CHECK(fs::exists(fs::path(o.output_dir) / "summary.txt"));

  // The two copies give the same mean: mean of means = that mean, std of means = 0; the
  // worst n_eff/n is the session's own.
  std::string session_report;
  for (const BatchItem& item : summary.items) {
    if (item.input.find("session.csv") != std::string::npos) session_report = item.report_path;
  }
  REQUIRE_FALSE(session_report.empty());
  const ordered_json one = ReadJson(session_report);
  const auto& pitch = one["sensors"][0]["quantities"]["pitch_deg"]["type_a"];
  bool found = false;
  for (const auto& q : s["quantities"]) {
    if (q["sensor"] == 2 && q["quantity"] == "pitch_deg") {
      found = true;
      CHECK(q["sessions"] == 2);
      CHECK(q["mean_of_means"].get<double>() == Approx(pitch["mean"].get<double>()));
      CHECK(q["std_of_means"].get<double>() == Approx(0.0).margin(1e-12));
      CHECK(q["worst_n_eff_ratio"].get<double>() ==
            Approx(pitch["n_eff"].get<double>() / pitch["n"].get<double>()));
    }
  }
  CHECK(found);
}

TEST_CASE("Std of session means across different sessions", "[report][batch]") {
  TempDir in, out;
  // The same tag in two sessions, offset by a known constant: means differ by that
  // constant, so the std of the two means is |d| / sqrt(2).
  const double d_deg = 0.5;
  std::ofstream a(in.path / "a.csv"), b(in.path / "b.csv");
  a.precision(17);
  b.precision(17);
  a << "t_s,sensor,pitch_deg\n";
  b << "t_s,sensor,pitch_deg\n";
  for (int i = 0; i < 200; ++i) {
    const double v = std::sin(i * 0.7) * 0.1;
    a << i * 0.1 << ",1," << v << "\n";
    b << i * 0.1 << ",1," << v + d_deg << "\n";
  }
  a.close();
  b.close();
  BatchOptions o;
  o.output_dir = out.path.string();
  const BatchSummary summary =
      RunBatch({(in.path / "a.csv").string(), (in.path / "b.csv").string()}, o);
  REQUIRE(summary.ok);
  REQUIRE(summary.summary.quantities.size() == 1);
  const BatchQuantitySummary& q = summary.summary.quantities[0];
  // pitch_deg is an angle: pooled on the circle. Two means d apart: R = cos(d / 2), so the
  // circular std with n - 1 is sqrt(2) sqrt(-2 ln cos(d / 2)) = d / sqrt(2) (1 + d^2 / 96 +
  // ...), d in rad: 0.35355395 deg against the linear 0.35355339.
  const double half_rad = 0.5 * d_deg * M_PI / 180.0;
  CHECK(q.statistics == "circular");
  CHECK(q.std_of_means ==
        Approx(std::sqrt(2.0) * std::sqrt(-2.0 * std::log(std::cos(half_rad))) * 180.0 / M_PI)
            .epsilon(1e-9));
  CHECK(q.std_of_means == Approx(d_deg / std::sqrt(2.0)).epsilon(2e-6));
}

TEST_CASE("Batch names the Allan analyses that produced nothing", "[report][batch]") {
  TempDir in, out;
  {
    // 10 ms grid with samples 3 and 4 missing: refused under --gaps refuse.
    std::ofstream a(in.path / "gap.csv");
    a << "t_s,sensor,gx_dps\n";
    for (int i : {0, 1, 2, 5, 6, 7, 8, 9, 10, 11}) a << i * 0.01 << ",1," << (i % 3) * 0.1 << "\n";
  }
  BatchOptions o;
  o.output_dir = out.path.string();
  o.analysis.allan = true;
  o.analysis.allan_options.gaps = AllanGapPolicy::kRefuse;
  const BatchSummary summary = RunBatch({(in.path / "gap.csv").string()}, o);
  REQUIRE(summary.ok);  // The Type A report was written.
  const std::string expected = (in.path / "gap.csv").string() + ": --allan: sensor 1 gx_dps: ";
  REQUIRE(summary.summary.warnings);
  REQUIRE(summary.summary.warnings->size() == 1);
  CHECK(summary.summary.warnings->front().find(expected) == 0);
  CHECK(summary.table.find(expected) != std::string::npos);
}

TEST_CASE("Batch report names never collide", "[report][batch]") {
  const std::vector<std::string> names =
      BatchReportNames({"x/session.csv", "y/session.csv", "y/other.txt", "summary.csv"});
  REQUIRE(names.size() == 4);
  CHECK(names[0] != names[1]);
  CHECK(names[0].rfind("session-", 0) == 0);
  CHECK(names[2] == "other.report.json");
  CHECK(names[3] == "summary.report.json");
}

TEST_CASE("Batch pools yaw across +-180 on the circle", "[report][batch]") {
  TempDir in, out;
  // Two sessions of one tag: yaw alternates 179.94 / 179.96 (mean 179.95) in one and
  // -179.94 / -179.96 (mean -179.95) in the other; pitch means 10 and 20; gx_dps 1 and 3.
  for (int k = 0; k < 2; ++k) {
    std::ofstream f(in.path / fmt::format("s{}.csv", k));
    f << "t_s,sensor,yaw_deg,pitch_deg,gx_dps\n";
    const double sign = k == 0 ? 1.0 : -1.0;
    for (int i = 0; i < 40; ++i) {
      f << fmt::format("{},1,{:.2f},{:.2f},{:.2f}\n", 0.1 * i,
                       sign * (i % 2 == 0 ? 179.94 : 179.96),
                       (k == 0 ? 10.0 : 20.0) + (i % 2 ? 0.01 : -0.01),
                       (k == 0 ? 1.0 : 3.0) + (i % 2 ? 0.01 : -0.01));
    }
  }
  BatchOptions o;
  o.output_dir = (out.path / "reports").string();
  o.jobs = 1;
  const BatchSummary summary =
      RunBatch({(in.path / "s0.csv").string(), (in.path / "s1.csv").string()}, o);
  REQUIRE(summary.ok);
  std::map<std::string, BatchQuantitySummary> q;
  for (const BatchQuantitySummary& row : summary.summary.quantities) q[row.quantity] = row;
  REQUIRE(q.count("yaw_deg") == 1);
  CHECK(q["yaw_deg"].statistics == "circular");
  CHECK(std::abs(q["yaw_deg"].mean_of_means) == Approx(180.0).margin(1e-6));
  CHECK(q["yaw_deg"].std_of_means == Approx(0.05 * std::sqrt(2.0)).epsilon(1e-4));
  // Pitch on the circle too: symmetric means 10 and 20 give 15 exactly; the spread of +-5
  // deg is 5 sqrt(2) (1 + O(1e-3)).
  CHECK(q["pitch_deg"].statistics == "circular");
  CHECK(q["pitch_deg"].mean_of_means == Approx(15.0).epsilon(1e-9));
  CHECK(q["pitch_deg"].std_of_means == Approx(5.0 * std::sqrt(2.0)).epsilon(2e-3));
  // A rate stays linear: mean 2, sample std sqrt(2).
  CHECK(q["gx_dps"].statistics == "linear");
  CHECK(q["gx_dps"].mean_of_means == Approx(2.0).epsilon(1e-12));
  CHECK(q["gx_dps"].std_of_means == Approx(std::sqrt(2.0)).epsilon(1e-12));
}

TEST_CASE("A tag that never connected has its row, loss 1.0 and a warning on top",
          "[report][batch]") {
  // datasets/capture_15tags_receiver.txt: tag 13 never connects (datasets/regenerate.sh).
  // Its frames are the capture's lines for sensor 13, all of them "ff".
  const std::string capture = kDatasets + "capture_15tags_receiver.txt";
  int64_t frames_13 = 0, stale_2 = 0, never_2 = 0, frames_2 = 0;
  {
    std::ifstream f(capture);
    std::string line;
    while (std::getline(f, line)) {
      if (line.size() < 4) continue;
      const int sensor = std::stoi(line.substr(0, 2), nullptr, 16);
      const std::string flag = line.substr(2, 2);
      if (sensor == 13) ++frames_13;
      if (sensor == 2) {
        ++frames_2;
        stale_2 += flag == "00" ? 1 : 0;
        never_2 += flag == "ff" ? 1 : 0;
      }
    }
  }
  REQUIRE(frames_13 > 0);
  TempDir out;
  BatchOptions o;
  o.output_dir = (out.path / "reports").string();
  o.jobs = 1;
  const BatchSummary summary = RunBatch({capture}, o);
  REQUIRE(summary.ok);
  const BatchSummaryReport& s = summary.summary;
  // The warning heads summary.json (before the sessions) and the table.
  REQUIRE(s.warnings);
  REQUIRE(s.warnings->size() == 1);
  const std::string w = s.warnings->front();
  CHECK(w.find("WARNING sensor 13") != std::string::npos);
  CHECK(w.find("packet_loss_ratio 1.0") != std::string::npos);
  CHECK(summary.table.rfind(capture + ": WARNING sensor 13", 0) == 0);
  bool found_13 = false, found_2 = false;
  REQUIRE(s.tags);
  for (const BatchTagSummary& t : *s.tags) {
    if (t.sensor == 13) {
      found_13 = true;
      CHECK(t.frames == frames_13);
      CHECK(t.fresh == 0);
      CHECK(t.never == frames_13);
      CHECK(t.packet_loss_ratio == 1.0);
      CHECK(t.sessions_without_fresh == 1);
    }
    if (t.sensor == 2) {
      found_2 = true;
      CHECK(t.packet_loss_ratio ==
            Approx(double(stale_2 + never_2) / double(frames_2)).epsilon(1e-15));
    }
  }
  CHECK(found_13);
  CHECK(found_2);
  CHECK(summary.table.find("no fresh packet in 1 session(s)") != std::string::npos);
  std::ifstream txt(fs::path(o.output_dir) / "summary.txt");
  std::string first;
  std::getline(txt, first);
  CHECK(first.find("WARNING sensor 13") != std::string::npos);
  // One session: the warning heads the console table, and the report says 1.0.
  const SessionAnalysis a = AnalyzeSession(capture, {});
  REQUIRE(a.ok);
  CHECK(a.table.rfind("WARNING sensor 13 (", 0) == 0);
  const SensorReport* dead = a.report.FindSensor(13);
  REQUIRE(dead != nullptr);
  CHECK(dead->packet_loss_ratio == 1.0);
}

TEST_CASE("Batch bad input is refused with a message", "[report][batch]") {
  Result<std::vector<std::string>> r = ExpandBatchInputs({});
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().message == "batch: no session files, directories or patterns");
  r = ExpandBatchInputs({"no_such_session.csv"});
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().ToString() == "no_such_session.csv: no such file");
  r = ExpandBatchInputs({"no_such_dir_*/x*.csv"});
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().ToString() == "no_such_dir_*/x*.csv: pattern matches no file");
  TempDir empty;
  r = ExpandBatchInputs({empty.path.string()});
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().message == "directory has no *.csv or *.txt session files");

  BatchOptions o;
  std::string why;
  CHECK_FALSE(o.IsValid(&why));
  CHECK(why == "batch: no output directory (-o DIR)");
  o.output_dir = "x";
  o.jobs = -1;
  CHECK_FALSE(o.IsValid(&why));
  CHECK(why == "batch: --jobs -1 must be >= 0 (0: all cores)");
  const BatchSummary s = RunBatch({}, o);
  CHECK_FALSE(s.ok);
  CHECK(s.error.message == "batch: --jobs -1 must be >= 0 (0: all cores)");
}

}  // namespace
}  // namespace metro
