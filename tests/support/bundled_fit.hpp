// calibration.json fitted from the bundled calibration session, once per build (tests only).
//
// ctest starts every test case as its own process, and several CLI tests need the same fit of
// datasets/calibration_session.csv; under the sanitizers one fit takes 50-100 s, so each
// process fitting again cost minutes of the sanitizer suite. The fit is kept in
// METRO_BINARY_DIR/test-cache/, named by its arguments, and fitted again whenever the
// calibrate program or the session is newer than the file. It is written to a temporary name
// and renamed, so processes that fit at the same time each leave a whole file (the fit is
// deterministic: calibration.json is byte-identical across runs, tests/calibration).
#pragma once

#include <catch2/catch.hpp>
#include <cctype>
#include <filesystem>
#include <string>

#include "support/run_program.hpp"

namespace metro::testing {

// The path of `calibrate fit datasets/calibration_session.csv -q <extra_args>`'s output.
inline std::string BundledFit(const std::string& extra_args) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::path(METRO_BINARY_DIR) / "test-cache";
  fs::create_directories(dir);
  const std::string session = std::string(METRO_SOURCE_DIR) + "/datasets/calibration_session.csv";
  std::string name = "fit";
  for (char c : extra_args) name += std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
  const fs::path out = dir / (name + ".json");
  std::error_code ec;
  const fs::file_time_type made = fs::last_write_time(out, ec);
  if (!ec && made > fs::last_write_time(METRO_CALIBRATE_EXE) &&
      made > fs::last_write_time(session)) {
    return out.string();
  }
  const fs::path tmp = dir / (name + "." + std::to_string(::getpid()) + ".tmp.json");
  const ProgramRun r = RunProgram(METRO_CALIBRATE_EXE,
                                  "fit " + session + " -q -o " + tmp.string() + " " + extra_args);
  INFO(r.err);
  REQUIRE(r.exit_code == 0);
  fs::rename(tmp, out);
  return out.string();
}

}  // namespace metro::testing
