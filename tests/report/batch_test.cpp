// Batch: a broken file among good ones, output names that never collide, the summary.
#include "metro/report/batch.hpp"

#include <unistd.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
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
  REQUIRE(summary.summary["quantities"].size() == 1);
  const auto& q = summary.summary["quantities"][0];
  CHECK(q["std_of_means"].get<double>() == Approx(d_deg / std::sqrt(2.0)).epsilon(1e-9));
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
