// Receive side of the push protocol, driven as the PC would drive it, with transfer faults.
#include "metro_fw/push.h"

#include <catch2/catch.hpp>
#include <memory>

#include "metro_fw/crc.h"
#include "test_support.hpp"

using fwtest::Build;
using fwtest::FakeFlash;
using fwtest::StandardBlob;

namespace {

struct Response {
  uint8_t op = 0;
  uint8_t txn = 0;
  std::vector<uint8_t> payload;
  uint8_t result() const { return payload.empty() ? 0 : payload[0]; }
};

// The tag on a link that delivers 20-byte NUS payloads.
class Link {
 public:
  Link() : push_(std::make_unique<metro_fw_push>()) {
    flash_if_ = flash.Interface();
    REQUIRE(metro_fw_push_init(push_.get(), &flash_if_, fwtest::kDeviceId, &Link::Send, this) ==
            METRO_FW_OK);
  }

  // Sends raw bytes in 20-byte chunks; returns the decoded responses.
  std::vector<Response> SendBytes(const std::vector<uint8_t>& bytes) {
    for (size_t off = 0; off < bytes.size(); off += 20) {
      const size_t n = std::min<size_t>(20, bytes.size() - off);
      metro_fw_push_rx(push_.get(), bytes.data() + off, static_cast<uint32_t>(n));
    }
    return Decode();
  }

  std::vector<uint8_t> Encode(uint8_t op, uint8_t txn, const std::vector<uint8_t>& payload) {
    uint8_t enc[160];
    uint32_t m = 0;
    REQUIRE(metro_fw_frame_encode(op, txn, payload.data(), static_cast<uint32_t>(payload.size()),
                                  enc, sizeof(enc), &m) == METRO_FW_OK);
    return std::vector<uint8_t>(enc, enc + m);
  }

  // One request, one response expected.
  Response Call(uint8_t op, const std::vector<uint8_t>& payload) {
    const auto responses = SendBytes(Encode(op, ++txn_, payload));
    REQUIRE(responses.size() == 1);
    CHECK(responses[0].op == (op | 0x80));
    CHECK(responses[0].txn == txn_);
    return responses[0];
  }
  uint8_t txn() const { return txn_; }

  static std::vector<uint8_t> Create(uint16_t total, uint32_t crc, uint32_t seq) {
    std::vector<uint8_t> p(10);
    p[0] = static_cast<uint8_t>(total);
    p[1] = static_cast<uint8_t>(total >> 8);
    for (int i = 0; i < 4; ++i) p[2 + i] = static_cast<uint8_t>(crc >> (8 * i));
    for (int i = 0; i < 4; ++i) p[6 + i] = static_cast<uint8_t>(seq >> (8 * i));
    return p;
  }
  static std::vector<uint8_t> Write(const std::vector<uint8_t>& blob, size_t off) {
    const size_t n = std::min<size_t>(16, blob.size() - off);
    std::vector<uint8_t> p(2 + n);
    p[0] = static_cast<uint8_t>(off);
    p[1] = static_cast<uint8_t>(off >> 8);
    for (size_t i = 0; i < n; ++i) p[2 + i] = blob[off + i];
    return p;
  }

  // CAL_CREATE for the whole of `blob`, then every CAL_WRITE chunk of it, each succeeding.
  void Upload(const std::vector<uint8_t>& blob, uint32_t seq = 1) {
    const uint32_t crc = metro_fw_crc32(0, blob.data(), static_cast<uint32_t>(blob.size()));
    REQUIRE(Call(METRO_FW_OP_CAL_CREATE, Create(static_cast<uint16_t>(blob.size()), crc, seq))
                .result() == METRO_FW_RES_SUCCESS);
    for (size_t off = 0; off < blob.size(); off += 16) {
      REQUIRE(Call(METRO_FW_OP_CAL_WRITE, Write(blob, off)).result() == METRO_FW_RES_SUCCESS);
    }
  }

  // The whole transfer, as calibrate push does it; returns EXECUTE's response.
  Response Push(const std::vector<uint8_t>& blob, uint32_t seq) {
    Upload(blob, seq);
    return Call(METRO_FW_OP_CAL_EXECUTE, {});
  }

  std::vector<uint8_t> ReadBack(size_t total) {
    std::vector<uint8_t> out;
    for (size_t off = 0; off < total; off += 16) {
      const auto n = static_cast<uint8_t>(std::min<size_t>(16, total - off));
      auto r = Call(METRO_FW_OP_CAL_READ,
                    {static_cast<uint8_t>(off), static_cast<uint8_t>(off >> 8), n});
      REQUIRE(r.result() == METRO_FW_RES_SUCCESS);
      out.insert(out.end(), r.payload.begin() + 1, r.payload.end());
    }
    return out;
  }

  FakeFlash flash;
  metro_fw_push* push() { return push_.get(); }

 private:
  static int Send(void* ctx, const uint8_t* data, uint32_t len) {
    auto* self = static_cast<Link*>(ctx);
    self->tx_.insert(self->tx_.end(), data, data + len);
    return 0;
  }

  // Independent SLIP decoder (RFC 1055) and frame check.
  std::vector<Response> Decode() {
    std::vector<Response> out;
    std::vector<uint8_t> frame;
    bool esc = false;
    for (uint8_t c : tx_) {
      if (c == 0xC0) {
        if (frame.size() >= 6) {
          const uint16_t len = static_cast<uint16_t>(frame[2] | frame[3] << 8);
          REQUIRE(frame.size() == len + 6u);
          const uint16_t crc = metro_fw_crc16(0xFFFF, frame.data(), len + 4u);
          REQUIRE(crc == (frame[4 + len] | frame[5 + len] << 8));
          Response r;
          r.op = frame[0];
          r.txn = frame[1];
          r.payload.assign(frame.begin() + 4, frame.begin() + 4 + len);
          out.push_back(r);
        }
        frame.clear();
      } else if (c == 0xDB) {
        esc = true;
      } else {
        frame.push_back(esc ? (c == 0xDC ? 0xC0 : 0xDB) : c);
        esc = false;
      }
    }
    tx_.clear();
    return out;
  }

  std::unique_ptr<metro_fw_push> push_;
  metro_fw_flash flash_if_{};
  std::vector<uint8_t> tx_;
  uint8_t txn_ = 0;
};

}  // namespace

TEST_CASE("GET_INFO reports the format and device id and active slot", "[fw][push]") {
  Link link;
  link.flash.Program(METRO_FW_SLOT_B_ADDR, Build(StandardBlob(12)));
  const auto r = link.Call(METRO_FW_OP_GET_INFO, {});
  REQUIRE(r.payload.size() == 22u);
  CHECK(r.result() == METRO_FW_RES_SUCCESS);
  CHECK(r.payload[1] == 1);
  CHECK(r.payload[3] == 1);  // slot B
  CHECK(fwtest::Get32(r.payload, 6) == fwtest::kDeviceId[0]);
  CHECK(fwtest::Get32(r.payload, 10) == fwtest::kDeviceId[1]);
  CHECK(fwtest::Get32(r.payload, 14) == 12u);
  CHECK(fwtest::Get32(r.payload, 18) == fwtest::Get32(Build(StandardBlob(12)), 0x218));
}

TEST_CASE("A clean push commits the blob and reads back byte for byte", "[fw][push]") {
  Link link;
  link.flash.Program(METRO_FW_SLOT_A_ADDR, Build(StandardBlob(4)));
  const auto blob = Build(StandardBlob(5));
  const auto r = link.Push(blob, 5);
  CHECK(r.result() == METRO_FW_RES_SUCCESS);
  CHECK(r.payload[1] == 1);
  CHECK(fwtest::Get32(r.payload, 2) == 5u);
  CHECK(link.push()->updated == 1);
  CHECK(link.ReadBack(blob.size()) == blob);
}

TEST_CASE("A lost chunk is detected by offset and the transfer resumes", "[fw][push]") {
  Link link;
  const auto blob = Build(StandardBlob(1));
  const uint32_t crc = metro_fw_crc32(0, blob.data(), 540);
  REQUIRE(link.Call(METRO_FW_OP_CAL_CREATE, Link::Create(540, crc, 1)).result() ==
          METRO_FW_RES_SUCCESS);
  REQUIRE(link.Call(METRO_FW_OP_CAL_WRITE, Link::Write(blob, 0)).result() == METRO_FW_RES_SUCCESS);
  // The chunk at 16 is lost; the one at 32 arrives.
  const auto r = link.Call(METRO_FW_OP_CAL_WRITE, Link::Write(blob, 32));
  CHECK(r.result() == METRO_FW_RES_INVALID_OFFSET);
  CHECK((r.payload[1] | r.payload[2] << 8) == 16);
  const auto g = link.Call(METRO_FW_OP_CAL_GET_CRC, {});
  CHECK((g.payload[1] | g.payload[2] << 8) == 16);
  CHECK(fwtest::Get32(g.payload, 3) == metro_fw_crc32(0, blob.data(), 16));
  for (size_t off = 16; off < 540; off += 16) {
    REQUIRE(link.Call(METRO_FW_OP_CAL_WRITE, Link::Write(blob, off)).result() ==
            METRO_FW_RES_SUCCESS);
  }
  CHECK(link.Call(METRO_FW_OP_CAL_EXECUTE, {}).result() == METRO_FW_RES_SUCCESS);
}

TEST_CASE("A duplicated request is answered again without being executed again", "[fw][push]") {
  Link link;
  const auto blob = Build(StandardBlob(1));
  const uint32_t crc = metro_fw_crc32(0, blob.data(), 540);
  link.Upload(blob);
  const auto exec = link.Encode(METRO_FW_OP_CAL_EXECUTE, 200, {});
  auto twice = exec;
  twice.insert(twice.end(), exec.begin(), exec.end());
  const auto responses = link.SendBytes(twice);
  REQUIRE(responses.size() == 2);
  CHECK(responses[0].payload == responses[1].payload);
  CHECK(responses[0].result() == METRO_FW_RES_SUCCESS);
  CHECK(link.flash.ops == 3);  // one update only
  // A duplicated CAL_WRITE after a later one does not move received_len backwards.
  Link l2;
  REQUIRE(l2.Call(METRO_FW_OP_CAL_CREATE, Link::Create(540, crc, 1)).result() ==
          METRO_FW_RES_SUCCESS);
  const auto w0 = l2.Encode(METRO_FW_OP_CAL_WRITE, 50, Link::Write(blob, 0));
  const auto w1 = l2.Encode(METRO_FW_OP_CAL_WRITE, 51, Link::Write(blob, 16));
  std::vector<uint8_t> seq = w0;
  seq.insert(seq.end(), w1.begin(), w1.end());
  seq.insert(seq.end(), w0.begin(), w0.end());
  const auto rs = l2.SendBytes(seq);
  REQUIRE(rs.size() == 3);
  CHECK((rs[2].payload[1] | rs[2].payload[2] << 8) == 32);
}

TEST_CASE("A corrupted frame gets a NAK and changes nothing", "[fw][push]") {
  Link link;
  auto bytes = link.Encode(METRO_FW_OP_CAL_CREATE, 1, Link::Create(540, 0, 1));
  bytes[5] ^= 0x01;
  const auto r = link.SendBytes(bytes);
  REQUIRE(r.size() == 1);
  CHECK(r[0].op == METRO_FW_OP_NAK);
  CHECK(r[0].result() == METRO_FW_RES_FRAME_ERROR);
  CHECK(link.push()->receiving == 0);
  // A bad SLIP escape and an overlong frame are NAKed too.
  const auto esc = link.SendBytes({0xC0, 0x01, 0xDB, 0x11, 0x00, 0x00, 0xC0});
  REQUIRE(esc.size() == 1);
  CHECK(esc[0].op == METRO_FW_OP_NAK);
  std::vector<uint8_t> longframe(60, 0x01);
  longframe.insert(longframe.begin(), 0xC0);
  longframe.push_back(0xC0);
  const auto lf = link.SendBytes(longframe);
  REQUIRE(lf.size() == 1);
  CHECK(lf[0].op == METRO_FW_OP_NAK);
}

TEST_CASE("A stale seq is refused at CREATE", "[fw][push]") {
  Link link;
  link.flash.Program(METRO_FW_SLOT_A_ADDR, Build(StandardBlob(9)));
  for (uint32_t seq : {9u, 3u, 0u, 0xFFFFFFFFu}) {
    CHECK(link.Call(METRO_FW_OP_CAL_CREATE, Link::Create(540, 0, seq)).result() ==
          METRO_FW_RES_STALE_SEQ);
  }
}

TEST_CASE("EXECUTE without CREATE or before all bytes arrived is a bad state", "[fw][push]") {
  Link link;
  CHECK(link.Call(METRO_FW_OP_CAL_EXECUTE, {}).result() == METRO_FW_RES_BAD_STATE);
  CHECK(link.Call(METRO_FW_OP_CAL_WRITE, Link::Write(Build(StandardBlob(1)), 0)).result() ==
        METRO_FW_RES_BAD_STATE);
  const auto blob = Build(StandardBlob(1));
  REQUIRE(link.Call(METRO_FW_OP_CAL_CREATE, Link::Create(540, 0, 1)).result() ==
          METRO_FW_RES_SUCCESS);
  REQUIRE(link.Call(METRO_FW_OP_CAL_WRITE, Link::Write(blob, 0)).result() == METRO_FW_RES_SUCCESS);
  CHECK(link.Call(METRO_FW_OP_CAL_EXECUTE, {}).result() == METRO_FW_RES_BAD_STATE);
  CHECK(link.Call(METRO_FW_OP_ABORT, {}).result() == METRO_FW_RES_SUCCESS);
  CHECK(link.Call(METRO_FW_OP_CAL_GET_CRC, {}).result() == METRO_FW_RES_BAD_STATE);
}

TEST_CASE("A wrong CRC at CREATE is a CRC mismatch at EXECUTE", "[fw][push]") {
  Link link;
  const auto blob = Build(StandardBlob(1));
  REQUIRE(link.Call(METRO_FW_OP_CAL_CREATE, Link::Create(540, 0x12345678u, 1)).result() ==
          METRO_FW_RES_SUCCESS);
  for (size_t off = 0; off < 540; off += 16)
    link.Call(METRO_FW_OP_CAL_WRITE, Link::Write(blob, off));
  CHECK(link.Call(METRO_FW_OP_CAL_EXECUTE, {}).result() == METRO_FW_RES_CRC_MISMATCH);
  CHECK(link.flash.ops == 0);
}

TEST_CASE("Blob-level refusals map to protocol results", "[fw][push]") {
  {
    Link link;
    auto foreign = StandardBlob(1);
    foreign.device_id[0] = 77;
    CHECK(link.Push(Build(foreign), 1).result() == METRO_FW_RES_FOREIGN_DEVICE);
  }
  {
    Link link;
    auto newer = StandardBlob(1);
    newer.fmt_major = 2;
    CHECK(link.Push(Build(newer), 1).result() == METRO_FW_RES_UNSUPPORTED_FORMAT);
  }
  {
    Link link;  // the blob's seq differs from CREATE's
    CHECK(link.Push(Build(StandardBlob(2)), 3).result() == METRO_FW_RES_INVALID_PARAM);
  }
  {
    Link link;
    link.flash.fail_at = 0;  // the erase fails
    CHECK(link.Push(Build(StandardBlob(1)), 1).result() == METRO_FW_RES_FLASH_ERROR);
    CHECK(link.push()->updated == 0);
  }
}

TEST_CASE("A blob the validator refuses or trailing bytes are INVALID_BLOB at EXECUTE",
          "[fw][push]") {
  {
    Link link;  // cut down to its header, length and CRC fixed
    auto cut = Build(StandardBlob(1));
    cut.resize(36);
    fwtest::Put16(cut, 8, 36);
    fwtest::Reseal(cut, 36);
    const auto r = link.Push(cut, 1);
    CHECK(r.result() == METRO_FW_RES_INVALID_BLOB);
    CHECK(r.payload[1] == 0xFF);
    CHECK(link.flash.ops == 0);
  }
  {
    Link link;  // CREATE's total_len 4 bytes beyond the blob's own
    auto longer = Build(StandardBlob(1));
    longer.resize(longer.size() + 4, 0);
    CHECK(link.Push(longer, 1).result() == METRO_FW_RES_INVALID_BLOB);
    CHECK(link.push()->updated == 0);
    CHECK(link.flash.ops == 0);
  }
}

TEST_CASE("EXECUTE answers SUCCESS when the commit happened but the tag's read-back failed",
          "[fw][push]") {
  Link link;
  link.flash.Program(METRO_FW_SLOT_A_ADDR, Build(StandardBlob(4)));
  link.flash.reads_fail_from = 3;  // after erase, body and commit word
  const auto r = link.Push(Build(StandardBlob(5)), 5);
  CHECK(r.result() == METRO_FW_RES_SUCCESS);
  CHECK(r.payload[1] == 1);
  CHECK(fwtest::Get32(r.payload, 2) == 5u);
  CHECK(link.push()->updated == 1);
  link.flash.reads_fail_from = -1;
  CHECK(link.ReadBack(540) == Build(StandardBlob(5)));
}

TEST_CASE("Malformed requests are invalid parameters", "[fw][push]") {
  Link link;
  CHECK(link.Call(METRO_FW_OP_CAL_CREATE, Link::Create(1028, 0, 1)).result() ==
        METRO_FW_RES_INVALID_PARAM);
  CHECK(link.Call(METRO_FW_OP_CAL_CREATE, {1, 2, 3}).result() == METRO_FW_RES_INVALID_PARAM);
  REQUIRE(link.Call(METRO_FW_OP_CAL_CREATE, Link::Create(40, 0, 1)).result() ==
          METRO_FW_RES_SUCCESS);
  CHECK(link.Call(METRO_FW_OP_CAL_WRITE, {32, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9}).result() ==
        METRO_FW_RES_INVALID_PARAM);  // 32 + 9 > 40
  CHECK(link.Call(0x33, {}).result() == METRO_FW_RES_UNKNOWN_OP);
  CHECK(link.Call(METRO_FW_OP_CAL_READ, {0, 0, 4}).result() == METRO_FW_RES_NO_CALIBRATION);
}

TEST_CASE("A disconnect mid-transfer is recovered by a new CREATE", "[fw][push]") {
  Link link;
  const auto blob = Build(StandardBlob(1));
  const uint32_t crc = metro_fw_crc32(0, blob.data(), 540);
  REQUIRE(link.Call(METRO_FW_OP_CAL_CREATE, Link::Create(540, crc, 1)).result() ==
          METRO_FW_RES_SUCCESS);
  link.Call(METRO_FW_OP_CAL_WRITE, Link::Write(blob, 0));
  // Half a frame, then the link drops.
  auto partial = link.Encode(METRO_FW_OP_CAL_WRITE, 99, Link::Write(blob, 16));
  partial.resize(partial.size() / 2);
  CHECK(link.SendBytes(partial).empty());
  // The PC reconnects: its leading END closes the half frame (NAK), then it starts over.
  const auto r = link.SendBytes(link.Encode(METRO_FW_OP_GET_INFO, 1, {}));
  REQUIRE(r.size() == 2);
  CHECK(r[0].op == METRO_FW_OP_NAK);
  CHECK(r[1].op == (METRO_FW_OP_GET_INFO | 0x80));
  CHECK(link.Push(blob, 1).result() == METRO_FW_RES_SUCCESS);
  CHECK(link.ReadBack(540) == blob);
}

TEST_CASE("Frame encoder: header, CRC-16 and SLIP escapes; parser checks length and CRC",
          "[fw][push]") {
  // op 0xC0 and txn 0xDB need escapes; CRC-16/CCITT-FALSE of C0 DB 03 00 01 02 03 computed
  // bit by bit here, independently of the library.
  const uint8_t payload[3] = {1, 2, 3};
  const std::vector<uint8_t> raw = {0xC0, 0xDB, 0x03, 0x00, 0x01, 0x02, 0x03};
  uint32_t crc = 0xFFFF;
  for (uint8_t b : raw) {
    crc ^= static_cast<uint32_t>(b) << 8;
    for (int i = 0; i < 8; ++i) crc = (crc & 0x8000) ? ((crc << 1) ^ 0x1021) & 0xFFFF : crc << 1;
  }
  std::vector<uint8_t> frame = raw;
  frame.push_back(static_cast<uint8_t>(crc));
  frame.push_back(static_cast<uint8_t>(crc >> 8));
  std::vector<uint8_t> expected = {0xC0};
  for (uint8_t b : frame) {
    if (b == 0xC0 || b == 0xDB) {
      expected.push_back(0xDB);
      expected.push_back(b == 0xC0 ? 0xDC : 0xDD);
    } else {
      expected.push_back(b);
    }
  }
  expected.push_back(0xC0);
  uint8_t enc[64];
  uint32_t n = 0;
  REQUIRE(metro_fw_frame_encode(0xC0, 0xDB, payload, 3, enc, sizeof(enc), &n) == METRO_FW_OK);
  CHECK(std::vector<uint8_t>(enc, enc + n) == expected);
  // out must hold the worst case, 2 * (3 + 6) + 2 bytes, whatever the content.
  CHECK(metro_fw_frame_encode(0xC0, 0xDB, payload, 3, enc, 19, &n) == METRO_FW_E_ARG);
  CHECK(metro_fw_frame_encode(0xC0, 0xDB, payload, 3, enc, 20, &n) == METRO_FW_OK);
  CHECK(metro_fw_frame_encode(0, 0, payload, 33, enc, sizeof(enc), &n) == METRO_FW_E_ARG);
  CHECK(metro_fw_frame_encode(0, 0, nullptr, 1, enc, sizeof(enc), &n) == METRO_FW_E_ARG);
  CHECK(metro_fw_frame_encode(0, 0, nullptr, 0, enc, sizeof(enc), &n) == METRO_FW_OK);

  CHECK(metro_fw_frame_parse(frame.data(), 9) == 3);
  CHECK(metro_fw_frame_parse(frame.data(), 8) == METRO_FW_E_FRAME);
  CHECK(metro_fw_frame_parse(nullptr, 9) == METRO_FW_E_ARG);
  frame[4] ^= 0x80;
  CHECK(metro_fw_frame_parse(frame.data(), 9) == METRO_FW_E_FRAME);
}

namespace {

struct RawSink {
  std::vector<uint8_t> bytes;
  int fail = 0;  // the send callback reports an error
  static int Send(void* ctx, const uint8_t* data, uint32_t len) {
    auto* self = static_cast<RawSink*>(ctx);
    if (self->fail) return -1;
    self->bytes.insert(self->bytes.end(), data, data + len);
    return 0;
  }
};

}  // namespace

TEST_CASE("The NAK is the frame of section 7 byte for byte", "[fw][push]") {
  // op 0xFF, txn 0, len 1, FRAME_ERROR, CRC-16/CCITT-FALSE 0xBD1F of FF 00 01 00 0C (computed
  // bit by bit outside the library), SLIP END before and after.
  FakeFlash flash;
  const metro_fw_flash f = flash.Interface();
  auto p = std::make_unique<metro_fw_push>();
  RawSink sink;
  REQUIRE(metro_fw_push_init(p.get(), &f, fwtest::kDeviceId, &RawSink::Send, &sink) == METRO_FW_OK);
  const std::vector<uint8_t> garbage = {0xC0, 0x01, 0x02, 0x03, 0xC0};
  CHECK(metro_fw_push_rx(p.get(), garbage.data(), 5) == METRO_FW_E_FRAME);
  const std::vector<uint8_t> nak = {0xC0, 0xFF, 0x00, 0x01, 0x00, 0x0C, 0x1F, 0xBD, 0xC0};
  CHECK(sink.bytes == nak);
  // A failing send is reported as METRO_FW_E_FLASH, for a NAK and for a response.
  sink.fail = 1;
  CHECK(metro_fw_push_rx(p.get(), garbage.data(), 5) == METRO_FW_E_FLASH);
  uint8_t enc[40];
  uint32_t m = 0;
  REQUIRE(metro_fw_frame_encode(METRO_FW_OP_ABORT, 1, nullptr, 0, enc, sizeof(enc), &m) ==
          METRO_FW_OK);
  CHECK(metro_fw_push_rx(p.get(), enc, m) == METRO_FW_E_FLASH);
  // The response was cached all the same: the retry is answered without a new execution.
  sink.fail = 0;
  CHECK(metro_fw_push_rx(p.get(), enc, m) == METRO_FW_OK);
  const std::vector<uint8_t> abort_ok = {0xC0, 0x87, 0x01, 0x01, 0x00, 0x01};
  REQUIRE(sink.bytes.size() == nak.size() + abort_ok.size() + 3u);
  CHECK(std::vector<uint8_t>(sink.bytes.begin() + 9, sink.bytes.begin() + 15) == abort_ok);
}

TEST_CASE("A NAK between a request and its retry keeps the cached response", "[fw][push]") {
  Link link;
  link.Upload(Build(StandardBlob(1)));
  const auto exec = link.Encode(METRO_FW_OP_CAL_EXECUTE, 77, {});
  auto bytes = exec;
  const std::vector<uint8_t> noise = {0xC0, 0x05, 0xDB, 0x00, 0xC0};
  bytes.insert(bytes.end(), noise.begin(), noise.end());
  bytes.insert(bytes.end(), exec.begin(), exec.end());
  const auto r = link.SendBytes(bytes);
  REQUIRE(r.size() == 3);
  CHECK(r[0].result() == METRO_FW_RES_SUCCESS);
  CHECK(r[1].op == METRO_FW_OP_NAK);
  CHECK(r[2].op == (METRO_FW_OP_CAL_EXECUTE | 0x80));
  CHECK(r[2].payload == r[0].payload);
  CHECK(link.flash.ops == 3);  // erase, write, commit: one update only
}
