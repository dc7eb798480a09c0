// Issue #37 point 6, "the re-attack's commands kept as tests": the classes of the re-attack
// that had no test through the programs yet (the others: tests/registry/registry_cli_test.cpp
// for the registry as an output and its schema_version; tests/apps/outputs_cli_test.cpp for
// capture -o, the tags file as an output, SIGINT/SIGTERM cleanup and SIGXFSZ;
// tests/apps/subcommands_cli_test.cpp for simulate --reference-output without --kind table).
// Each runs the attack as a user would, and checks the exit code (1 or 2), that the message
// names the file and the cause, and that the file a user owns is unchanged (its SHA-256).
#include <sys/stat.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "metro/blob/blob.hpp"
#include "metro/core/file.hpp"
#include "support/run_program.hpp"
#include "support/temp_file.hpp"

namespace metro {
namespace {

namespace fs = std::filesystem;
using Run = testing::ProgramRun;

const std::string kDatasets = std::string(METRO_SOURCE_DIR) + "/datasets/";
const std::string kChest = kDatasets + "static_chest.csv";
const std::string kGoldenBin = kDatasets + "golden/tag_sensor2.bin";
const std::string kGoldenCal = kDatasets + "golden/calibration_sensor2.json";

Run Characterize(const std::string& args) {
  return testing::RunProgram(METRO_CHARACTERIZE_EXE, args);
}
Run Calibrate(const std::string& args) { return testing::RunProgram(METRO_CALIBRATE_EXE, args); }

using Dir = testing::WorkDir;
using testing::Put;

std::string Hash(const std::string& path) {
  Result<std::string> sha = Sha256File(path);
  REQUIRE(sha.ok());
  return sha.value();
}

bool Has(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

// An old report the attack must leave as it was.
struct OldOutput {
  explicit OldOutput(std::string p) : path(std::move(p)) {
    Put(path, "old report\n");
    sha256 = Hash(path);
  }
  bool Unchanged() const { return Hash(path) == sha256; }
  std::string path;
  std::string sha256;
};

TEST_CASE("Re-attack: --columns-file /dev/zero stops at once, naming it (exit 2)",
          "[apps][security][issue37]") {
  // It grew to 11 GB in 120 s.
  Dir d;
  const OldOutput old(d / "r.json");
  const auto start = std::chrono::steady_clock::now();
  Run r = testing::RunProgram("timeout 60 " + std::string(METRO_CHARACTERIZE_EXE),
                              kChest + " --type-a --columns-file /dev/zero -o " + old.path);
  INFO(r.err);
  CHECK(r.exit_code == 2);
  CHECK(r.err.rfind("error: /dev/zero", 0) == 0);
  CHECK(std::chrono::steady_clock::now() - start < std::chrono::seconds(30));
  CHECK(old.Unchanged());
}

TEST_CASE("Re-attack: yes | characterize - (and convert -, fit -, apply -) stops at the cap",
          "[apps][security][issue37][stdin]") {
  // It grew about 1 GB/s without a cap. A 1 MB cap (METRO_MAX_STREAM_BYTES) keeps the test short.
  Dir d;
  const OldOutput old(d / "out");
  const std::string cap = "METRO_MAX_STREAM_BYTES=1000000 timeout 60 ";
  for (const std::string& command :
       {cap + METRO_CHARACTERIZE_EXE + " - --type-a -o " + old.path,
        cap + METRO_CHARACTERIZE_EXE + " convert - -o " + old.path,
        cap + METRO_CALIBRATE_EXE + " fit - -o " + old.path,
        cap + METRO_CALIBRATE_EXE + " apply " + kGoldenCal + " - -o " + old.path}) {
    INFO(command);
    Run r = testing::run_program_internal::RunShell("yes | " + command);
    INFO(r.err);
    CHECK(r.exit_code == 2);
    CHECK(Has(r.err, "error: "));
    CHECK(Has(r.err, "stdin"));
    CHECK(Has(r.err, "1000000"));
    CHECK(Has(r.err, "METRO_MAX_STREAM_BYTES"));
    CHECK(old.Unchanged());
  }
}

TEST_CASE("Re-attack: a FIFO named as the session is read, and its errors name it",
          "[apps][security][issue37]") {
  // It got "the file changed while metro read it".
  Dir d;
  const std::string fifo = d / "session.fifo";
  REQUIRE(::mkfifo(fifo.c_str(), 0600) == 0);
  const OldOutput old(d / "r.json");
  std::thread writer([&fifo] {
    std::ofstream out(fifo, std::ios::binary);
    out << "t_s,pitch_deg\n0,1\n1,oops\n";
  });
  Run r = testing::RunProgram("timeout 60 " + std::string(METRO_CHARACTERIZE_EXE),
                              fifo + " --type-a -o " + old.path);
  writer.join();
  INFO(r.err);
  CHECK(r.exit_code == 2);
  CHECK(r.err.rfind("error: " + fifo + ":3:2: ", 0) == 0);
  CHECK_FALSE(Has(r.err, "changed"));
  CHECK(old.Unchanged());
}

TEST_CASE("Re-attack: CR-only line ends with a leading comment are read as lines",
          "[apps][security][issue37]") {
  // The whole file was taken for one comment line and refused as empty.
  Dir d;
  const OldOutput old(d / "r.json");
  const std::string bad = d / "cr.csv";
  Put(bad, "# logged by hand\rt_s,pitch_deg\r0,1\r1,oops\r");
  Run r = Characterize(bad + " --type-a -o " + old.path);
  INFO(r.err);
  CHECK(r.exit_code == 2);
  CHECK(r.err.rfind("error: " + bad + ":4:2: ", 0) == 0);  // the bad value, on its line
  CHECK(old.Unchanged());
  const std::string good = d / "cr_good.csv";
  Put(good, "# logged by hand\rt_s,pitch_deg\r0,1\r1,2\r2,3\r");
  r = Characterize(good + " --type-a -o " + d / "good.json");
  INFO(r.err);
  CHECK(r.exit_code == 0);
}

TEST_CASE("Re-attack: a raw logger's bad Fs line is refused at its line and column",
          "[apps][security][issue37]") {
  // A bad `Fs,` line was skipped silently.
  Dir d;
  const OldOutput old(d / "r.json");
  for (const std::string value : {"abc", "", "0"}) {
    INFO(value);
    const std::string raw = d / "raw.csv";
    Put(raw, "Logging Type,1\nFs," + value + "\nax,ay,az\n0,0,16384\n0,0,16384\n0,0,8192\n");
    Run r = Characterize(raw + " --type-a --accel-fs-g 2 -o " + old.path);
    INFO(r.err);
    CHECK(r.exit_code == 2);
    CHECK(r.err.rfind("error: " + raw + ":2:4: ", 0) == 0);
    CHECK(Has(r.err, "Fs"));
    CHECK(old.Unchanged());
  }
}

TEST_CASE("Re-attack: calibrate inspect names a sensor refusal METRO_FW_E_SENSOR",
          "[apps][security][issue37]") {
  // It said METRO_FW_E_UNKNOWN(-14) for every sensor refusal.
  Dir d;
  Result<std::string> golden = ReadFile(kGoldenBin);
  REQUIRE(golden.ok());
  std::string bin = golden.value();
  // accel and gyro M[0] (section bodies at 0x0B0 and 0x168, M after 8 bytes) = NaN, CRC fixed.
  for (size_t at : {size_t{0x0B0 + 8}, size_t{0x168 + 8}}) {
    const std::string nan("\x00\x00\xc0\x7f", 4);
    bin.replace(at, 4, nan);
  }
  const uint32_t crc = blob::Crc32(reinterpret_cast<const uint8_t*>(bin.data()), bin.size() - 4);
  for (int i = 0; i < 4; ++i) bin[bin.size() - 4 + i] = static_cast<char>((crc >> (8 * i)) & 0xFF);
  const std::string path = d / "nan.bin";
  Put(path, bin);
  const std::string sha = Hash(path);
  Run r = Calibrate("inspect " + path);
  INFO(r.out + r.err);
  CHECK(r.exit_code == 1);
  CHECK(Has(r.out, path + " (bin)"));
  CHECK(Has(r.out, "METRO_FW_E_SENSOR"));
  CHECK_FALSE(Has(r.out, "METRO_FW_E_UNKNOWN"));
  CHECK(Has(r.out, "result: REFUSED"));
  CHECK(Hash(path) == sha);  // Inspect only reads.
}

}  // namespace
}  // namespace metro
