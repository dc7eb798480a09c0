// characterize's explicit subcommands `analyze` and `accuracy` (issue #25 point 7): each gives
// byte for byte what today's spelling gives (`characterize SESSION --type-a ...`,
// `characterize SESSION --accuracy ...`), which keeps working as an alias; options of the other
// mode are refused (exit 2); --help lists the accepted values and defaults.
#include <unistd.h>

#include <catch2/catch.hpp>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "metro/core/file.hpp"
#include "support/run_program.hpp"
#include "support/temp_file.hpp"

namespace metro {
namespace {

using Run = testing::ProgramRun;

const std::string kDatasets = std::string(METRO_SOURCE_DIR) + "/datasets/";

// A scratch folder for this file's outputs, removed when the test program ends.
const std::string& Scratch() {
  static const testing::ScratchFolder folder("metro_subcommands");
  return folder.path();
}

Run Characterize(const std::string& args) {
  return testing::RunProgram(METRO_CHARACTERIZE_EXE, args);
}

std::string Slurp(const std::string& path) {
  Result<std::string> text = ReadFile(path);
  REQUIRE(text.ok());
  return text.value();
}

// Both spellings give the same exit code, stdout and stderr.
void CheckSameRun(const Run& old_spelling, const Run& new_spelling) {
  INFO(old_spelling.err);
  INFO(new_spelling.err);
  CHECK(old_spelling.exit_code == 0);
  CHECK(new_spelling.exit_code == old_spelling.exit_code);
  CHECK(new_spelling.out == old_spelling.out);
  CHECK(new_spelling.err == old_spelling.err);
}

}  // namespace

TEST_CASE("characterize analyze SESSION gives the JSON of characterize SESSION --type-a",
          "[apps][subcommands]") {
  const std::string chest = kDatasets + "static_chest.csv";
  // The JSON on stdout, the warnings on stderr.
  Run old_run = Characterize(chest + " --type-a");
  Run new_run = Characterize("analyze " + chest);
  CheckSameRun(old_run, new_run);
  REQUIRE(old_run.out.find("\"sensors\"") != std::string::npos);
  // --type-a is accepted (implied) by analyze.
  CheckSameRun(old_run, Characterize("analyze " + chest + " --type-a"));
  // The spelling without --type-a (the default analysis) is the same, too.
  CheckSameRun(old_run, Characterize(chest));

  // Window and settle options, -o FILE and the table on stdout.
  const std::string a = Scratch() + "metro_subcommands_old.json";
  const std::string b = Scratch() + "metro_subcommands_new.json";
  std::remove(a.c_str());
  std::remove(b.c_str());
  old_run = Characterize(chest + " --type-a --skip-seconds 2 --settle auto -o " + a);
  new_run = Characterize("analyze " + chest + " --skip-seconds 2 --settle auto -o " + b);
  CheckSameRun(old_run, new_run);
  CHECK(Slurp(a) == Slurp(b));
  CHECK_THAT(Slurp(a), Catch::Contains("\"skip_seconds\""));
}

TEST_CASE("characterize analyze --allan gives the report and curves of SESSION --type-a --allan",
          "[apps][subcommands]") {
  const std::string imu = kDatasets + "static_imu_100hz.csv";
  const std::string csv_a = Scratch() + "metro_subcommands_old_allan.csv";
  const std::string csv_b = Scratch() + "metro_subcommands_new_allan.csv";
  Run old_run = Characterize(imu + " --type-a --allan --taus decade:4 --allan-csv " + csv_a +
                             " -o " + Scratch() + "metro_subcommands_old_allan.json");
  Run new_run = Characterize("analyze " + imu + " --allan --taus decade:4 --allan-csv " + csv_b +
                             " -o " + Scratch() + "metro_subcommands_new_allan.json");
  // The table names no file, so stdout and stderr are the same.
  CheckSameRun(old_run, new_run);
  CHECK(Slurp(Scratch() + "metro_subcommands_old_allan.json") ==
        Slurp(Scratch() + "metro_subcommands_new_allan.json"));
  CHECK(Slurp(csv_a) == Slurp(csv_b));
  CHECK_THAT(Slurp(csv_a), Catch::Contains("tau_s"));
}

TEST_CASE("characterize accuracy SESSION gives the JSON of characterize SESSION --accuracy",
          "[apps][subcommands]") {
  const std::string sweep = kDatasets + "table_sweep.csv";
  Run old_run = Characterize(sweep + " --accuracy");
  Run new_run = Characterize("accuracy " + sweep);
  CheckSameRun(old_run, new_run);
  REQUIRE(old_run.out.find("\"plateaus\"") != std::string::npos);
  // --accuracy is implied and accepted.
  CheckSameRun(old_run, Characterize("accuracy " + sweep + " --accuracy"));
  // Its own options, a window option and -o -: the same report and table.
  old_run = Characterize(sweep +
                         " --accuracy --table-axis yaw --min-dwell-s 4 --reference-u 0.01 "
                         "--error-model harmonic1 --skip-seconds 1 -o -");
  new_run = Characterize("accuracy " + sweep +
                         " --table-axis yaw --min-dwell-s 4 --reference-u 0.01 "
                         "--error-model harmonic1 --skip-seconds 1 -o -");
  CheckSameRun(old_run, new_run);
  CHECK_THAT(new_run.out, Catch::Contains("harmonic1"));
}

TEST_CASE("characterize analyze and accuracy refuse the other mode's options (exit 2)",
          "[apps][subcommands]") {
  const std::string chest = kDatasets + "static_chest.csv";
  const std::string sweep = kDatasets + "table_sweep.csv";
  for (const std::string& args : std::vector<std::string>{
           "analyze " + chest + " --accuracy", "analyze " + chest + " --table-axis yaw",
           "accuracy " + sweep + " --allan", "accuracy " + sweep + " --type-a",
           "accuracy " + sweep + " --budget " + kDatasets + "budgets/gum_h1_end_gauge.json",
           "analyze", "accuracy"}) {
    INFO(args);
    const Run r = Characterize(args);
    CHECK(r.exit_code == 2);
    CHECK(r.out.empty());
  }
  // Within one mode, the rule of the old spelling holds: --taus needs --allan.
  Run r = Characterize("analyze " + chest + " --taus octave");
  CHECK(r.exit_code == 2);
  CHECK_THAT(r.err, Catch::Contains("--taus needs --allan"));
}

TEST_CASE("characterize simulate refuses an output its kind does not write (exit 2)",
          "[apps][subcommands]") {
  const std::string out = Scratch() + "sim_refused.csv";
  for (const std::string& args : std::vector<std::string>{
           "simulate -o " + out + " --reference-output " + Scratch() + "ref.csv",
           "simulate --kind calibration -o " + out + " --reference-output " + Scratch() + "ref.csv",
           "simulate -o " + out + " --truth-output " + Scratch() + "truth.json"}) {
    INFO(args);
    const Run r = Characterize(args);
    CHECK(r.exit_code == 2);
    CHECK_THAT(r.err, Catch::Contains("only with --kind table") ||
                          Catch::Contains("--kind table, calibration or thermal"));
    CHECK_FALSE(std::filesystem::exists(out));
  }
}

TEST_CASE("characterize --help lists analyze and accuracy and their --help the values and defaults",
          "[apps][subcommands]") {
  Run r = Characterize("--help");
  CHECK(r.exit_code == 0);
  for (const char* sub :
       {"analyze", "accuracy", "budget", "batch", "convert", "simulate", "report", "capture"}) {
    INFO(sub);
    CHECK_THAT(r.out, Catch::Contains(std::string("\n  ") + sub + " "));
  }
  r = Characterize("analyze --help");
  CHECK(r.exit_code == 0);
  // CLI11 prints the accepted values in braces and the default after '='.
  CHECK_THAT(r.out, Catch::Contains("--settle TEXT:{none,auto}=none"));
  CHECK_THAT(r.out, Catch::Contains("--settle-scope TEXT:{quantity,tag}=quantity"));
  CHECK_THAT(r.out, Catch::Contains("--taus TEXT=octave"));
  CHECK_THAT(r.out, Catch::Contains("--estimator TEXT=oadev"));
  CHECK_THAT(r.out, Catch::Contains("--gaps TEXT:{skip,split,refuse}=skip"));
  CHECK(r.out.find("--table-axis") == std::string::npos);
  r = Characterize("accuracy --help");
  CHECK(r.exit_code == 0);
  CHECK_THAT(r.out, Catch::Contains("--table-axis TEXT:{yaw,pitch,roll}=yaw"));
  CHECK_THAT(r.out, Catch::Contains("--error-model TEXT:{auto,linear,harmonic1,harmonic2}=auto"));
  CHECK_THAT(r.out, Catch::Contains("--min-dwell-s FLOAT:POSITIVE=3"));
  CHECK_THAT(r.out, Catch::Contains("--settle TEXT:{none,auto}=none"));
  CHECK(r.out.find("--allan") == std::string::npos);
}

}  // namespace metro
