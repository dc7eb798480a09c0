// metro_sim_tag's command line (issue #25 point 6: `metro_sim_tag --help` works).
#include <catch2/catch.hpp>
#include <string>

#include "support/run_program.hpp"

namespace metro {
namespace {

#ifdef METRO_SIM_TAG_EXE
TEST_CASE("metro_sim_tag --help lists its options with their defaults", "[blob][apps]") {
  const testing::ProgramRun help = testing::RunProgram(METRO_SIM_TAG_EXE, "--help");
  CHECK(help.exit_code == 0);
  for (const char* option :
       {"--device-id", "--flash", "--drop-frame", "--dup-frame", "--corrupt-frame",
        "--drop-response", "--hangup-after", "--flash-write-error"}) {
    CHECK(help.out.find(option) != std::string::npos);
  }
  CHECK(help.out.find("9ABCDEF012345678") != std::string::npos);  // the default device ID
  // Bad arguments: exit 2 with the reason, before any terminal is opened.
  testing::ProgramRun bad = testing::RunProgram(METRO_SIM_TAG_EXE, "--drop-frame 0");
  CHECK(bad.exit_code == 2);
  CHECK(bad.out.find("pty:") == std::string::npos);
  bad = testing::RunProgram(METRO_SIM_TAG_EXE, "--device-id 12");
  CHECK(bad.exit_code == 2);
  CHECK(bad.err.find("--device-id takes 16 hex digits") != std::string::npos);
  bad = testing::RunProgram(METRO_SIM_TAG_EXE, "--frobnicate 1");
  CHECK(bad.exit_code == 2);
}
#endif

}  // namespace
}  // namespace metro
