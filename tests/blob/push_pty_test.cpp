// End to end over a real tty: the simulated tag (firmware/sim_tag, the tag's C receiver and
// update code on a RAM flash behind a pseudo-terminal) and the push client through SerialPort,
// then the `calibrate push` program, with injected link and flash faults.
#ifdef METRO_SIM_TAG_EXE

#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "metro/blob/push_client.hpp"
#include "metro/calibration/calibration_io.hpp"
#include "metro/core/file.hpp"
#include "metro/serial/serial_port.hpp"
#include "support/run_program.hpp"

extern char** environ;

namespace metro::blob {
namespace {

const std::string kGolden = std::string(METRO_SOURCE_DIR) + "/datasets/golden/";

// A running metro_sim_tag; SIGTERM and wait on destruction.
class SimTag {
 public:
  SimTag(const std::string& flash_file, const std::vector<std::string>& faults) {
    std::vector<std::string> args = {METRO_SIM_TAG_EXE, "--flash", flash_file};
    args.insert(args.end(), faults.begin(), faults.end());
    std::vector<char*> argv;
    for (std::string& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    int fds[2];
    REQUIRE(::pipe(fds) == 0);
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_adddup2(&fa, fds[1], STDOUT_FILENO);
    posix_spawn_file_actions_addclose(&fa, fds[0]);
    REQUIRE(::posix_spawn(&pid_, METRO_SIM_TAG_EXE, &fa, nullptr, argv.data(), environ) == 0);
    posix_spawn_file_actions_destroy(&fa);
    ::close(fds[1]);
    std::string line;
    char c;
    while (::read(fds[0], &c, 1) == 1 && c != '\n') line += c;
    ::close(fds[0]);
    REQUIRE(line.rfind("pty: ", 0) == 0);
    pty_ = line.substr(5);
  }
  ~SimTag() { Stop(); }
  // Ends the simulator (it saves its flash) and returns its exit status.
  int Stop() {
    if (pid_ > 0) {
      ::kill(pid_, SIGTERM);
      ::waitpid(pid_, &status_, 0);
      pid_ = -1;
    }
    return WIFEXITED(status_) ? WEXITSTATUS(status_) : -1;
  }
  const std::string& pty() const { return pty_; }

 private:
  pid_t pid_ = -1;
  int status_ = 0;
  std::string pty_;
};

std::vector<uint8_t> Bytes(const std::string& path) {
  Result<std::string> s = ReadFile(path);
  REQUIRE(s.ok());
  return std::vector<uint8_t>(s.value().begin(), s.value().end());
}

std::vector<uint8_t> Slot(const std::vector<uint8_t>& flash, int slot, size_t n) {
  REQUIRE(flash.size() == 2 * kPageSize);
  auto begin = flash.begin() + slot * static_cast<std::ptrdiff_t>(kPageSize);
  return std::vector<uint8_t>(begin, begin + static_cast<std::ptrdiff_t>(n));
}

}  // namespace

TEST_CASE("pty: the push client over SerialPort updates the simulated tag", "[blob][push]") {
  const std::string flash = "metro_pty_lib_flash.bin";
  std::remove(flash.c_str());
  const std::vector<uint8_t> golden = Bytes(kGolden + "tag_sensor2.bin");
  {
    SimTag sim(flash, {"--drop-frame", "7", "--corrupt-frame", "20", "--drop-response", "40"});
    Result<std::unique_ptr<serial::SerialPort>> port = serial::SerialPort::Open(sim.pty());
    REQUIRE(port.ok());
    // Another program cannot take the port while it is open.
    Result<std::unique_ptr<serial::SerialPort>> second = serial::SerialPort::Open(sim.pty());
    REQUIRE_FALSE(second.ok());
    CHECK(second.error().message.find("in use by another program") != std::string::npos);
    PushOptions o;
    o.timeout_ms = 200;
    PushClient client(port.value().get(), o);
    Result<TagInfo> info = client.GetInfo();
    REQUIRE(info.ok());
    CHECK(info.value().device_id == 0x9ABCDEF012345678ull);
    Result<int> slot = client.Push(golden);
    REQUIRE(slot.ok());
    CHECK(slot.value() == 0);
    CHECK(client.stats().retries == 3);
    CHECK(client.stats().naks == 1);
    CHECK(sim.Stop() == 0);
  }
  CHECK(Slot(Bytes(flash), 0, golden.size()) == golden);
  std::remove(flash.c_str());
}

TEST_CASE("pty: the simulated tag takes a blob with a section v2.0 (issue #25)", "[blob][push]") {
  // The tag's receiver and update code validate with the firmware of issue #25: a gyroscope of
  // 83.2 LSB/(deg/s) with unsigned counts (imu_tk's Xsens) is accepted and committed.
  Result<BlobContents> golden = DecodeBlob(Bytes(kGolden + "tag_sensor2.bin"));
  REQUIRE(golden.ok());
  BlobContents c = golden.value();
  const double s_nom = 3.14159265358979323846 / 180.0 / 83.2;
  for (double& m : c.gyro->m) m *= s_nom / (250.0 / 32768.0 * 3.14159265358979323846 / 180.0);
  c.gyro->s_nom_si_per_lsb = s_nom;
  c.gyro->input = kInputOffsetBinary;
  c.gyro->fs_sel = 1;
  Result<std::vector<uint8_t>> blob = WriteBlob(c);
  REQUIRE(blob.ok());
  const std::string flash = "metro_pty_v2_flash.bin";
  std::remove(flash.c_str());
  {
    SimTag sim(flash, {});
    Result<std::unique_ptr<serial::SerialPort>> port = serial::SerialPort::Open(sim.pty());
    REQUIRE(port.ok());
    PushOptions o;
    o.timeout_ms = 200;
    PushClient client(port.value().get(), o);
    Result<int> slot = client.Push(blob.value());
    REQUIRE(slot.ok());
    CHECK(slot.value() == 0);
    CHECK(sim.Stop() == 0);
  }
  CHECK(Slot(Bytes(flash), 0, blob.value().size()) == blob.value());
  std::remove(flash.c_str());
}

TEST_CASE("pty: SerialPort errors name the path", "[blob][push]") {
  Result<std::unique_ptr<serial::SerialPort>> p = serial::SerialPort::Open("/nonexistent/ttyX");
  REQUIRE_FALSE(p.ok());
  CHECK(p.error().ToString() == "/nonexistent/ttyX: cannot open: No such file or directory");
  const std::string plain = "metro_pty_plain.txt";
  REQUIRE(WriteFileAtomically(plain, "x").ok());
  p = serial::SerialPort::Open(plain);
  REQUIRE_FALSE(p.ok());
  CHECK(p.error().message.rfind("not a serial port (tcgetattr)", 0) == 0);
  std::remove(plain.c_str());
  p = serial::SerialPort::Open("/dev/null", 12345);
  REQUIRE_FALSE(p.ok());
  CHECK(p.error().message == "unsupported baud rate 12345");
}

#ifdef METRO_CALIBRATE_EXE
namespace {

struct Run {
  int exit_code;
  std::string err;
};

Run Push(const std::string& pty, const std::string& extra = "") {
  static int counter = 0;
  const std::string err_path =
      "metro_pty_err_" + std::to_string(::getpid()) + "_" + std::to_string(++counter) + ".txt";
  // The simulated tag's device (its default, the golden blob's): push refuses a tag whose
  // device ID is not known (issue #25), so the cases name it unless they give their own.
  const std::string device =
      extra.find("--device-id") == std::string::npos ? "--device-id 9ABCDEF012345678 " : "";
  const std::string cmd = std::string(METRO_CALIBRATE_EXE) + " push --port " + pty + " " + kGolden +
                          "calibration_sensor2.json --sensor 2 " + device + extra + " 2>" +
                          err_path;
  const int status = std::system(cmd.c_str());
  Run r{WIFEXITED(status) ? WEXITSTATUS(status) : -1, ""};
  std::ifstream err(err_path);
  std::stringstream ss;
  ss << err.rdbuf();
  r.err = ss.str();
  std::remove(err_path.c_str());
  return r;
}

// A flash image with `blob` in slot A and slot B erased.
std::string FlashWith(const std::string& name, const std::vector<uint8_t>& blob) {
  std::vector<uint8_t> img(2 * kPageSize, 0xFF);
  std::copy(blob.begin(), blob.end(), img.begin());
  REQUIRE(WriteFileAtomically(name, std::string(img.begin(), img.end())).ok());
  return name;
}

bool Has(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

}  // namespace

TEST_CASE("pty: calibrate push writes the golden blob despite link faults", "[blob][push][apps]") {
  const std::vector<uint8_t> golden = Bytes(kGolden + "tag_sensor2.bin");
  struct Case {
    const char* name;
    std::vector<std::string> faults;
    const char* link_line;
  };
  const std::vector<Case> cases = {
      {"clean", {}, "link: 72 requests, 72 frames sent, 0 retries, 0 NAKs, 0 timeouts"},
      {"lost frame",
       {"--drop-frame", "9"},
       "link: 72 requests, 73 frames sent, 1 retries, 0 NAKs, 1 timeouts"},
      {"duplicated frame",
       {"--dup-frame", "38"},
       "link: 72 requests, 72 frames sent, 0 retries, 0 NAKs, 0 timeouts"},
      {"corrupted frame",
       {"--corrupt-frame", "3"},
       "link: 72 requests, 73 frames sent, 1 retries, 1 NAKs, 0 timeouts"},
      {"lost answer",
       {"--drop-response", "38"},
       "link: 72 requests, 73 frames sent, 1 retries, 0 NAKs, 1 timeouts"},
  };
  for (const Case& c : cases) {
    SECTION(c.name) {
      const std::string flash = "metro_pty_flash.bin";
      std::remove(flash.c_str());
      SimTag sim(flash, c.faults);
      // seq 3 and this tag's id: the pushed blob is the golden file, byte for byte.
      Run r = Push(sim.pty(), "--seq 3 --timeout-ms 200");
      INFO(r.err);
      CHECK(r.exit_code == 0);
      CHECK(Has(r.err, "tag 9ABCDEF012345678: format 1.0, active slot none, seq 0"));
      CHECK(Has(r.err, c.link_line));
      CHECK(Has(r.err,
                "OK: tag 9ABCDEF012345678 calibrated: seq 3 in slot A, 540 bytes read "
                "back identical"));
      CHECK(sim.Stop() == 0);
      const std::vector<uint8_t> img = Bytes(flash);
      CHECK(Slot(img, 0, golden.size()) == golden);
      CHECK(Slot(img, 1, kPageSize) == std::vector<uint8_t>(kPageSize, 0xFF));
      std::remove(flash.c_str());
    }
  }
}

TEST_CASE("pty: calibrate push reports a stale seq and a disconnect and a flash error and no tag",
          "[blob][push][apps]") {
  const std::vector<uint8_t> golden = Bytes(kGolden + "tag_sensor2.bin");  // seq 3
  const std::string flash = "metro_pty_fault_flash.bin";

  SECTION("stale seq") {
    SimTag sim(FlashWith(flash, golden), {});
    Run r = Push(sim.pty(), "--seq 2");
    CHECK(r.exit_code == 1);
    CHECK(Has(r.err, "tag 9ABCDEF012345678: format 1.0, active slot A, seq 3"));
    CHECK(Has(r.err,
              "FAILED: CAL_CREATE: the tag answered STALE_SEQ (seq 2 is not above the "
              "tag's active seq)"));
    CHECK(Has(r.err, "to program over SWD instead: calibrate blob "));
    CHECK(Has(r.err, "nrfjprog -f NRF51 --program tag.hex --sectorerase --verify --reset"));
    sim.Stop();
    CHECK(Bytes(flash) == Bytes(FlashWith(flash + ".ref", golden)));
  }
  SECTION("disconnect mid-transfer, then a new session") {
    {
      SimTag sim(FlashWith(flash, golden), {"--hangup-after", "12"});
      Run r = Push(sim.pty(), "--timeout-ms 2000");  // The hang-up is seen at once.
      INFO(r.err);
      CHECK(r.exit_code == 1);
      CHECK(Has(r.err, "FAILED: CAL_WRITE: link lost: "));
      CHECK(Has(r.err, "the link hung up"));
      CHECK(sim.Stop() == 0);
    }
    CHECK(Slot(Bytes(flash), 0, golden.size()) == golden);  // the old calibration stays
    SimTag sim(flash, {});
    Run r = Push(sim.pty());
    CHECK(r.exit_code == 0);
    CHECK(Has(r.err, "OK: tag 9ABCDEF012345678 calibrated: seq 4 in slot B"));
    sim.Stop();
    CHECK(Slot(Bytes(flash), 0, golden.size()) == golden);
  }
  SECTION("flash write error") {
    SimTag sim(FlashWith(flash, golden), {"--flash-write-error", "1"});
    Run r = Push(sim.pty());
    CHECK(r.exit_code == 1);
    CHECK(Has(r.err, "FAILED: CAL_EXECUTE: the tag answered FLASH_ERROR"));
    sim.Stop();
    CHECK(Slot(Bytes(flash), 0, golden.size()) == golden);
  }
  SECTION("no answer") {
    SimTag sim(FlashWith(flash, golden),
               {"--drop-frame", "1", "--drop-frame", "2", "--drop-frame", "3"});
    Run r = Push(sim.pty(), "--timeout-ms 50 --retries 2");
    CHECK(r.exit_code == 1);
    CHECK(Has(r.err,
              "FAILED: no tag: GET_INFO: no valid answer after 3 attempts (no answer "
              "within 50 ms)"));
    CHECK(Has(r.err, "link: 1 requests, 3 frames sent, 2 retries, 0 NAKs, 3 timeouts"));
  }
  SECTION("another tag") {
    SimTag sim(FlashWith(flash, golden), {});
    Run r = Push(sim.pty(), "--device-id 0000000000000001");
    CHECK(r.exit_code == 2);
    CHECK(Has(r.err,
              "FAILED: the tag on the link is 9ABCDEF012345678, not 0000000000000001: "
              "nothing was written"));
  }
  SECTION("no port") {
    Run r = Push("/nonexistent/ttyX");
    CHECK(r.exit_code == 1);
    CHECK(r.err == "error: /nonexistent/ttyX: cannot open: No such file or directory\n");
  }
  std::remove(flash.c_str());
  std::remove((flash + ".ref").c_str());
}
TEST_CASE("pty: calibrate push says outcome unknown when the link drops after CAL_EXECUTE",
          "[blob][push][apps][security]") {
  // issue #20: the tag committed, its answer was lost with the link, and push said FAILED.
  const std::vector<uint8_t> golden = Bytes(kGolden + "tag_sensor2.bin");  // seq 3
  const std::string flash = "metro_pty_unknown_flash.bin";
  {
    // Frames: GET_INFO 1, CREATE 2, CAL_WRITE 3..36, GET_CRC 37, EXECUTE 38.
    SimTag sim(FlashWith(flash, golden), {"--drop-response", "38", "--hangup-after", "38"});
    Run r = Push(sim.pty(), "--timeout-ms 2000");
    INFO(r.err);
    CHECK(r.exit_code == 1);
    CHECK(Has(r.err, "outcome unknown: the tag may hold seq 4 (CAL_EXECUTE: link lost: "));
    CHECK_FALSE(Has(r.err, "FAILED"));
    CHECK(Has(r.err, "to find out: calibrate push --port " + sim.pty() + " " + kGolden +
                         "calibration_sensor2.json --sensor 2 --device-id 9ABCDEF012345678 "
                         "--seq 4 (a tag that holds this blob is only read back and compared; "
                         "one that does not gets seq 4)"));
    sim.Stop();
  }
  // It did commit; the advised command, with the flags it prints (the device ID included: a
  // push with no known device is refused), finds that out and writes nothing.
  SimTag sim(flash, {});
  Run r = Push(sim.pty(), "--device-id 9ABCDEF012345678 --seq 4");
  INFO(r.err);
  CHECK(r.exit_code == 0);
  CHECK(Has(r.err,
            "OK: tag 9ABCDEF012345678 already holds this calibration: seq 4 in slot B, 540 bytes "
            "read back identical; nothing written"));
  CHECK(Has(r.err, "link: 35 requests"));  // GET_INFO and 34 reads
  sim.Stop();
  std::remove(flash.c_str());
}

TEST_CASE("pty: calibrate push on an exhausted seq advises seq 1 over the wire path",
          "[blob][push][apps][security]") {
  // issue #20: at seq 4294967294 the advice named --seq 4294967295, which calibrate blob refuses.
  BlobContents c = DecodeBlob(Bytes(kGolden + "tag_sensor2.bin")).value();
  c.seq = kSeqMax;
  const std::string flash = "metro_pty_exhausted_flash.bin";
  SimTag sim(FlashWith(flash, WriteBlob(c).value()), {});
  Run r = Push(sim.pty());
  INFO(r.err);
  CHECK(r.exit_code == 1);
  CHECK(Has(r.err,
            "FAILED: the tag's seq is exhausted (4294967294); only the wired path (a factory HEX) "
            "resets it"));
  CHECK(Has(r.err, "--device-id 9ABCDEF012345678 --seq 1 -o tag.bin --hex tag.hex && nrfjprog"));
  CHECK_FALSE(Has(r.err, "4294967295"));
  sim.Stop();
  std::remove(flash.c_str());
}
// issue #25: which tag a push may reach. The simulated tag's FICR holds DEVICEID[0] 0x12345678
// and DEVICEID[1] 0x9ABCDEF0 (nrfjprog --memrd prints "12345678 9ABCDEF0").
TEST_CASE("pty: calibrate push reaches only a known device", "[blob][push][apps]") {
  const std::string flash = "metro_pty_known_flash.bin";
  const std::string tags = "metro_pty_tags.json";
  auto write_tags = [&](const std::string& json) { std::ofstream(tags) << json; };
  SECTION("no device ID known: refused before the port is opened") {
    std::remove(flash.c_str());
    SimTag sim(flash, {});
    Run r = Push(sim.pty(), "--device-id ''");
    CHECK(r.exit_code == 2);
    CHECK(Has(r.err,
              "error: no device ID known for sensor 2: give --device-id, --tags FILE with "
              "its device_id, or --any-device to write to whichever tag answers (nothing "
              "sent; " +
                  sim.pty() + " not opened)"));
    CHECK(sim.Stop() == 0);
    const std::vector<uint8_t> img = Bytes(flash);  // both slots still erased
    CHECK(Slot(img, 0, kPageSize) == std::vector<uint8_t>(kPageSize, 0xFF));
    CHECK(Slot(img, 1, kPageSize) == std::vector<uint8_t>(kPageSize, 0xFF));
  }
  SECTION("--any-device writes to whichever tag answers") {
    std::remove(flash.c_str());
    SimTag sim(flash, {});
    Run r = Push(sim.pty(), "--device-id '' --any-device --seq 3");
    INFO(r.err);
    CHECK(r.exit_code == 0);
    CHECK(Has(r.err, "OK: tag 9ABCDEF012345678 calibrated: seq 3 in slot A"));
  }
  SECTION("the device ID in nrfjprog's word order, and from a tags file") {
    std::remove(flash.c_str());
    SimTag sim(flash, {});
    Run r = Push(sim.pty(), "--device-id '0x12345678 0x9ABCDEF0' --seq 3");
    INFO(r.err);
    CHECK(r.exit_code == 0);
    write_tags(R"({"2": {"name": "Chest", "device_id": "12345678 9ABCDEF0"}})");
    r = Push(sim.pty(), "--device-id '' --tags " + tags + " --seq 4");
    INFO(r.err);
    CHECK(r.exit_code == 0);
    CHECK(Has(r.err, "OK: tag 9ABCDEF012345678 calibrated: seq 4 in slot B"));
  }
  SECTION("the tags file names another device for the sensor: nothing written") {
    std::remove(flash.c_str());
    SimTag sim(flash, {});
    write_tags(R"({"2": {"name": "Chest", "device_id": "0000000100000000"}})");
    Run r = Push(sim.pty(), "--device-id '' --tags " + tags);
    CHECK(r.exit_code == 2);
    CHECK(Has(r.err,
              "FAILED: the tag on the link is 9ABCDEF012345678, not 0000000100000000: "
              "nothing was written"));
    // --device-id against the tags file's ID for the sensor: refused before the port.
    r = Push(sim.pty(), "--device-id 9ABCDEF012345678 --tags " + tags);
    CHECK(r.exit_code == 2);
    // At the tags file's device_id: `{"2": {"name": "Chest", "device_id": ` is 37 characters.
    CHECK(
        Has(r.err, "error: " + tags +
                       ":1:38: --device-id 9ABCDEF012345678 is not sensor 2's device "
                       "0000000100000000 in the tags file; expected --device-id 0000000100000000"));
  }
  std::remove(flash.c_str());
  std::remove(tags.c_str());
}

// --all: every tag of calibration.json, each to its own device. On the simulated tag's port
// only sensor 2's device answers: sensor 2 is written and read back, sensor 3 is refused (the
// tag on the link is not its device) with nothing written, and the table says so.
TEST_CASE("pty: calibrate push --all pushes each tag to its own device", "[blob][push][apps]") {
  const std::string flash = "metro_pty_all_flash.bin";
  const std::string tags = "metro_pty_all_tags.json";
  const std::string cal = "metro_pty_all_cal.json";
  std::remove(flash.c_str());
  std::ofstream(tags) << R"({"2": {"name": "Chest", "device_id": "12345678 9ABCDEF0"},
                             "3": {"name": "Left Arm", "device_id": "0011223344556677"}})";
  Result<Calibration> golden = LoadCalibration(kGolden + "calibration_sensor2.json");
  REQUIRE(golden.ok());
  Calibration two = golden.value();
  two.tags.push_back(two.tags.front());
  two.tags.back().sensor = 3;
  REQUIRE(WriteFileAtomically(cal, FormatCalibrationJson(two)).ok());
  {
    SimTag sim(flash, {});
    testing::ProgramRun r = testing::RunProgram(
        METRO_CALIBRATE_EXE, "push --port " + sim.pty() + " " + cal + " --all --tags " + tags);
    INFO(r.err);
    CHECK(r.exit_code == 2);
    CHECK(Has(r.err,
              "OK: tag 9ABCDEF012345678 calibrated: seq 1 in slot A, 540 bytes read back "
              "identical"));
    CHECK(Has(r.err,
              "FAILED: the tag on the link is 9ABCDEF012345678, not 0011223344556677: "
              "nothing was written"));
    CHECK(r.out ==
          "sensor  name              device            result\n"
          "     2  Chest             9ABCDEF012345678  OK: seq 1 in slot A, read back identical\n"
          "     3  Left Arm          0011223344556677  FAILED\n");
    CHECK(sim.Stop() == 0);
  }
  // The tag holds sensor 2's blob (seq 1), as calibrate blob writes it for that device.
  const std::vector<uint8_t> img = Bytes(flash);
  Result<BlobContents> held = DecodeBlob(Slot(img, 0, 540), 0x9ABCDEF012345678ull);
  REQUIRE(held.ok());
  CHECK(held.value().seq == 1);
  // A tag without a device ID stops --all before the port is opened.
  std::ofstream(tags) << R"({"2": {"name": "Chest", "device_id": "12345678 9ABCDEF0"}})";
  testing::ProgramRun r = testing::RunProgram(
      METRO_CALIBRATE_EXE, "push --port /nonexistent/tty " + cal + " --all --tags " + tags);
  CHECK(r.exit_code == 2);
  CHECK(r.err ==
        "error: sensor 3: no device ID in the tags file or calibration.json (nothing "
        "sent; /nonexistent/tty not opened)\n");
  std::remove(flash.c_str());
  std::remove(tags.c_str());
  std::remove(cal.c_str());
}

TEST_CASE("pty: a lying tag's push is labelled MISMATCH and recorded so in the registry",
          "[blob][push][apps][security][issue37]") {
  // issue #37: a tag that acknowledged the blob but read back other bytes was labelled
  // "UNVERIFIED: ... the read-back did not finish" and recorded as "committed, read-back not
  // finished"; one that named another seq or CRC-32 was a plain FAILED.
  const std::vector<uint8_t> golden = Bytes(kGolden + "tag_sensor2.bin");  // seq 3
  const std::string flash = "metro_pty_liar_flash.bin";
  const std::string reg = "metro_pty_liar_registry.sqlite";
  struct Case {
    const char* lie;
    const char* line;      // stderr's final line
    const char* readback;  // the registry's push record
  };
  const std::vector<Case> cases = {
      {"readback",
       "MISMATCH: the tag contradicts itself (read-back differs) pushing seq 3: read-back: byte 0 "
       "of the active slot is 0x48, sent 0x49; what it runs is unknown until its flash is read "
       "over SWD",
       "differs: byte 0 of the active slot is 0x48, sent 0x49"},
      {"execute-seq",
       "MISMATCH: the tag contradicts itself (seq differs) pushing seq 3: CAL_EXECUTE: the tag "
       "answered SUCCESS with seq 4, sent 3",
       "not read back: the tag contradicted itself (seq differs): CAL_EXECUTE: the tag answered "
       "SUCCESS with seq 4, sent 3"},
      {"get-crc",
       "MISMATCH: the tag contradicts itself (CRC-32 differs) pushing seq 3: CAL_GET_CRC: "
       "the tag acknowledged every byte but holds 540 bytes with CRC-32",
       "not read back: the tag contradicted itself (CRC-32 differs): CAL_GET_CRC: the tag "
       "acknowledged every byte"},
  };
  for (const Case& c : cases) {
    SECTION(c.lie) {
      std::remove(flash.c_str());
      std::remove(reg.c_str());
      // The line recorded the device's blob first, so its history shows the push.
      testing::ProgramRun blob = testing::RunProgram(
          METRO_CALIBRATE_EXE, "blob " + kGolden +
                                   "calibration_sensor2.json --sensor 2 --device-id "
                                   "9ABCDEF012345678 -o metro_pty_liar.bin --registry " +
                                   reg);
      REQUIRE(blob.exit_code == 0);
      std::remove("metro_pty_liar.bin");
      SimTag sim(flash, {"--lie", c.lie});
      Run r = Push(sim.pty(), "--seq 3 --timeout-ms 200 --retries 1 --registry " + reg);
      INFO(r.err);
      CHECK(r.exit_code == 1);
      CHECK(Has(r.err, c.line));
      CHECK_FALSE(Has(r.err, "OK:"));
      CHECK_FALSE(Has(r.err, "UNVERIFIED"));
      CHECK_FALSE(Has(r.err, "FAILED"));
      CHECK_FALSE(Has(r.err, "to find out"));  // A second push would be answered alike.
      CHECK(Has(r.err, "to program over SWD instead: calibrate blob "));
      CHECK(Has(r.err,
                "registry: recorded push to device 9ABCDEF012345678 (MISMATCH: the tag "
                "contradicted itself)"));
      sim.Stop();
      testing::ProgramRun h =
          testing::RunProgram(METRO_CALIBRATE_EXE, "registry history --json --registry " + reg +
                                                       " --device-id 9ABCDEF012345678");
      INFO(h.out + h.err);
      REQUIRE(h.exit_code == 0);
      const std::string json = h.out;
      CHECK(Has(json, "\"ok\": false"));
      CHECK(Has(json, std::string("\"readback\": \"") + c.readback));
    }
  }
  std::remove(flash.c_str());
  for (const char* suffix : {"", "-shm", "-wal"}) std::remove((reg + suffix).c_str());
}

#endif  // METRO_CALIBRATE_EXE

}  // namespace metro::blob

#endif  // METRO_SIM_TAG_EXE
