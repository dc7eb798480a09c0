// The push client against the tag's own receiver (firmware/src/push.c) in memory, with the
// link faults of docs/calibration-blob.md section 7: lost, duplicated and corrupted frames,
// lost answers, a stale seq, a disconnect mid-transfer, a flash error and a silent tag.
#include "metro/blob/push_client.hpp"

#include <catch2/catch.hpp>
#include <deque>
#include <functional>
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
class LossyTag : public ByteStream {
 public:
  explicit LossyTag(RamFlash* flash) : flash_if_(flash->Interface()) {
    REQUIRE(metro_fw_push_init(&push_, &flash_if_, kIdWords, &LossyTag::Send, this) == METRO_FW_OK);
  }
  std::set<int> drop_frames, dup_frames, corrupt_frames, drop_answers;
  int hangup_after = -1;  // frames
  std::function<void()> after_execute;
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
    self->out_.insert(self->out_.end(), data, data + len);
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
    CHECK(r.error().message == "CAL_EXECUTE: the tag answered FLASH_ERROR");
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
