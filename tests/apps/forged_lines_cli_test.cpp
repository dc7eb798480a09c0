// Issue #37 (lower): newlines from data printed raw forged output lines (a "result: valid"
// inside a blob inspect refuses). Every string a program prints from a file it read (a blob,
// calibration.json, a tags file, a budget, the registry, a directory listing) is one field of
// one line: its control characters are escaped (metro/core/terminal_text.hpp), so no line
// of the output starts with text the data carried.
#include <unistd.h>

#include <catch2/catch.hpp>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
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

std::string Get(const std::string& path) {
  Result<std::string> text = ReadFile(path);
  REQUIRE(text.ok());
  return text.value();
}

// The line of `text` that starts with `forged` (leading blanks skipped), or "" when none does.
std::string ForgedLine(const std::string& text, const std::string& forged) {
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    const size_t first = line.find_first_not_of(" \t");
    if (first != std::string::npos && line.compare(first, forged.size(), forged) == 0) return line;
  }
  return "";
}

// `bytes` with its last four bytes the CRC-32 of the rest (the blob's own CRC word).
std::string WithCrc(std::string bytes) {
  const uint32_t crc =
      blob::Crc32(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size() - 4);
  for (int i = 0; i < 4; ++i) {
    bytes[bytes.size() - 4 + i] = static_cast<char>((crc >> (8 * i)) & 0xFF);
  }
  return bytes;
}

TEST_CASE("Forged lines: calibrate inspect of a refused image prints no 'result: valid' line",
          "[apps][security][issue37]") {
  Dir d;
  // The golden blob's reference_id (META body at 0x28, its offset 80: 16 ASCII bytes,
  // NUL-padded; docs/calibration-blob.md 2.3) becomes "\nresult: valid", the CRC is fixed,
  // and 4 bytes after total_len make inspect refuse the file.
  std::string bin = Get(kGoldenBin);
  const std::string forged("\nresult: valid\0\0", 16);
  bin.replace(0x28 + 80, forged.size(), forged);
  bin = WithCrc(bin);
  Result<blob::BlobContents> decoded =
      blob::DecodeBlob(std::vector<uint8_t>(bin.begin(), bin.end()));
  REQUIRE(decoded.ok());
  REQUIRE(decoded.value().meta.reference_id == "\nresult: valid");
  const std::string path = d / "forged.bin";
  Put(path, bin + std::string(4, '\0'));
  Run r = Calibrate("inspect " + path);
  INFO(r.out);
  CHECK(r.exit_code == 1);
  CHECK(ForgedLine(r.out, "result: valid").empty());
  CHECK_FALSE(ForgedLine(r.out, "result: REFUSED").empty());
  CHECK(r.out.find("reference '\\nresult: valid'") != std::string::npos);

  // The tags file's name of the blob's tag, in inspect's note on stderr.
  const std::string tags = d / "tags.json";
  Put(tags, R"({"2": {"name": "Chest\nresult: valid", "device_id": "9ABCDEF012345678"}})");
  r = Calibrate("inspect " + kGoldenBin + " --tags " + tags);
  INFO(r.err);
  CHECK(r.exit_code == 0);
  CHECK(ForgedLine(r.err, "result: valid").empty());
  CHECK(r.err.find("(Chest\\nresult: valid)") != std::string::npos);
}

TEST_CASE("Forged lines: tag names from a tags file stay in their row",
          "[apps][security][issue37]") {
  Dir d;
  const std::string tags = d / "tags.json";
  Put(tags, R"({"2": {"name": "Chest\nFORGED 2 pitch_deg", "device_id": "9ABCDEF012345678"}})");
  // characterize's table (stdout).
  Run r = Characterize(kChest + " --type-a --tags " + tags + " -o " + d / "r.json");
  INFO(r.err);
  REQUIRE(r.exit_code == 0);
  CHECK(ForgedLine(r.out, "FORGED") == "");
  CHECK(r.out.find("Chest\\nFORGED") != std::string::npos);
  // calibrate report's tag lines (stdout).
  r = Calibrate("report " + kGoldenCal + " --tags " + tags);
  INFO(r.err);
  CHECK(r.exit_code == 0);
  CHECK(ForgedLine(r.out, "FORGED") == "");
  // calibrate push --all's table (stdout), printed although no port opens.
  r = Calibrate("push " + kGoldenCal + " --all --tags " + tags + " --port " + d / "no-tty");
  INFO(r.err);
  CHECK(r.exit_code == 1);
  CHECK(ForgedLine(r.out, "FORGED") == "");
  CHECK(r.out.find("Chest\\nFORGED") != std::string::npos);
}

TEST_CASE("Forged lines: calibration.json strings in calibrate report",
          "[apps][security][issue37]") {
  Dir d;
  std::string cal = Get(kGoldenCal);
  const std::string version = "\"tool_version\": \"metro 0.1.0\"";
  const size_t at = cal.find(version);
  REQUIRE(at != std::string::npos);
  cal.replace(at, version.size(), "\"tool_version\": \"metro\\nFORGED: tool\"");
  const size_t input = cal.find("\"path\": \"golden_session.csv\"");
  REQUIRE(input != std::string::npos);
  cal.replace(input, std::string("\"path\": \"golden_session.csv\"").size(),
              "\"path\": \"s.csv\\nFORGED: input\"");
  Put(d / "c.json", cal);
  Run r = Calibrate("report " + d / "c.json");
  INFO(r.out + r.err);
  CHECK(r.exit_code == 0);
  CHECK(ForgedLine(r.out, "FORGED") == "");
  CHECK(r.out.find("metro\\nFORGED: tool") != std::string::npos);
}

TEST_CASE("Forged lines: registry history and export keep one record per line",
          "[apps][security][issue37][registry]") {
  Dir d;
  const std::string reg = d / "reg.sqlite";
  Run r = Calibrate("blob " + kGoldenCal + " --sensor 2 --device-id 9ABCDEF012345678 -o " +
                    d / "t.bin --registry " + reg +
                    " --station 'line-2\nFORGED station' --operator 'ops\nFORGED op'");
  INFO(r.err);
  REQUIRE(r.exit_code == 0);
  r = Calibrate("registry history --registry " + reg + " --device-id 9ABCDEF012345678");
  INFO(r.out + r.err);
  CHECK(r.exit_code == 0);
  CHECK(ForgedLine(r.out, "FORGED") == "");
  CHECK(r.out.find("station line-2\\nFORGED station") != std::string::npos);
  r = Calibrate("registry export --registry " + reg);
  INFO(r.out + r.err);
  CHECK(r.exit_code == 0);
  CHECK(ForgedLine(r.out, "FORGED") == "");
  CHECK(r.out.find(",line-2\\nFORGED station,ops\\nFORGED op,") != std::string::npos);
  // The JSON export keeps the text as recorded (JSON escapes it itself).
  r = Calibrate("registry export --format json --registry " + reg);
  CHECK(r.exit_code == 0);
  CHECK(r.out.find("line-2\\nFORGED station") != std::string::npos);
}

TEST_CASE("Forged lines: budget names in characterize budget's table",
          "[apps][security][issue37]") {
  Dir d;
  Put(d / "b.json", R"({"measurand": {"name": "y\nFORGED: measurand", "unit": "m"},
  "inputs": [{"name": "a\nFORGED: input", "value": 1, "u": 0.1, "sensitivity": 1},
             {"name": "b", "value": 2, "u": 0.2, "sensitivity": 1}],
  "monte_carlo": false})");
  Run r = Characterize("budget " + d / "b.json -o " + d / "r.json");  // The table on stdout.
  INFO(r.out + r.err);
  CHECK(r.exit_code == 0);
  CHECK(ForgedLine(r.out, "FORGED") == "");
  CHECK(r.out.find("a\\nFORGED: input") != std::string::npos);
}

TEST_CASE("Forged lines: file names in batch and convert", "[apps][security][issue37]") {
  Dir d;
  fs::create_directories(d / "in");
  // A session that fails (its table line FAILED <file>: ...) and one that is skipped.
  Put(d / "in/s\nFORGED one.csv", "t_s,pitch_deg\n0,1\n1,oops\n");
  Put(d / "in/ok.csv", Get(kChest));
  Run r = Characterize("batch " + d / "in" + " --type-a -o " + d / "out");
  INFO(r.out + r.err);
  CHECK(r.exit_code == 1);
  CHECK(ForgedLine(r.out, "FORGED") == "");
  CHECK(ForgedLine(r.err, "FORGED") == "");
  CHECK(ForgedLine(Get(d / "out/summary.txt"), "FORGED") == "");
  // convert names its input in a comment of session.csv: a newline there would start a row.
  Put(d / "c\n1,FORGED.csv", Get(kChest));
  r = Characterize("convert '" + d / "c\n1,FORGED.csv' -o " + d / "c.csv");
  INFO(r.err);
  REQUIRE(r.exit_code == 0);
  CHECK(ForgedLine(Get(d / "c.csv"), "1,FORGED") == "");
  CHECK(ForgedLine(r.err, "1,FORGED") == "");
}

}  // namespace
}  // namespace metro
