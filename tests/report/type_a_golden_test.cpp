// The main job's numbers stay what they were before issue #38's speed work: every bundled
// session's `characterize --type-a` report against the one the build of e20f3ca wrote
// (datasets/golden/type_a_reports/, SOURCE.md there), plot data aside.
#ifdef METRO_CHARACTERIZE_EXE
#include <catch2/catch.hpp>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <string>

#include "support/run_program.hpp"
#include "support/temp_file.hpp"

namespace metro {
namespace {

// The AR spectral fit's outputs and the coverage factor from its dof: within 1e-9 (the old
// lattice's own rounding, datasets/golden/SOURCE.md).
const std::set<std::string> kArKeys = {"u_mean", "U_mean", "u_mean_dof", "u_mean_ar", "k"};

void CompareJson(const nlohmann::json& expected, const nlohmann::json& actual,
                 const std::string& path, const std::string& key, int* numbers) {
  INFO(path);
  if (expected.is_object()) {
    REQUIRE(actual.is_object());
    for (const auto& [k, v] : expected.items()) {
      if (k == "plot") continue;
      REQUIRE(actual.contains(k));
      CompareJson(v, actual[k], path + "/" + k, k, numbers);
    }
    for (const auto& [k, v] : actual.items()) {
      (void)v;
      if (k != "plot") CHECK(expected.contains(k));
    }
  } else if (expected.is_array()) {
    REQUIRE(actual.is_array());
    REQUIRE(actual.size() == expected.size());
    for (size_t i = 0; i < expected.size(); ++i) {
      CompareJson(expected[i], actual[i], path + "[" + std::to_string(i) + "]", key, numbers);
    }
  } else if (expected.is_number() && !expected.is_boolean()) {
    REQUIRE(actual.is_number());
    const double e = expected.get<double>();
    const double a = actual.get<double>();
    const double tolerance = kArKeys.count(key) > 0 ? 1e-9 : 1e-12;
    CHECK(std::abs(a - e) <= tolerance * std::max(std::abs(e), std::abs(a)));
    ++*numbers;
  } else {
    CHECK(actual == expected);
  }
}

TEST_CASE("The bundled sessions' Type A reports keep their numbers (golden, issue #38)",
          "[report][golden]") {
  const std::string source = METRO_SOURCE_DIR;
  for (const std::string dataset :
       {"static_chest.csv", "static_chest_receiver.txt", "static_imu_100hz.csv",
        "capture_15tags.csv", "capture_15tags_receiver.txt", "table_sweep.csv",
        "calibration_session.csv"}) {
    CAPTURE(dataset);
    testing::TempFile out("", ".json");
    const testing::ProgramRun run = testing::RunProgram(
        METRO_CHARACTERIZE_EXE, source + "/datasets/" + dataset + " --type-a -o " + out.path());
    REQUIRE(run.exit_code == 0);
    std::ifstream expected_in(source + "/datasets/golden/type_a_reports/" + dataset + ".json");
    std::ifstream actual_in(out.path());
    REQUIRE(expected_in.good());
    const nlohmann::json expected = nlohmann::json::parse(expected_in);
    const nlohmann::json actual = nlohmann::json::parse(actual_in);
    // The input's path is the only string allowed to differ (the golden file's was relative).
    nlohmann::json actual_same_input = actual;
    actual_same_input["input"]["path"] = expected["input"]["path"];
    int numbers = 0;
    CompareJson(expected, actual_same_input, "", "", &numbers);
    CHECK(numbers > 100);
  }
}

}  // namespace
}  // namespace metro
#endif  // METRO_CHARACTERIZE_EXE
