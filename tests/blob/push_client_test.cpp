// The push client against the tag's own receiver (firmware/src/push.c) in memory, with the
// link faults of docs/calibration-blob.md section 7: lost, duplicated and corrupted frames,
// lost answers, a stale seq, a disconnect mid-transfer, a flash error and a silent tag.
#include "metro/blob/push_client.hpp"

#include <fmt/format.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <deque>
#include <functional>
#include <map>
#include <optional>
#include <set>

#include "blob/blob_test_support.hpp"
#include "metro_fw/crc.h"
#include "metro_fw/push.h"
#include "tests/test_support.hpp"

namespace metro::blob {
namespace {

using RamFlash = fwtest::FakeFlash;  // The firmware tests' RAM flash (nRF51 semantics).

constexpr uint32_t kIdWords[2] = {0x12345678u, 0x9ABCDEF0u};  // testing::kDeviceId

// The tag behind a lossy link. Faults count the PC's SLIP frames and the tag's answers from 1.
// Read never waits: an empty queue is an immediate timeout, so retries cost no time.
class LossyTag : public serial::ByteStream {
 public:
  explicit LossyTag(RamFlash* flash) : flash_if_(flash->Interface()) {
    REQUIRE(metro_fw_push_init(&push_, &flash_if_, kIdWords, &LossyTag::Send, this) == METRO_FW_OK);
  }
  std::set<int> drop_frames, dup_frames, corrupt_frames, drop_answers;
  int hangup_after = -1;  // frames
  std::function<void()> after_execute;
  // A tag that lies: rewrites the payload (result byte first) of its answer to `op` before it
  // is framed again with a valid CRC-16.
  std::function<void(uint8_t op, std::vector<uint8_t>* payload)> lie;
  int frames = 0, answers = 0;
  bool hung_up = false;

  Status Write(const uint8_t* data, size_t size) override {
    if (hung_up) return MakeError("hung up");
    for (size_t i = 0; i < size; ++i) {
      if (data[i] != METRO_FW_SLIP_END) {
        pending_.push_back(data[i]);
        continue;
      }
      if (pending_.empty()) continue;
      ++frames;
      std::vector<uint8_t> wire{METRO_FW_SLIP_END};
      wire.insert(wire.end(), pending_.begin(), pending_.end());
      wire.push_back(METRO_FW_SLIP_END);
      const uint8_t op = pending_[0];
      pending_.clear();
      if (corrupt_frames.count(frames)) wire[wire.size() / 2] ^= 0x04;
      const int copies = drop_frames.count(frames) ? 0 : dup_frames.count(frames) ? 2 : 1;
      for (int k = 0; k < copies; ++k) {
        metro_fw_push_rx(&push_, wire.data(), static_cast<uint32_t>(wire.size()));
      }
      if (op == METRO_FW_OP_CAL_EXECUTE && push_.updated && after_execute) {
        push_.updated = 0;
        after_execute();
      }
      if (frames == hangup_after) hung_up = true;
    }
    return Status::Ok();
  }
  Result<size_t> Read(uint8_t* data, size_t capacity, int) override {
    if (hung_up && out_.empty()) return MakeError("hung up");
    size_t n = 0;
    while (n < capacity && !out_.empty()) {
      data[n++] = out_.front();
      out_.pop_front();
    }
    return n;
  }

 private:
  static int Send(void* ctx, const uint8_t* data, uint32_t len) {
    auto* self = static_cast<LossyTag*>(ctx);
    if (self->drop_answers.count(++self->answers)) return 0;
    if (!self->lie) {
      self->out_.insert(self->out_.end(), data, data + len);
      return 0;
    }
    SlipDecoder decoder(METRO_FW_PUSH_MAX_FRAME);
    std::optional<SlipDecoder::Frame> f;
    for (uint32_t i = 0; i < len && !f; ++i) f = decoder.Feed(data[i]);
    REQUIRE(f);
    const int n = metro_fw_frame_parse(f->bytes.data(), static_cast<uint32_t>(f->bytes.size()));
    REQUIRE(n >= 1);
    std::vector<uint8_t> payload(f->bytes.begin() + 4, f->bytes.begin() + 4 + n);
    self->lie(static_cast<uint8_t>(f->bytes[0] & ~METRO_FW_PUSH_RESPONSE_BIT), &payload);
    std::vector<uint8_t> enc(2 * METRO_FW_PUSH_MAX_FRAME + 2);
    uint32_t enc_len = 0;
    REQUIRE(metro_fw_frame_encode(f->bytes[0], f->bytes[1], payload.data(),
                                  static_cast<uint32_t>(payload.size()), enc.data(),
                                  static_cast<uint32_t>(enc.size()), &enc_len) == METRO_FW_OK);
    self->out_.insert(self->out_.end(), enc.begin(), enc.begin() + enc_len);
    return 0;
  }
  metro_fw_flash flash_if_;
  metro_fw_push push_{};
  std::vector<uint8_t> pending_;
  std::deque<uint8_t> out_;
};

// The fake answers at once, so a wait for a lost answer only needs to be short.
PushOptions Fast() {
  PushOptions o;
  o.timeout_ms = 5;
  o.execute_timeout_ms = 5;
  return o;
}

std::vector<uint8_t> Blob(uint32_t seq) { return WriteBlob(testing::Contents(seq)).value(); }

std::vector<uint8_t> SlotBytes(const RamFlash& f, int slot, size_t n) {
  auto begin = f.Memory().begin() + slot * static_cast<std::ptrdiff_t>(kPageSize);
  return std::vector<uint8_t>(begin, begin + static_cast<std::ptrdiff_t>(n));
}

bool SlotErased(const RamFlash& f, int slot) {
  const std::vector<uint8_t> s = SlotBytes(f, slot, kPageSize);
  return std::all_of(s.begin(), s.end(), [](uint8_t b) { return b == 0xFF; });
}

// Requests of a clean push of n bytes: GET_CRC, EXECUTE, CREATE, ceil(n/16) writes and reads.
int CleanRequests(size_t n) { return 3 + 2 * static_cast<int>((n + 15) / 16); }

}  // namespace

TEST_CASE("Push: a clean transfer writes slot A and reads it back", "[blob][push]") {
  RamFlash flash;
  LossyTag tag(&flash);
  PushClient client(&tag, Fast());
  Result<TagInfo> info = client.GetInfo();
  REQUIRE(info.ok());
  CHECK(info.value().device_id == testing::kDeviceId);
  CHECK(info.value().active_slot == -1);
  CHECK(info.value().max_len == 1024);
  CHECK(info.value().fmt_major == 1);
  const std::vector<uint8_t> blob = Blob(4);
  int calls = 0;
  size_t last_done = 0;
  Result<int> slot = client.Push(blob, [&](const char*, size_t done, size_t total) {
    ++calls;
    CHECK(total == blob.size());
    last_done = done;
  });
  REQUIRE(slot.ok());
  CHECK(slot.value() == 0);
  CHECK(SlotBytes(flash, 0, blob.size()) == blob);
  CHECK(SlotErased(flash, 1));
  CHECK(client.stats().requests == 1 + CleanRequests(blob.size()));  // 72 for 540 bytes
  CHECK(client.stats().frames_sent == client.stats().requests);
  CHECK(client.stats().retries == 0);
  CHECK(calls == 2 * 34);
  CHECK(last_done == blob.size());

  // The next update goes to slot B; slot A keeps the old one until the update after next.
  Result<TagInfo> again = client.GetInfo();
  REQUIRE(again.ok());
  CHECK(again.value().active_slot == 0);
  CHECK(again.value().active_seq == 4u);
  CHECK(again.value().active_crc32 == Crc32(blob.data(), blob.size() - 4));
  const std::vector<uint8_t> next = Blob(5);
  REQUIRE(client.Push(next).value() == 1);
  CHECK(SlotBytes(flash, 1, next.size()) == next);
  CHECK(SlotBytes(flash, 0, blob.size()) == blob);
}

TEST_CASE("Push: lost and duplicated and corrupted frames and lost answers are recovered",
          "[blob][push]") {
  const std::vector<uint8_t> blob = Blob(9);
  struct Case {
    const char* name;
    std::function<void(LossyTag&)> fault;
    int retries, naks, timeouts, ignored;
  };
  // Frame 1 GET_INFO, 2 CREATE, 3..36 WRITE, 37 GET_CRC, 38 EXECUTE, 39.. READ.
  const std::vector<Case> cases = {
      {"lost CREATE", [](LossyTag& t) { t.drop_frames = {2}; }, 1, 0, 1, 0},
      {"lost WRITE", [](LossyTag& t) { t.drop_frames = {10}; }, 1, 0, 1, 0},
      {"lost EXECUTE", [](LossyTag& t) { t.drop_frames = {38}; }, 1, 0, 1, 0},
      {"duplicated WRITE", [](LossyTag& t) { t.dup_frames = {12}; }, 0, 0, 0, 1},
      {"duplicated EXECUTE", [](LossyTag& t) { t.dup_frames = {38}; }, 0, 0, 0, 1},
      {"corrupted WRITE", [](LossyTag& t) { t.corrupt_frames = {20}; }, 1, 1, 0, 0},
      {"lost WRITE answer", [](LossyTag& t) { t.drop_answers = {15}; }, 1, 0, 1, 0},
      {"lost EXECUTE answer", [](LossyTag& t) { t.drop_answers = {38}; }, 1, 0, 1, 0},
      {"three faults",
       [](LossyTag& t) {
         t.drop_frames = {5};
         t.corrupt_frames = {30};
         t.drop_answers = {45};
       },
       3, 1, 2, 0},
  };
  for (const Case& c : cases) {
    SECTION(c.name) {
      RamFlash flash;
      LossyTag tag(&flash);
      c.fault(tag);
      PushClient client(&tag, Fast());
      REQUIRE(client.GetInfo().ok());
      Result<int> slot = client.Push(blob);
      REQUIRE(slot.ok());
      CHECK(slot.value() == 0);
      CHECK(SlotBytes(flash, 0, blob.size()) == blob);
      CHECK(SlotErased(flash, 1));  // a retried EXECUTE is answered from the cache, not redone
      CHECK(client.stats().requests == 1 + CleanRequests(blob.size()));
      CHECK(client.stats().retries == c.retries);
      CHECK(client.stats().naks == c.naks);
      CHECK(client.stats().timeouts == c.timeouts);
      CHECK(client.stats().ignored_frames == c.ignored);
    }
  }
}

TEST_CASE("Push: a stale seq is refused and nothing is written", "[blob][push]") {
  RamFlash flash;
  const std::vector<uint8_t> old_blob = Blob(7);
  flash.Program(METRO_FW_SLOT_A_ADDR, old_blob);
  LossyTag tag(&flash);
  PushClient client(&tag, Fast());
  Result<int> r = client.Push(Blob(7));
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().message ==
        "CAL_CREATE: the tag answered STALE_SEQ (seq 7 is not above the tag's active seq)");
  CHECK(SlotBytes(flash, 0, old_blob.size()) == old_blob);
  CHECK(SlotErased(flash, 1));
}

TEST_CASE("Push: a disconnect mid-transfer keeps the old calibration - a new session succeeds",
          "[blob][push]") {
  RamFlash flash;
  const std::vector<uint8_t> old_blob = Blob(7);
  flash.Program(METRO_FW_SLOT_A_ADDR, old_blob);
  {
    LossyTag tag(&flash);
    tag.hangup_after = 12;
    PushClient client(&tag, Fast());
    Result<int> r = client.Push(Blob(8));
    REQUIRE_FALSE(r.ok());
    CHECK(r.error().message == "CAL_WRITE: link lost: hung up");
  }
  CHECK(SlotBytes(flash, 0, old_blob.size()) == old_blob);
  CHECK(SlotErased(flash, 1));
  LossyTag tag(&flash);  // reconnected: the tag was left RECEIVING, CREATE starts over
  PushClient client(&tag, Fast());
  REQUIRE(client.Push(Blob(8)).value() == 1);
  CHECK(SlotBytes(flash, 1, old_blob.size()) == Blob(8));
}

TEST_CASE("Push: a flash error and a read-back difference are reported", "[blob][push]") {
  SECTION("flash error") {
    // Slot B does not exist in this flash: the update's erase of the target page fails.
    RamFlash flash;
    flash.Memory().resize(kPageSize);
    const std::vector<uint8_t> old_blob = Blob(7);
    flash.Program(METRO_FW_SLOT_A_ADDR, old_blob);
    LossyTag tag(&flash);
    PushClient client(&tag, Fast());
    Result<int> r = client.Push(Blob(8));
    REQUIRE_FALSE(r.ok());
    // FLASH_ERROR may follow the commit word: GET_INFO says the old seq is still live.
    CHECK(r.error().message ==
          "CAL_EXECUTE: the tag answered FLASH_ERROR; GET_INFO: the tag still holds seq 7");
    CHECK(client.commit_state() == CommitState::kNotDone);
    CHECK(SlotBytes(flash, 0, old_blob.size()) == old_blob);
  }
  SECTION("read-back difference") {
    RamFlash flash;
    LossyTag tag(&flash);
    const std::vector<uint8_t> blob = Blob(3);
    // After the update, something else rewrites slot A with a valid blob of the same seq
    // whose META differs: the read-back must notice.
    tag.after_execute = [&] {
      BlobContents c = testing::Contents(3);
      c.meta.tag_label = "OTHER";
      flash.Program(METRO_FW_SLOT_A_ADDR, WriteBlob(c).value());
    };
    PushClient client(&tag, Fast());
    Result<int> r = client.Push(blob);
    REQUIRE_FALSE(r.ok());
    // tag_label is META byte 116, blob offset 0x28 + 116 = 156: 'T' became 'O'.
    CHECK(r.error().message == "read-back: byte 156 of the active slot is 0x4F, sent 0x54");
  }
}

TEST_CASE("Push: a silent tag exhausts the retries - options are checked", "[blob][push]") {
  RamFlash flash;
  LossyTag tag(&flash);
  for (int k = 1; k <= 10; ++k) tag.drop_frames.insert(k);
  PushOptions o;
  o.max_retries = 3;
  o.timeout_ms = 5;
  PushClient client(&tag, o);
  Result<TagInfo> r = client.GetInfo();
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().message == "GET_INFO: no valid answer after 4 attempts (no answer within 5 ms)");
  CHECK(client.stats().frames_sent == 4);
  CHECK(client.stats().retries == 3);

  std::string why;
  o = PushOptions{};
  o.chunk_bytes = 17;
  CHECK_FALSE(o.IsValid(&why));
  CHECK(why == "chunk_bytes 17 is not 1..16");
  o = PushOptions{};
  o.timeout_ms = 0;
  CHECK_FALSE(o.IsValid(&why));
  CHECK(why == "timeouts must be >= 1 ms");
  o = PushOptions{};
  o.max_retries = -1;
  CHECK_FALSE(o.IsValid(&why));
  CHECK(why == "max_retries must be >= 0");
}

TEST_CASE("Push: PushCalibration builds the blob for the tag on the link", "[blob][push]") {
  Calibration cal;
  cal.date_utc = "2024-05-01T12:00:00Z";
  TagCalibration t;
  t.sensor = 2;
  SensorCalibration a;
  a.model.sensor = ImuSensor::kAccel;
  a.model.kind = ModelKind::kBias;
  a.model.input_unit = "LSB";
  a.model.output_unit = "g";
  a.model.scale = Eigen::Vector3d::Constant(1.0 / 16384.0);
  a.model.bias = {10, 20, 30};
  t.accel = a;
  cal.tags.push_back(t);
  BlobFromCalibrationOptions bo;
  bo.sensor = 2;
  bo.seq = 0;  // the tag's active seq + 1

  RamFlash flash;
  flash.Program(METRO_FW_SLOT_A_ADDR, Blob(41));
  LossyTag tag(&flash);
  PushSummary s = PushCalibration(&tag, cal, bo, std::nullopt, Fast());
  REQUIRE(s.ok);
  CHECK(s.seq == 42u);
  CHECK(s.slot == 1);
  CHECK(s.message ==
        "tag 9ABCDEF012345678 calibrated: seq 42 in slot B, 356 bytes read back identical");
  Result<BlobContents> back = DecodeBlob(SlotBytes(flash, 1, s.blob.size()));
  REQUIRE(back.ok());
  CHECK(back.value().accel->b0_lsb[2] == 30.0);
  CHECK(back.value().device_id == testing::kDeviceId);

  LossyTag tag2(&flash);
  PushSummary wrong = PushCalibration(&tag2, cal, bo, 0x0102030405060708ull, Fast());
  CHECK_FALSE(wrong.ok);
  CHECK(wrong.input_error);
  CHECK(wrong.message ==
        "the tag on the link is 9ABCDEF012345678, not 0102030405060708: nothing was written");
}

namespace {

// A tag that answers every request at once with what `answer` returns (result byte and
// payload), through the firmware's own frame encoder: for answers the real receiver never gives.
class ScriptedTag : public serial::ByteStream {
 public:
  std::function<std::vector<uint8_t>(uint8_t op, const std::vector<uint8_t>& payload)> answer;
  std::map<uint8_t, int> requests;  // frames received per op

  Status Write(const uint8_t* data, size_t size) override {
    for (size_t i = 0; i < size; ++i) {
      std::optional<SlipDecoder::Frame> f = decoder_.Feed(data[i]);
      if (!f || f->bad) continue;
      const int n = metro_fw_frame_parse(f->bytes.data(), static_cast<uint32_t>(f->bytes.size()));
      REQUIRE(n >= 0);
      const uint8_t op = f->bytes[0];
      ++requests[op];
      const std::vector<uint8_t> payload(f->bytes.begin() + 4, f->bytes.begin() + 4 + n);
      const std::vector<uint8_t> r = answer(op, payload);
      std::vector<uint8_t> enc(2 * METRO_FW_PUSH_MAX_FRAME + 2);
      uint32_t len = 0;
      REQUIRE(metro_fw_frame_encode(static_cast<uint8_t>(op | METRO_FW_PUSH_RESPONSE_BIT),
                                    f->bytes[1], r.data(), static_cast<uint32_t>(r.size()),
                                    enc.data(), static_cast<uint32_t>(enc.size()),
                                    &len) == METRO_FW_OK);
      out_.insert(out_.end(), enc.begin(), enc.begin() + len);
    }
    return Status::Ok();
  }
  Result<size_t> Read(uint8_t* data, size_t capacity, int) override {
    size_t n = 0;
    while (n < capacity && !out_.empty()) {
      data[n++] = out_.front();
      out_.pop_front();
    }
    return n;
  }

 private:
  SlipDecoder decoder_{METRO_FW_PUSH_MAX_FRAME};
  std::deque<uint8_t> out_;
};

}  // namespace

TEST_CASE("Push: a tag answering CAL_WRITE with INVALID_OFFSET and 16, 0, 16, ... stops",
          "[blob][push]") {
  // issue #20: the old client followed the tag's received_len forever (0 -> 16 -> 0 ...).
  ScriptedTag tag;
  int writes = 0;
  tag.answer = [&](uint8_t op, const std::vector<uint8_t>&) -> std::vector<uint8_t> {
    if (op == METRO_FW_OP_CAL_WRITE) {
      const uint8_t received = (writes++ % 2 == 0) ? 16 : 0;
      return {METRO_FW_RES_INVALID_OFFSET, received, 0};
    }
    return {METRO_FW_RES_SUCCESS};
  };
  PushOptions o = Fast();
  o.max_retries = 5;
  PushClient client(&tag, o);
  const auto start = std::chrono::steady_clock::now();
  Result<int> r = client.Push(Blob(8));
  const auto took = std::chrono::steady_clock::now() - start;
  REQUIRE_FALSE(r.ok());
  // Resumes 1..5 are allowed (offsets 0, 16, 0, 16, 0 sent), the 6th (offset 16) is refused.
  CHECK(r.error().message ==
        "CAL_WRITE: the tag answered INVALID_OFFSET 6 times in one pass (last: offset 16 sent, "
        "received_len 0); at most 5 resumes (--retries) are allowed");
  CHECK(tag.requests[METRO_FW_OP_CAL_WRITE] == 6);
  CHECK(tag.requests[METRO_FW_OP_CAL_EXECUTE] == 0);
  CHECK(client.commit_state() == CommitState::kNotSent);
  CHECK(took < std::chrono::seconds(2));

  // --retries 0: the first INVALID_OFFSET already ends the push.
  ScriptedTag tag0;
  writes = 0;
  tag0.answer = tag.answer;
  o.max_retries = 0;
  PushClient client0(&tag0, o);
  Result<int> r0 = client0.Push(Blob(8));
  REQUIRE_FALSE(r0.ok());
  CHECK(r0.error().message ==
        "CAL_WRITE: the tag answered INVALID_OFFSET 1 times in one pass (last: offset 0 sent, "
        "received_len 16); at most 0 resumes (--retries) are allowed");
  CHECK(tag0.requests[METRO_FW_OP_CAL_WRITE] == 1);
}

TEST_CASE("Push: a tag that answers nonsense to every request ends within the retry budget",
          "[blob][push]") {
  // Every request is answered with a frame for another op (skipped as stale): only the
  // timeouts end each request, --retries + 1 attempts of --timeout-ms each.
  ScriptedTag tag;
  tag.answer = [](uint8_t, const std::vector<uint8_t>&) -> std::vector<uint8_t> { return {}; };
  PushOptions o = Fast();
  o.timeout_ms = 20;
  o.max_retries = 2;
  PushClient client(&tag, o);
  const auto start = std::chrono::steady_clock::now();
  Result<TagInfo> r = client.GetInfo();
  const auto took = std::chrono::steady_clock::now() - start;
  REQUIRE_FALSE(r.ok());
  // An answer with no result byte is not an answer: 3 attempts, 3 timeouts.
  CHECK(r.error().message == "GET_INFO: no valid answer after 3 attempts (no answer within 20 ms)");
  CHECK(client.stats().timeouts == 3);
  CHECK(client.stats().ignored_frames == 3);
  CHECK(took >= std::chrono::milliseconds(57));  // 3 x 20 ms, each cut to whole ms
  CHECK(took < std::chrono::seconds(2));
}

TEST_CASE("Push: a link lost after CAL_EXECUTE is an unknown outcome, not a failure",
          "[blob][push]") {
  // Frames of Push(540 bytes): CREATE 1, CAL_WRITE 2..35, GET_CRC 36, EXECUTE 37.
  RamFlash flash;
  flash.Program(METRO_FW_SLOT_A_ADDR, Blob(7));
  {
    LossyTag tag(&flash);
    tag.drop_answers = {37};
    tag.hangup_after = 37;  // the tag commits, its answer is lost, the link drops
    PushClient client(&tag, Fast());
    Result<int> r = client.Push(Blob(8));
    REQUIRE_FALSE(r.ok());
    CHECK(r.error().message == "CAL_EXECUTE: link lost: hung up");
    CHECK(client.commit_state() == CommitState::kUnknown);
  }
  CHECK(SlotBytes(flash, 1, Blob(8).size()) == Blob(8));  // it did commit

  SECTION("PushCalibration says so, and the same push with --seq 8 only reads it back") {
    RamFlash f2;
    f2.Program(METRO_FW_SLOT_A_ADDR, Blob(7));
    Calibration cal;
    cal.date_utc = "2024-05-01T12:00:00Z";
    TagCalibration t;
    t.sensor = 2;
    SensorCalibration a;
    a.model.sensor = ImuSensor::kAccel;
    a.model.kind = ModelKind::kBias;
    a.model.input_unit = "LSB";
    a.model.output_unit = "g";
    a.model.scale = Eigen::Vector3d::Constant(1.0 / 16384.0);
    t.accel = a;
    cal.tags.push_back(t);
    BlobFromCalibrationOptions bo;
    bo.sensor = 2;
    bo.seq = 8;
    PushSummary s;
    {
      LossyTag tag(&f2);
      // GET_INFO is frame 1, so EXECUTE is frame 1 + 1 + 23 + 1 + 1 = 27 for 356 bytes.
      tag.drop_answers = {27};
      tag.hangup_after = 27;
      s = PushCalibration(&tag, cal, bo, std::nullopt, Fast());
    }
    CHECK_FALSE(s.ok);
    CHECK(s.commit == CommitState::kUnknown);
    CHECK(s.message == "outcome unknown: the tag may hold seq 8 (CAL_EXECUTE: link lost: hung up)");
    const std::string advice = PushRecoveryAdvice(s, "/dev/ttyACM0", "cal.json", 2);
    CHECK(advice ==
          "to find out: calibrate push --port /dev/ttyACM0 cal.json --sensor 2 --device-id "
          "9ABCDEF012345678 --seq 8 (a tag that holds this blob is only read back and compared; "
          "one that does not gets seq 8)\n"
          "to program over SWD instead: calibrate blob cal.json --sensor 2 --device-id "
          "9ABCDEF012345678 --seq 8 -o tag.bin --hex tag.hex && nrfjprog -f NRF51 --program "
          "tag.hex --sectorerase --verify --reset\n");
    LossyTag again(&f2);
    PushSummary s2 = PushCalibration(&again, cal, bo, std::nullopt, Fast());
    REQUIRE(s2.ok);
    CHECK(s2.already_held);
    CHECK(s2.message ==
          "tag 9ABCDEF012345678 already holds this calibration: seq 8 in slot B, 356 bytes read "
          "back identical; nothing written");
    CHECK(again.frames == 1 + 23);  // GET_INFO and the reads, no write
  }
}

TEST_CASE("Push: a tag that contradicts what it acknowledged is labelled so, not unverified",
          "[blob][push][security][issue37]") {
  // issue #37: "the tag committed seq 8, but the read-back did not finish (read-back: byte 0
  // ...)" for a read-back that finished and differed; a plain failure for a tag naming another
  // seq or CRC-32.
  Calibration cal;
  cal.date_utc = "2024-05-01T12:00:00Z";
  TagCalibration t;
  t.sensor = 2;
  SensorCalibration a;
  a.model.sensor = ImuSensor::kAccel;
  a.model.kind = ModelKind::kBias;
  a.model.input_unit = "LSB";
  a.model.output_unit = "g";
  a.model.scale = Eigen::Vector3d::Constant(1.0 / 16384.0);
  t.accel = a;
  cal.tags.push_back(t);
  BlobFromCalibrationOptions bo;
  bo.sensor = 2;
  bo.seq = 8;
  RamFlash flash;
  flash.Program(METRO_FW_SLOT_A_ADDR, Blob(7));
  LossyTag tag(&flash);
  PushOptions o = Fast();
  o.max_retries = 2;
  SECTION("read-back differs") {
    tag.lie = [](uint8_t op, std::vector<uint8_t>* p) {
      if (op == METRO_FW_OP_CAL_READ && p->size() > 1) (*p)[1] ^= 0x01;  // its first data byte
    };
    const PushSummary s = PushCalibration(&tag, cal, bo, std::nullopt, o);
    CHECK_FALSE(s.ok);
    CHECK(s.contradiction == TagContradiction::kReadBackDiffers);
    CHECK(s.commit == CommitState::kCommitted);  // It said SUCCESS: the flash is written.
    const std::string detail = fmt::format("byte 0 of the active slot is 0x{:02X}, sent 0x{:02X}",
                                           s.blob[0] ^ 1, s.blob[0]);
    CHECK(s.message == "the tag contradicts itself (read-back differs) pushing seq 8: read-back: " +
                           detail + "; what it runs is unknown until its flash is read over SWD");
    CHECK(PushReadBackText(s) == "differs: " + detail);
    // The same push again would be answered alike: the advice is the wired path alone.
    const std::string advice = PushRecoveryAdvice(s, "/dev/ttyACM0", "cal.json", 2);
    CHECK(advice.find("to find out") == std::string::npos);
    CHECK(advice.rfind("to program over SWD instead: calibrate blob cal.json --sensor 2", 0) == 0);
  }
  SECTION("seq differs") {
    tag.lie = [](uint8_t op, std::vector<uint8_t>* p) {
      if (op == METRO_FW_OP_CAL_EXECUTE && p->size() >= 6 && (*p)[0] == METRO_FW_RES_SUCCESS) {
        ++(*p)[2];  // seq 8 -> 9
      }
    };
    const PushSummary s = PushCalibration(&tag, cal, bo, std::nullopt, o);
    CHECK_FALSE(s.ok);
    CHECK(s.contradiction == TagContradiction::kSeqDiffers);
    CHECK(s.commit == CommitState::kUnknown);
    CHECK(s.message ==
          "the tag contradicts itself (seq differs) pushing seq 8: CAL_EXECUTE: the tag answered "
          "SUCCESS with seq 9, sent 8; what it runs is unknown until its flash is read over SWD");
    CHECK(PushReadBackText(s) ==
          "not read back: the tag contradicted itself (seq differs): CAL_EXECUTE: the tag "
          "answered SUCCESS with seq 9, sent 8");
  }
  SECTION("CRC-32 differs: CAL_GET_CRC") {
    tag.lie = [](uint8_t op, std::vector<uint8_t>* p) {
      if (op == METRO_FW_OP_CAL_GET_CRC && p->size() >= 7) (*p)[3] ^= 0x01;
    };
    const PushSummary s = PushCalibration(&tag, cal, bo, std::nullopt, o);
    CHECK_FALSE(s.ok);
    CHECK(s.contradiction == TagContradiction::kCrcDiffers);
    CHECK(s.commit == CommitState::kNotSent);  // Nothing executed: the old blob stays.
    CHECK(s.message.rfind("the tag contradicts itself (CRC-32 differs) pushing seq 8: CAL_GET_CRC: "
                          "the tag acknowledged every byte but holds 356 bytes with CRC-32 0x",
                          0) == 0);
    CHECK(SlotBytes(flash, 0, Blob(7).size()) == Blob(7));
  }
  SECTION("CRC-32 differs: GET_INFO after a lost CAL_EXECUTE answer") {
    // GET_INFO 1, CREATE 2, CAL_WRITE 3..25 (356 bytes), GET_CRC 26, EXECUTE 27 and its two
    // resends lost; GET_INFO (answer 30) names seq 8 with another CRC-32.
    tag.drop_answers = {27, 28, 29};
    tag.lie = [&tag](uint8_t op, std::vector<uint8_t>* p) {
      if (op == METRO_FW_OP_GET_INFO && tag.answers > 1 && p->size() >= 22) (*p)[18] ^= 0x01;
    };
    const PushSummary s = PushCalibration(&tag, cal, bo, std::nullopt, o);
    CHECK_FALSE(s.ok);
    CHECK(s.contradiction == TagContradiction::kCrcDiffers);
    CHECK(s.message.find("; GET_INFO: the tag holds seq 8 with CRC-32 0x") != std::string::npos);
    CHECK(s.message.find("but the blob sent as seq 8 has 0x") != std::string::npos);
  }
}

TEST_CASE("Push: a lost CAL_EXECUTE answer on a live link is settled by GET_INFO and read back",
          "[blob][push]") {
  RamFlash flash;
  flash.Program(METRO_FW_SLOT_A_ADDR, Blob(7));
  LossyTag tag(&flash);
  // EXECUTE (frame 37) and its 2 resends: the tag commits once, its cached answers are lost.
  tag.drop_answers = {37, 38, 39};
  PushOptions o = Fast();
  o.max_retries = 2;
  PushClient client(&tag, o);
  Result<int> r = client.Push(Blob(8));
  REQUIRE(r.ok());
  CHECK(r.value() == 1);
  CHECK(client.commit_state() == CommitState::kCommitted);
  CHECK(SlotBytes(flash, 1, Blob(8).size()) == Blob(8));
}

TEST_CASE("Push: recovery advice never names a seq the tools refuse", "[blob][push]") {
  PushSummary s;
  s.tag_answered = true;
  s.tag.device_id = testing::kDeviceId;
  s.tag.active_seq = kSeqMax;  // 4294967294: exhausted, seq never set
  s.message = "the tag's seq is exhausted (4294967294)";
  CHECK(WiredPathSeq(s) == 1u);  // the old advice said 4294967295
  const std::string advice = PushRecoveryAdvice(s, "/dev/ttyACM0", "cal.json", 2);
  CHECK(advice ==
        "to program over SWD instead: calibrate blob cal.json --sensor 2 --device-id "
        "9ABCDEF012345678 --seq 1 -o tag.bin --hex tag.hex && nrfjprog -f NRF51 --program "
        "tag.hex --sectorerase --verify --reset\n"
        "the tag's seq space is exhausted (4294967294): the HEX erases both slot pages, so seq 1 "
        "is the only calibration afterwards\n");
  s.tag.active_seq = kSeqMax - 1;  // 4294967293: the next seq is the last one
  CHECK(WiredPathSeq(s) == kSeqMax);
  s.seq = 12;
  CHECK(WiredPathSeq(s) == 12u);
  s.input_error = true;
  CHECK(PushRecoveryAdvice(s, "p", "c", 2).empty());

  // PushCalibration on an exhausted tag: refused before anything is written.
  RamFlash flash;
  flash.Program(METRO_FW_SLOT_A_ADDR, Blob(kSeqMax));
  LossyTag tag(&flash);
  Calibration cal;
  BlobFromCalibrationOptions bo;
  bo.sensor = 2;
  bo.seq = 0;
  PushSummary e = PushCalibration(&tag, cal, bo, std::nullopt, Fast());
  CHECK_FALSE(e.ok);
  CHECK(e.commit == CommitState::kNotSent);
  CHECK(e.message ==
        "the tag's seq is exhausted (4294967294); only the wired path (a factory HEX) resets it");
  CHECK(tag.frames == 1);
  CHECK(WiredPathSeq(e) == 1u);
}

TEST_CASE("SLIP decoder: escapes and bad escapes and overlong frames", "[blob][push]") {
  const std::vector<uint8_t> frame = {0x01, 0xC0, 0xDB, 0x02, 0xDB, 0xDC};
  // RFC 1055: END 01 (DB DC) (DB DD) 02 (DB DD) DC END
  const std::vector<uint8_t> enc = {0xC0, 0x01, 0xDB, 0xDC, 0xDB, 0xDD,
                                    0x02, 0xDB, 0xDD, 0xDC, 0xC0};
  SlipDecoder d(38);
  std::vector<SlipDecoder::Frame> got;
  for (uint8_t b : enc) {
    if (auto f = d.Feed(b)) got.push_back(*f);
  }
  REQUIRE(got.size() == 1);
  CHECK_FALSE(got[0].bad);
  CHECK(got[0].bytes == frame);

  got.clear();
  for (uint8_t b : {0xC0, 0x01, 0xDB, 0x05, 0x02, 0xC0}) {
    if (auto f = d.Feed(b)) got.push_back(*f);
  }
  REQUIRE(got.size() == 1);
  CHECK(got[0].bad);  // ESC followed by 0x05

  got.clear();
  SlipDecoder small(4);
  for (uint8_t b : {0x01, 0x02, 0x03, 0x04, 0x05, 0xC0, 0x07, 0xC0}) {
    if (auto f = small.Feed(b)) got.push_back(*f);
  }
  REQUIRE(got.size() == 2);
  CHECK(got[0].bad);  // 5 bytes > 4
  CHECK(got[1].bytes == std::vector<uint8_t>{0x07});
}

}  // namespace metro::blob
