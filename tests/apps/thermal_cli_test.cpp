// `characterize simulate --kind thermal` and `calibrate fit --thermal` (docs/thermal.md): the
// bundled session regenerates byte for byte, the fit recovers its truth, bad input exits 2.
#include <catch2/catch.hpp>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "support/run_program.hpp"
#include "support/temp_file.hpp"

namespace metro {
namespace {

using Run = testing::ProgramRun;

const std::string kDatasets = std::string(METRO_SOURCE_DIR) + "/datasets/";

const std::string& Scratch() {
  static const testing::ScratchFolder folder("metro_thermal_cli");
  return folder.path();
}

std::string ReadAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// The command of datasets/regenerate.sh.
const char* kBundledArgs =
    "simulate --kind thermal --seed 42 --sensor 2 --rate-hz 1 --thermal-profile ramp "
    "--ramp-s 1800 --cooling-leg --bias-order 3 --accel-hysteresis-g 0.004 "
    "--gyro-hysteresis-dps 0.15 --temp-glitches 3 -q";

TEST_CASE("thermal CLI: the bundled session regenerates byte for byte", "[apps][thermal]") {
  const std::string out = Scratch() + "thermal.csv";
  const Run r =
      testing::RunProgram(METRO_CHARACTERIZE_EXE, std::string(kBundledArgs) + " -o " + out);
  REQUIRE(r.exit_code == 0);
  CHECK(ReadAll(out) == ReadAll(kDatasets + "thermal_session.csv"));
  CHECK(ReadAll(out + ".truth.json") == ReadAll(kDatasets + "thermal_session.csv.truth.json"));
}

TEST_CASE("thermal CLI: calibrate fit --thermal recovers the bundled truth within 3u",
          "[apps][thermal]") {
  const std::string out = Scratch() + "thermal_fit.json";
  const Run r = testing::RunProgram(METRO_CALIBRATE_EXE,
                                    "fit --thermal " + kDatasets + "thermal_session.csv -o " + out);
  REQUIRE(r.exit_code == 0);
  const auto truth = nlohmann::json::parse(ReadAll(kDatasets + "thermal_session.csv.truth.json"));
  const auto fit = nlohmann::json::parse(ReadAll(out));
  for (const auto& line : truth["temp_glitch_lines"]) {
    CHECK_THAT(r.err, Catch::Contains("thermal_session.csv:" + std::to_string(line.get<int>()) +
                                      ": temp_c is a read error"));
  }
  const char* names[5] = {"bias", "bias_per_c", "bias_per_c2", "bias_per_c3", "bias_per_c4"};
  for (const char* sensor : {"accel", "gyro"}) {
    const auto& s = fit["tags"][0][sensor];
    CHECK(s["excluded_temp_lines"] == truth["temp_glitch_lines"]);
    CHECK(s["t_ref_c"].get<double>() == Approx(truth["t_ref_c"].get<double>()).margin(0.5));
    for (int a = 0; a < 3; ++a) {
      const auto& ax = s["axes"][a];
      const auto& c = truth[sensor]["bias_coefficients_lsb_per_c_pow_j"][a];
      // The fit's t_ref_c differs from the truth's: compare b(T) and its u at T = truth t_ref.
      const int order = ax["order"].get<int>();
      CHECK(order >= 3);
      // Coefficients about the same reference when the two t_ref agree to 0.05 degC.
      if (std::abs(s["t_ref_c"].get<double>() - truth["t_ref_c"].get<double>()) < 0.05) {
        for (int j = 1; j <= order; ++j) {
          const double true_c = j < static_cast<int>(c.size()) ? c[j].get<double>() : 0.0;
          CHECK(std::abs(ax[names[j]].get<double>() - true_c) <=
                3.0 * ax[std::string(names[j]) + "_u"].get<double>());
        }
      }
      CHECK(std::abs(ax["hysteresis"].get<double>() -
                     truth[sensor]["hysteresis_lsb"][a].get<double>()) <=
            3.0 * ax["hysteresis_u"].get<double>());
    }
  }
}

TEST_CASE("thermal CLI: no temp_c column and a span too small exit 2, named", "[apps][thermal]") {
  // Without temp_c: the bundled session with its last column dropped.
  const std::string no_temp = Scratch() + "no_temp.csv";
  {
    std::ifstream in(kDatasets + "thermal_session.csv");
    std::ofstream o(no_temp);
    std::string line;
    while (std::getline(in, line)) o << line.substr(0, line.rfind(',')) << "\n";
  }
  Run r = testing::RunProgram(METRO_CALIBRATE_EXE,
                              "fit --thermal " + no_temp + " -o " + Scratch() + "x.json");
  CHECK(r.exit_code == 2);
  CHECK_THAT(r.err, Catch::Contains("sensor 2 accel: no temp_c column"));
  // 25 -> 28 degC: order 1 needs 5 degC.
  const std::string narrow = Scratch() + "narrow.csv";
  r = testing::RunProgram(METRO_CHARACTERIZE_EXE,
                          "simulate --kind thermal --sensor 2 --temp-low-c 25 --temp-high-c 28 "
                          "--ramp-s 600 -q -o " +
                              narrow);
  REQUIRE(r.exit_code == 0);
  r = testing::RunProgram(METRO_CALIBRATE_EXE,
                          "fit --thermal " + narrow + " -o " + Scratch() + "y.json");
  CHECK(r.exit_code == 2);
  CHECK_THAT(r.err, Catch::Contains("order 1 needs at least 5.0 degC"));
}

}  // namespace
}  // namespace metro
