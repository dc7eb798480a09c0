// End-to-end tests of characterize SESSION --accuracy and simulate --kind table.
#include <sys/wait.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "support/run_program.hpp"

namespace metro {
namespace {

using Run = testing::ProgramRun;

Run Characterize(const std::string& args) {
  return testing::RunProgram(METRO_CHARACTERIZE_EXE, args);
}

const std::string kSweep = std::string(METRO_SOURCE_DIR) + "/datasets/table_sweep.csv";

TEST_CASE("characterize --accuracy on the bundled table sweep", "[apps][accuracy]") {
  const std::string out = "metro_acc_report.json";
  std::remove(out.c_str());
  Run r = Characterize(kSweep + " --accuracy --reference-u 0.01 -o " + out);
  REQUIRE(r.exit_code == 0);
  CHECK(r.out.find("hysteresis (up - down)") != std::string::npos);
  std::ifstream in(out);
  const auto j = nlohmann::json::parse(in);
  CHECK(j["schema"] == "metro.accuracy-report/1");
  CHECK(j["points"].size() == 29);
  // datasets/regenerate.sh: hysteresis 0.15 deg and tilt 0.4 deg by default.
  CHECK(j["hysteresis"]["mean_deg"].get<double>() == Approx(0.15).margin(0.03));
  CHECK(j["options"]["reference_u_deg"] == 0.01);
  std::remove(out.c_str());
  // Without -o: JSON on stdout.
  Run stdout_run = Characterize(kSweep + " --accuracy --table-axis yaw");
  REQUIRE(stdout_run.exit_code == 0);
  CHECK(nlohmann::json::parse(stdout_run.out)["input"]["table_axis"] == "yaw");
}

TEST_CASE("characterize --accuracy with a receiver capture and a reference log",
          "[apps][accuracy]") {
  const std::string cap = "metro_acc_cap.txt", ref = "metro_acc_ref.csv";
  Run sim = Characterize("simulate --kind table --sweeps 1 --format receiver --reference-output " +
                         ref + " --reference-offset-s 1 -o " + cap);
  REQUIRE(sim.exit_code == 0);
  Run r = Characterize(cap + " --accuracy --reference " + ref);
  REQUIRE(r.exit_code == 0);
  const auto j = nlohmann::json::parse(r.out);
  const auto& a = j["input"]["reference"]["alignment"];
  CHECK(a["estimated"] == true);
  CHECK(a["offset_s"].get<double>() == Approx(1.0).margin(0.4));
  CHECK(a.contains("residual_std_deg"));
  std::remove(cap.c_str());
  std::remove((cap + ".truth.json").c_str());  // The simulator's truth sidecar.
  std::remove(ref.c_str());
}

TEST_CASE("characterize --accuracy honours the window options", "[apps][accuracy]") {
  // The rows of the bundled sweep, counted here from the file.
  std::ifstream file(kSweep);
  std::string line;
  std::vector<double> t_s;
  while (std::getline(file, line)) {
    if (line.empty() || line[0] == '#' || line.rfind("t_s", 0) == 0) continue;
    t_s.push_back(std::stod(line.substr(0, line.find(','))));
  }
  REQUIRE(t_s.size() > 1000);
  Run all = Characterize(kSweep + " --accuracy");
  REQUIRE(all.exit_code == 0);
  const auto full = nlohmann::json::parse(all.out);
  CHECK(full["window"]["n"] == t_s.size());

  Run late = Characterize(kSweep + " --accuracy --from-s 100 --to-s 500");
  REQUIRE(late.exit_code == 0);
  const auto j = nlohmann::json::parse(late.out);
  const size_t kept = static_cast<size_t>(
      std::count_if(t_s.begin(), t_s.end(), [](double t) { return t >= 100 && t <= 500; }));
  CHECK(j["window"]["n_total"] == t_s.size());
  CHECK(j["window"]["n"] == kept);
  CHECK(j["window"]["from_s"] == 100.0);
  CHECK(j["points"].size() < full["points"].size());
  for (const auto& p : j["points"]) {
    CHECK(p["t_start_s"].get<double>() >= 100.0);
    CHECK(p["t_end_s"].get<double>() <= 500.0);
  }
  Run skip = Characterize(kSweep + " --accuracy --skip-samples 1000");
  REQUIRE(skip.exit_code == 0);
  CHECK(nlohmann::json::parse(skip.out)["window"]["n"] == t_s.size() - 1000);

  Run none = Characterize(kSweep + " --accuracy --from-s 1e6");
  CHECK(none.exit_code == 2);
  CHECK(none.err.find("keeps no observation of tag") != std::string::npos);
}

TEST_CASE("characterize --accuracy bad input exits 2 with the message", "[apps][accuracy]") {
  Run axis = Characterize(kSweep + " --accuracy --table-axis heading");
  CHECK(axis.exit_code == 2);
  CHECK(axis.err == "error: unknown table axis 'heading' (expected yaw, pitch or roll)\n");
  Run both = Characterize(kSweep + " --accuracy --type-a");
  CHECK(both.exit_code == 2);
  CHECK(both.err.find("--accuracy and --type-a are separate analyses") != std::string::npos);
  Run few = Characterize(kSweep + " --accuracy --min-dwell-s 100");
  CHECK(few.exit_code == 2);
  CHECK(few.err.find("no plateau found") != std::string::npos);
  Run no_table =
      Characterize(std::string(METRO_SOURCE_DIR) + "/datasets/static_chest.csv --accuracy");
  CHECK(no_table.exit_code == 2);
  CHECK(no_table.err.find("has no table_angle_deg column") != std::string::npos);
}

}  // namespace
}  // namespace metro
