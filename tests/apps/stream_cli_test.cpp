// End-to-end: `characterize SESSION --type-a [--allan] --stream` (issue #38 step 2) gives the
// in-memory report's numbers, with groups of rows small enough that every tag and column
// crosses many group boundaries; and what cannot be streamed is refused or named.
#include <catch2/catch.hpp>
#include <cmath>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "support/run_program.hpp"

namespace metro {
namespace {

const std::string kDatasets = std::string(METRO_SOURCE_DIR) + "/datasets/";

testing::ProgramRun Characterize(const std::string& args) {
  return testing::RunProgram(METRO_CHARACTERIZE_EXE, args);
}

// Every value of `a` and `b` but the plot series and the input notes (which say that the
// report was streamed): numbers within 1e-12 relative (the Allan sums add the same terms in
// another order; a term fitted as 0 may read 1e-12), everything else identical.
void CompareReports(const nlohmann::json& a, const nlohmann::json& b, const std::string& path,
                    std::vector<std::string>* diff) {
  if (a.is_object() && b.is_object()) {
    for (const auto& [key, value] : a.items()) {
      if (key == "plot" || (key == "notes" && path == "/input")) continue;
      if (!b.contains(key)) {
        diff->push_back(path + "/" + key + " missing when streamed");
        continue;
      }
      CompareReports(value, b[key], path + "/" + key, diff);
    }
    for (const auto& [key, value] : b.items()) {
      if (!a.contains(key) && !(key == "notes" && path == "/input")) {
        diff->push_back(path + "/" + key + " only when streamed");
      }
    }
  } else if (a.is_array() && b.is_array() && a.size() == b.size()) {
    for (size_t i = 0; i < a.size(); ++i) {
      CompareReports(a[i], b[i], path + "/" + std::to_string(i), diff);
    }
  } else if (a.is_number_float() && b.is_number()) {
    const double x = a.get<double>(), y = b.get<double>();
    if (!(std::abs(x - y) <= 1e-12 * std::max(std::abs(x), std::abs(y)) + 1e-12)) {
      diff->push_back(path + ": " + a.dump() + " in memory, " + b.dump() + " streamed");
    }
  } else if (a != b) {
    diff->push_back(path + ": " + a.dump() + " in memory, " + b.dump() + " streamed");
  }
}

}  // namespace

TEST_CASE("characterize --stream reports the in-memory numbers on the bundled sessions",
          "[apps][stream]") {
  struct Case {
    std::string file, args;
  };
  const std::vector<Case> cases = {
      {"static_imu_100hz.csv", "--type-a --allan"},
      {"static_imu_100hz.csv", "--type-a --allan --estimator ohdev"},
      {"static_imu_100hz.csv", "--allan --estimator mdev"},
      {"static_imu_100hz.csv", "--allan --estimator adev --quantity gz_dps"},
      {"static_imu_100hz.csv", "--allan --estimator hdev --quantity az_g"},
      {"static_chest.csv", "--type-a"},
      {"capture_15tags.csv", "--type-a --sensor 3 --sensor 7"},
      {"table_sweep.csv", "--type-a"},
      {"calibration_session.csv", "--type-a --quantity gx_lsb --quantity temp_c"},
  };
  for (const Case& c : cases) {
    INFO(c.file << " " << c.args);
    auto memory = Characterize(kDatasets + c.file + " " + c.args);
    // 64 kB groups: hundreds of groups, each tag's rows split between them.
    auto streamed =
        Characterize(kDatasets + c.file + " " + c.args + " --stream --stream-group-bytes 65536");
    INFO(streamed.err);
    REQUIRE(memory.exit_code == 0);
    REQUIRE(streamed.exit_code == 0);
    const auto a = nlohmann::json::parse(memory.out);
    const auto b = nlohmann::json::parse(streamed.out);
    std::vector<std::string> diff;
    CompareReports(a, b, "", &diff);
    for (const std::string& d : diff) UNSCOPED_INFO(d);
    CHECK(diff.empty());
    CHECK(b["input"]["notes"].dump().find("streaming mode") != std::string::npos);
  }
}

TEST_CASE("characterize - --stream reads stdin once and streams it", "[apps][stream]") {
  const std::string file = kDatasets + "static_imu_100hz.csv";
  std::ifstream in(file, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  auto memory = Characterize(file + " --type-a --allan");
  auto piped = testing::RunProgramWithStdin(
      METRO_CHARACTERIZE_EXE, "- --type-a --allan --stream --stream-group-bytes 65536", bytes);
  INFO(piped.err);
  REQUIRE(memory.exit_code == 0);
  REQUIRE(piped.exit_code == 0);
  const auto a = nlohmann::json::parse(memory.out);
  auto b = nlohmann::json::parse(piped.out);
  CHECK(b["input"]["path"] == "<stdin>");
  b["input"]["path"] = a["input"]["path"];
  std::vector<std::string> diff;
  CompareReports(a, b, "", &diff);
  for (const std::string& d : diff) UNSCOPED_INFO(d);
  CHECK(diff.empty());
}

TEST_CASE("characterize streams by itself only what it can stream", "[apps][stream]") {
  // A share of memory so small that every file is "larger": a text session streams (said on
  // stderr), with any estimator; a ULog stays in memory and works.
  const std::string tiny = " --stream-above-memory-share 1e-12";
  auto csv = Characterize(kDatasets + "static_imu_100hz.csv --type-a" + tiny);
  INFO(csv.err);
  CHECK(csv.exit_code == 0);
  CHECK_THAT(csv.err, Catch::Contains("streaming mode"));
  auto ulog = Characterize(std::string(METRO_EXTERNAL_DATA_DIR) +
                           "/px4_pyulog_samples/sample.ulg --type-a" + tiny);
  INFO(ulog.err);
  CHECK(ulog.exit_code == 0);
  CHECK_THAT(ulog.err, !Catch::Contains("streaming mode"));
  auto mdev = Characterize(kDatasets + "static_imu_100hz.csv --type-a --allan --estimator mdev" +
                           " --quantity gx_dps" + tiny);
  INFO(mdev.err);
  CHECK(mdev.exit_code == 0);
  CHECK_THAT(mdev.err, Catch::Contains("streaming mode"));
}

TEST_CASE("characterize --stream refuses what needs the whole record", "[apps][stream]") {
  const std::string imu = kDatasets + "static_imu_100hz.csv --type-a --stream ";
  auto settle = Characterize(imu + "--settle auto");
  CHECK(settle.exit_code == 2);
  CHECK_THAT(settle.err, Catch::Contains("not available in streaming mode"));
  auto window = Characterize(imu + "--from-s 1");
  CHECK(window.exit_code == 2);
  CHECK_THAT(window.err, Catch::Contains("not available in streaming mode"));
  auto html = Characterize(imu + "--html /tmp/metro-stream-test-never-written.html");
  CHECK(html.exit_code == 2);
  CHECK_THAT(html.err, Catch::Contains("not available in streaming mode"));
}

}  // namespace metro
