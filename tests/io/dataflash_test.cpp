// ArduPilot DataFlash reader and loader against a real ArduPilot log, pymavlink's test.BIN
// (datasets/external/ardupilot_pymavlink_test_bin): message counts and every IMU/IMU2 value
// against pymavlink's own reader's output written beside it (test_dfreader.json, an
// independent reader); then byte edits of that file for the time order and each class of bad
// input, and a small log written here from the format's description for the I column.
#include "metro/io/dataflash.hpp"

#include <fmt/format.h>

#include <catch2/catch.hpp>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "metro/io/session_io.hpp"
#include "support/temp_file.hpp"

namespace metro {
namespace {

using testing::TempFile;

const std::string kDir = std::string(METRO_EXTERNAL_DATA_DIR) + "/ardupilot_pymavlink_test_bin/";

std::string Slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

bool SameBits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// The test's own walk: offsets of the messages of type `type` (lengths from the FMT
// messages, read here with fixed offsets: type at 3, length at 4).
std::vector<size_t> Offsets(const std::string& b, int type) {
  int length[256] = {};
  length[128] = 89;
  std::vector<size_t> out;
  size_t p = 0;
  while (p + 3 <= b.size() && length[static_cast<unsigned char>(b[p + 2])] > 0) {
    const int t = static_cast<unsigned char>(b[p + 2]);
    if (p + static_cast<size_t>(length[t]) > b.size()) break;
    if (t == 128)
      length[static_cast<unsigned char>(b[p + 3])] = static_cast<unsigned char>(b[p + 4]);
    if (t == type) out.push_back(p);
    p += static_cast<size_t>(length[t]);
  }
  return out;
}

LoadOptions Lenient() {
  LoadOptions o;
  o.lenient = true;
  return o;
}

TEST_CASE("DataFlash: test.BIN's message counts equal pymavlink's", "[io][dataflash]") {
  const auto want = nlohmann::json::parse(Slurp(kDir + "test_dfreader.json"));
  const std::string path = kDir + "test.BIN";
  CHECK(DetectSessionFormat(path).value() == SessionFormat::kDataFlash);
  // The file is the first 65536 bytes of a log: its last message is cut.
  // The test's walk: the message at 65512 is of type 141, which an FMT names AHR2, 45 bytes.
  const std::string b = Slurp(path);
  REQUIRE(b.size() == 65536);
  REQUIRE(static_cast<unsigned char>(b[65512 + 2]) == 141);
  REQUIRE(b.find(std::string("\xA3\x95\x80\x8d\x2d"
                             "AHR2",
                             9)) != std::string::npos);
  auto strict = ReadDataFlash(path);
  REQUIRE_FALSE(strict.ok());
  CHECK(strict.error().ToString() ==
        path +
            ": byte offset 65512: truncated file: a message of type 141 (AHR2) of 45 bytes, 24 "
            "left; expected a complete message (--lenient reads the messages before it)");
  auto log = ReadDataFlash(path, {true, {}});
  REQUIRE(log.ok());
  CHECK(log.value().truncated_bytes == 24);
  int64_t total = 0;
  for (const auto& [name, count] : want["counts"].items()) {
    INFO(name);
    const DataFlashFormat* f = log.value().Find(name);
    REQUIRE(f != nullptr);
    CHECK(f->message_count == count.get<int64_t>());
    total += count.get<int64_t>();
  }
  CHECK(log.value().message_count == total);
}

TEST_CASE("DataFlash: IMU and IMU2 load bit for bit as two tags", "[io][dataflash]") {
  const auto want = nlohmann::json::parse(Slurp(kDir + "test_dfreader.json"));
  auto r = LoadSession(kDir + "test.BIN", Lenient());
  REQUIRE(r.ok());
  const Session& s = r.value();
  CHECK(s.format == SessionFormat::kDataFlash);
  REQUIRE(s.tags.size() == 2);
  const char* columns[] = {"gx_rads", "gy_rads", "gz_rads", "ax_mps2",
                           "ay_mps2", "az_mps2", "temp_c"};
  const int64_t t0_us = want["imu"]["IMU"][0][0].get<int64_t>();
  CHECK(t0_us == want["imu"]["IMU2"][0][0].get<int64_t>());
  for (size_t k = 0; k < 2; ++k) {
    const std::string name = k == 0 ? "IMU" : "IMU2";
    const nlohmann::json& rows = want["imu"][name];
    const Tag& t = s.tags[k];
    INFO(name);
    CHECK(t.source_name == name);
    REQUIRE(t.size() == rows.size());
    REQUIRE(t.size() == 45);
    int64_t mismatches = 0;
    for (size_t i = 0; i < rows.size(); ++i) {
      const int64_t t_us = rows[i][0].get<int64_t>();
      mismatches += t.t_ns[i] != t_us * 1000;
      mismatches += t.t_s[i] != static_cast<double>(t_us - t0_us) * 1e-6;
      for (int c = 0; c < 7; ++c) {
        mismatches += !SameBits(t.Find(columns[c])->values[i], rows[i][c + 1].get<double>());
      }
    }
    CHECK(mismatches == 0);
  }
  CHECK(s.tags[0].Find("gx_rads")->unit == "rad/s");
  CHECK(s.tags[0].Find("temp_c")->unit == "degC");
  CHECK(s.input.time_unit == "us");
  CHECK(s.input.warnings ==
        std::vector<std::string>{"truncated file: the last 24 bytes are an incomplete message, "
                                 "skipped (--lenient)"});
  LoadOptions one = Lenient();
  one.topics = {"IMU2"};
  auto imu2 = LoadSession(kDir + "test.BIN", one);
  REQUIRE(imu2.ok());
  REQUIRE(imu2.value().tags.size() == 1);
  CHECK(imu2.value().tags[0].source_name == "IMU2");
  one.topics = {"IMU3"};
  auto none = LoadSession(kDir + "test.BIN", one);
  REQUIRE_FALSE(none.ok());
  CHECK(none.error().message ==
        "--topic IMU3: expected one of the log's IMU messages: IMU (45 messages), IMU2 (45 "
        "messages) (NAME[K] for instance K of a message with an I column; `characterize topics " +
            kDir + "test.BIN` lists all)");
}

TEST_CASE("DataFlash: out-of-order and repeated TimeUS are sorted or refused (--time-order)",
          "[io][dataflash]") {
  const std::string good = Slurp(kDir + "test.BIN").substr(0, 65512);  // Whole messages only.
  const auto imu = Offsets(good, 133);  // IMU's type in this log (its FMT).
  REQUIRE(imu.size() == 45);
  const size_t body = 53 - 3;
  std::string b = good;
  b.replace(imu[10] + 3, body, good.substr(imu[11] + 3, body));
  b.replace(imu[11] + 3, body, good.substr(imu[10] + 3, body));
  b.replace(imu[21] + 3, body, good.substr(imu[20] + 3, body));
  TempFile file(b, ".bin");
  auto sorted = LoadSession(file.path());
  REQUIRE(sorted.ok());
  const Tag& t = sorted.value().tags[0];
  REQUIRE(t.size() == 44);
  auto u64 = [&](size_t at) {
    uint64_t v = 0;
    std::memcpy(&v, good.data() + at + 3, 8);
    return static_cast<int64_t>(v);
  };
  for (size_t i = 0; i < 44; ++i) {
    const size_t j = i < 21 ? i : i + 1;
    if (t.t_ns[i] != u64(imu[j]) * 1000) FAIL("sample " << i);
  }
  const auto& notes = sorted.value().input.notes;
  CHECK(std::count(notes.begin(), notes.end(),
                   "IMU: 1 messages out of TimeUS order, sorted; 1 repeated TimeUS dropped (the "
                   "first in the file kept) (--time-order sort)") == 1);
  LoadOptions refuse;
  refuse.time_order = LoadOptions::TimeOrder::kRefuse;
  auto r = LoadSession(file.path(), refuse);
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().message ==
        fmt::format("byte offset {}: IMU message 12: TimeUS {} us is not after the previous "
                    "message's {} us; expected increasing times (--time-order sort sorts them)",
                    imu[11], u64(imu[10]), u64(imu[11])));
}

TEST_CASE("DataFlash: IMU with an instance column gives one tag per instance", "[io][dataflash]") {
  // A log written here from the format's description: FMT of FMT, FMT of IMU with "I", then
  // four IMU messages alternating instances 1 and 0.
  auto fmt_message = [](int type, int length, const std::string& name, const std::string& format,
                        const std::string& columns) {
    std::string m = "\xA3\x95\x80";
    m += static_cast<char>(type);
    m += static_cast<char>(length);
    m += name + std::string(4 - name.size(), '\0');
    m += format + std::string(16 - format.size(), '\0');
    m += columns + std::string(64 - columns.size(), '\0');
    return m;
  };
  std::string b = fmt_message(128, 89, "FMT", "BBnNZ", "Type,Length,Name,Format,Columns");
  b += fmt_message(20, 3 + 8 + 1 + 7 * 4, "IMU", "QBfffffff",
                   "TimeUS,I,GyrX,GyrY,GyrZ,AccX,AccY,AccZ,T");
  const float values[4][7] = {{0.5f, -0.25f, 0.125f, 1.5f, -2.5f, -9.75f, 30.5f},
                              {0.1f, 0.2f, 0.3f, 0.4f, 0.5f, -9.8f, 31.25f},
                              {-0.5f, 0.25f, -0.125f, -1.5f, 2.5f, -9.5f, 30.75f},
                              {1e-3f, 2e-3f, 3e-3f, 4e-3f, 5e-3f, -9.81f, 31.5f}};
  for (int i = 0; i < 4; ++i) {
    b += "\xA3\x95\x14";
    const uint64_t t_us = 1000000 + 2500 * static_cast<uint64_t>(i / 2);
    b.append(reinterpret_cast<const char*>(&t_us), 8);  // The test runs little endian (x86-64).
    b += static_cast<char>(1 - i % 2);
    b.append(reinterpret_cast<const char*>(values[i]), 28);
  }
  TempFile file(b, ".bin");
  auto r = LoadSession(file.path());
  REQUIRE(r.ok());
  REQUIRE(r.value().tags.size() == 2);
  const Tag& i1 = r.value().tags[0];  // Instance 1 met first.
  const Tag& i0 = r.value().tags[1];
  CHECK(i1.source_name == "IMU[1]");
  CHECK(i0.source_name == "IMU[0]");
  REQUIRE(i1.size() == 2);
  CHECK(i1.Find("gx_rads")->values == std::vector<double>{0.5f, -0.5f});
  CHECK(i0.Find("az_mps2")->values == std::vector<double>{-9.8f, -9.81f});
  CHECK(i0.Find("temp_c")->values == std::vector<double>{31.25f, 31.5f});
  CHECK(i0.t_s == std::vector<double>{0.0, 0.0025});
  LoadOptions o;
  o.topics = {"IMU[0]"};
  auto only = LoadSession(file.path(), o);
  REQUIRE(only.ok());
  REQUIRE(only.value().tags.size() == 1);
  CHECK(only.value().tags[0].source_name == "IMU[0]");
}

TEST_CASE("DataFlash: bad input names the file and the byte offset", "[io][dataflash]") {
  const std::string good = Slurp(kDir + "test.BIN").substr(0, 65512);
  LoadOptions dataflash;
  dataflash.format = SessionFormat::kDataFlash;
  SECTION("not a DataFlash log") {
    std::string b = good;
    b[5] = 'X';
    TempFile file(b, ".bin");
    auto r = LoadSession(file.path(), dataflash);
    REQUIRE_FALSE(r.ok());
    CHECK(r.error().message ==
          "byte offset 0: expected an ArduPilot DataFlash log's first message, the FMT that "
          "defines FMT: a3 95 80 80 59 46 4d 54 (header, type 128, length 89, \"FMT\"), found a3 "
          "95 80 80 59 58 4d 54");
  }
  SECTION("a message of a type no FMT defined, and bytes that are not a header") {
    const auto imu = Offsets(good, 133);
    std::string b = good;
    b[imu[5] + 2] = 5;  // No FMT defines type 5.
    TempFile file(b, ".bin");
    auto r = LoadSession(file.path());
    REQUIRE_FALSE(r.ok());
    CHECK(r.error().message ==
          fmt::format("byte offset {}: a message of type 5, which no FMT message before it "
                      "defines; expected a defined type (--lenient skips to the next message)",
                      imu[5]));
    auto skipped = LoadSession(file.path(), Lenient());
    REQUIRE(skipped.ok());
    CHECK(skipped.value().tags[0].size() == 44);
    CHECK(skipped.value().input.warnings.back() ==
          "53 bytes that were not a message skipped to the next message header (--lenient)");
    std::string c = good;
    c[imu[7]] = 0x00;
    TempFile file_c(c, ".bin");
    auto rc = ReadDataFlash(file_c.path());
    REQUIRE_FALSE(rc.ok());
    CHECK(rc.error().message == fmt::format("byte offset {}: expected a message header a3 95, "
                                            "found 00 95 (--lenient skips to the next message)",
                                            imu[7]));
  }
  SECTION("an FMT with an unknown format character or a wrong length") {
    const size_t fmt_imu = good.find(std::string("IMU\0QffffffIIfBBHH", 18)) - 5;
    REQUIRE(good[fmt_imu + 3] == static_cast<char>(133));
    std::string b = good;
    b[fmt_imu + 3 + 6 + 1] = 'y';
    TempFile file(b, ".bin");
    auto r = ReadDataFlash(file.path());
    REQUIRE_FALSE(r.ok());
    CHECK_THAT(r.error().message,
               Catch::StartsWith(fmt::format(
                   "byte offset {}: FMT of type 133 'IMU' (format \"Qyfffff", fmt_imu)));
    CHECK_THAT(r.error().message, Catch::Contains("unknown format character 'y'; expected one"));
    std::string c = good;
    c[fmt_imu + 4] = 54;  // Length 54: one byte more than the fields.
    TempFile file_c(c, ".bin");
    auto rc = ReadDataFlash(file_c.path());
    REQUIRE_FALSE(rc.ok());
    CHECK_THAT(rc.error().message,
               Catch::EndsWith("Length 54 bytes, but its fields and the 3-byte header add up to "
                               "53; expected equal"));
  }
  SECTION("--topic that is not an IMU message") {
    LoadOptions o = Lenient();
    o.topics = {"ATT"};
    auto r = LoadSession(kDir + "test.BIN", o);
    REQUIRE_FALSE(r.ok());
    CHECK_THAT(r.error().message,
               Catch::StartsWith("--topic ATT: expected one of the log's IMU messages: IMU (45 "
                                 "messages), IMU2 (45 messages)"));
  }
}

}  // namespace
}  // namespace metro
