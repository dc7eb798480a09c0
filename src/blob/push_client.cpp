#include "metro/blob/push_client.hpp"

#include <fmt/format.h>

#include <chrono>
#include <random>

#include "metro/blob/intel_hex.hpp"
#include "metro_fw/crc.h"
#include "metro_fw/push.h"

namespace metro::blob {
namespace {

using Clock = std::chrono::steady_clock;

const char* OpName(uint8_t op) {
  switch (op) {
    case METRO_FW_OP_GET_INFO:
      return "GET_INFO";
    case METRO_FW_OP_CAL_CREATE:
      return "CAL_CREATE";
    case METRO_FW_OP_CAL_WRITE:
      return "CAL_WRITE";
    case METRO_FW_OP_CAL_GET_CRC:
      return "CAL_GET_CRC";
    case METRO_FW_OP_CAL_EXECUTE:
      return "CAL_EXECUTE";
    case METRO_FW_OP_CAL_READ:
      return "CAL_READ";
    case METRO_FW_OP_ABORT:
      return "ABORT";
    default:
      return "UNKNOWN";
  }
}

void Put16(std::vector<uint8_t>& b, uint16_t v) {
  b.push_back(static_cast<uint8_t>(v & 0xFF));
  b.push_back(static_cast<uint8_t>(v >> 8));
}
void Put32(std::vector<uint8_t>& b, uint32_t v) {
  for (int i = 0; i < 4; ++i) b.push_back(static_cast<uint8_t>((v >> (8 * i)) & 0xFF));
}
uint16_t Get16(const std::vector<uint8_t>& b, size_t off) {
  return static_cast<uint16_t>(b[off] | (b[off + 1] << 8));
}
uint32_t Get32(const std::vector<uint8_t>& b, size_t off) {
  return uint32_t{b[off]} | uint32_t{b[off + 1]} << 8 | uint32_t{b[off + 2]} << 16 |
         uint32_t{b[off + 3]} << 24;
}

Error Refused(uint8_t op, uint8_t result, const std::string& detail = "") {
  return MakeError(fmt::format("{}: the tag answered {}{}", OpName(op), PushResultName(result),
                               detail.empty() ? "" : " (" + detail + ")"));
}

}  // namespace

std::string TagContradictionName(TagContradiction contradiction) {
  switch (contradiction) {
    case TagContradiction::kNone:
      return "";
    case TagContradiction::kReadBackDiffers:
      return "read-back differs";
    case TagContradiction::kCrcDiffers:
      return "CRC-32 differs";
    case TagContradiction::kSeqDiffers:
      return "seq differs";
  }
  return "";
}

std::string PushResultName(uint8_t result) {
  switch (result) {
    case METRO_FW_RES_SUCCESS:
      return "SUCCESS";
    case METRO_FW_RES_BAD_STATE:
      return "BAD_STATE";
    case METRO_FW_RES_CRC_MISMATCH:
      return "CRC_MISMATCH";
    case METRO_FW_RES_FOREIGN_DEVICE:
      return "FOREIGN_DEVICE";
    case METRO_FW_RES_STALE_SEQ:
      return "STALE_SEQ";
    case METRO_FW_RES_UNSUPPORTED_FORMAT:
      return "UNSUPPORTED_FORMAT";
    case METRO_FW_RES_FLASH_ERROR:
      return "FLASH_ERROR";
    case METRO_FW_RES_INVALID_PARAM:
      return "INVALID_PARAM";
    case METRO_FW_RES_INVALID_OFFSET:
      return "INVALID_OFFSET";
    case METRO_FW_RES_INVALID_BLOB:
      return "INVALID_BLOB";
    case METRO_FW_RES_UNKNOWN_OP:
      return "UNKNOWN_OP";
    case METRO_FW_RES_FRAME_ERROR:
      return "FRAME_ERROR";
    case METRO_FW_RES_NO_CALIBRATION:
      return "NO_CALIBRATION";
    default:
      return fmt::format("result 0x{:02X}", result);
  }
}

std::optional<SlipDecoder::Frame> SlipDecoder::Feed(uint8_t c) {
  if (c == METRO_FW_SLIP_END) {
    std::optional<Frame> out;
    if (!buf_.empty() || bad_) out = Frame{bad_ ? std::vector<uint8_t>{} : buf_, bad_};
    buf_.clear();
    escape_ = false;
    bad_ = false;
    return out;
  }
  if (bad_) return std::nullopt;
  if (escape_) {
    escape_ = false;
    if (c == METRO_FW_SLIP_ESC_END) {
      c = METRO_FW_SLIP_END;
    } else if (c == METRO_FW_SLIP_ESC_ESC) {
      c = METRO_FW_SLIP_ESC;
    } else {
      bad_ = true;
      buf_.clear();
      return std::nullopt;
    }
  } else if (c == METRO_FW_SLIP_ESC) {
    escape_ = true;
    return std::nullopt;
  }
  if (buf_.size() >= max_frame_) {
    bad_ = true;
    buf_.clear();
    return std::nullopt;
  }
  buf_.push_back(c);
  return std::nullopt;
}

bool PushOptions::IsValid(std::string* why) const {
  auto fail = [&](std::string msg) {
    if (why) *why = std::move(msg);
    return false;
  };
  if (timeout_ms < 1 || execute_timeout_ms < 1) return fail("timeouts must be >= 1 ms");
  if (max_retries < 0) return fail("max_retries must be >= 0");
  if (chunk_bytes < 1 || chunk_bytes > METRO_FW_PUSH_MAX_CHUNK) {
    return fail(fmt::format("chunk_bytes {} is not 1..{}", chunk_bytes, METRO_FW_PUSH_MAX_CHUNK));
  }
  if (link_write_bytes < 1) return fail("link_write_bytes must be >= 1");
  return true;
}

PushClient::PushClient(serial::ByteStream* stream, PushOptions options)
    : stream_(stream),
      options_(options),
      // A random first txn, so a new session rarely repeats the tag's last (op, txn).
      txn_(static_cast<uint8_t>(std::random_device{}() & 0xFF)),
      decoder_(METRO_FW_PUSH_MAX_FRAME) {
  METRO_CHECK(stream != nullptr);
  std::string why;
  METRO_CHECK(options_.IsValid(&why));
}

Status PushClient::SendFrame(const std::vector<uint8_t>& enc) {
  const size_t n = enc.size();
  ++stats_.frames_sent;
  // The central forwards each write as one NUS payload of at most 20 bytes.
  for (size_t off = 0; off < n; off += options_.link_write_bytes) {
    const size_t len = std::min<size_t>(options_.link_write_bytes, n - off);
    if (Status s = stream_->Write(enc.data() + off, len); !s.ok()) return s;
  }
  return Status::Ok();
}

Result<PushClient::Response> PushClient::Transact(uint8_t op, const std::vector<uint8_t>& payload,
                                                  int timeout_ms) {
  const uint8_t txn = ++txn_;
  ++stats_.requests;
  std::vector<uint8_t> frame(2 * METRO_FW_PUSH_MAX_FRAME + 2);  // SLIP-encoded
  uint32_t flen = 0;
  METRO_CHECK(metro_fw_frame_encode(op, txn, payload.data(), static_cast<uint32_t>(payload.size()),
                                    frame.data(), static_cast<uint32_t>(frame.size()),
                                    &flen) == METRO_FW_OK);
  frame.resize(flen);
  std::string last_problem;
  for (int attempt = 0; attempt <= options_.max_retries; ++attempt) {
    if (attempt > 0) ++stats_.retries;
    if (Status s = SendFrame(frame); !s.ok()) {
      return MakeError(fmt::format("{}: link lost: {}", OpName(op), s.error().message));
    }
    const Clock::time_point deadline = Clock::now() + std::chrono::milliseconds(timeout_ms);
    bool resend = false;
    while (!resend) {
      // Bytes left over from an earlier read come first (a duplicate answer, say).
      while (rx_pos_ < rx_.size() && !resend) {
        std::optional<SlipDecoder::Frame> f = decoder_.Feed(rx_[rx_pos_++]);
        if (!f) continue;
        const int parsed =
            f->bad ? METRO_FW_E_FRAME
                   : metro_fw_frame_parse(f->bytes.data(), static_cast<uint32_t>(f->bytes.size()));
        if (parsed < 0) {
          ++stats_.ignored_frames;  // a corrupted answer: the timeout resends
          continue;
        }
        const uint8_t rop = f->bytes[0], rtxn = f->bytes[1];
        const uint8_t* rp = f->bytes.data() + 4;
        const uint32_t rn = static_cast<uint32_t>(parsed);
        if (rop == METRO_FW_OP_NAK) {
          ++stats_.naks;
          last_problem = "the tag rejected the frame (NAK)";
          resend = true;
          continue;
        }
        if (rop != (op | METRO_FW_PUSH_RESPONSE_BIT) || rtxn != txn || rn < 1) {
          ++stats_.ignored_frames;  // a late or repeated answer to an earlier request
          continue;
        }
        Response r;
        r.result = rp[0];
        r.payload.assign(rp + 1, rp + rn);
        return r;
      }
      if (resend) break;
      const auto left =
          std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now());
      if (left.count() <= 0) {
        ++stats_.timeouts;
        last_problem = fmt::format("no answer within {} ms", timeout_ms);
        break;
      }
      rx_.resize(64);
      rx_pos_ = 0;
      Result<size_t> got = stream_->Read(rx_.data(), rx_.size(), static_cast<int>(left.count()));
      if (!got.ok()) {
        rx_.clear();
        return MakeError(fmt::format("{}: link lost: {}", OpName(op), got.error().message));
      }
      rx_.resize(got.value());
    }
  }
  return MakeError(fmt::format("{}: no valid answer after {} attempts ({})", OpName(op),
                               options_.max_retries + 1, last_problem));
}

Result<TagInfo> PushClient::GetInfo() {
  Result<Response> r = Transact(METRO_FW_OP_GET_INFO, {}, options_.timeout_ms);
  if (!r.ok()) return r.error();
  const Response& x = r.value();
  if (x.result != METRO_FW_RES_SUCCESS) return Refused(METRO_FW_OP_GET_INFO, x.result);
  if (x.payload.size() < 21) {
    return MakeError(
        fmt::format("GET_INFO: answer of {} bytes, expected 22", x.payload.size() + 1));
  }
  TagInfo info;
  info.fmt_major = x.payload[0];
  info.fmt_minor = x.payload[1];
  info.active_slot = x.payload[2] == 0xFF ? -1 : x.payload[2];
  info.max_len = Get16(x.payload, 3);
  info.device_id = uint64_t{Get32(x.payload, 9)} << 32 | Get32(x.payload, 5);
  info.active_seq = Get32(x.payload, 13);
  info.active_crc32 = Get32(x.payload, 17);
  return info;
}

Status PushClient::Abort() {
  Result<Response> r = Transact(METRO_FW_OP_ABORT, {}, options_.timeout_ms);
  if (!r.ok()) return r.error();
  if (r.value().result != METRO_FW_RES_SUCCESS) return Refused(METRO_FW_OP_ABORT, r.value().result);
  return Status::Ok();
}

Result<int> PushClient::Push(const std::vector<uint8_t>& blob, const PushProgress& progress) {
  if (blob.size() < 36 || blob.size() > METRO_FW_MAX_LEN || blob.size() % 4 != 0) {
    return MakeError(
        fmt::format("blob of {} bytes: expected a multiple of 4 in 36..1024", blob.size()));
  }
  commit_ = CommitState::kNotSent;
  contradiction_ = TagContradiction::kNone;
  const uint16_t total = static_cast<uint16_t>(blob.size());
  const uint32_t crc = metro_fw_crc32(0, blob.data(), total);
  const uint32_t seq = Get32(blob, 12);
  std::vector<uint8_t> create;
  Put16(create, total);
  Put32(create, crc);
  Put32(create, seq);
  Result<Response> c = Transact(METRO_FW_OP_CAL_CREATE, create, options_.timeout_ms);
  if (!c.ok()) return c.error();
  if (c.value().result != METRO_FW_RES_SUCCESS) {
    return Refused(METRO_FW_OP_CAL_CREATE, c.value().result,
                   c.value().result == METRO_FW_RES_STALE_SEQ
                       ? fmt::format("seq {} is not above the tag's active seq", seq)
                       : "");
  }

  for (int pass = 0; pass < 2; ++pass) {
    size_t offset = 0;
    // Every INVALID_OFFSET answer moves the transfer to the tag's received_len; a tag that
    // keeps answering it (even with lengths that look like progress, 16, 0, 16, ...) would
    // otherwise hold the PC forever, so each pass allows max_retries of them.
    int resumes = 0;
    while (offset < total) {
      const size_t len = std::min(options_.chunk_bytes, total - offset);
      std::vector<uint8_t> w;
      Put16(w, static_cast<uint16_t>(offset));
      w.insert(w.end(), blob.begin() + static_cast<std::ptrdiff_t>(offset),
               blob.begin() + static_cast<std::ptrdiff_t>(offset + len));
      Result<Response> r = Transact(METRO_FW_OP_CAL_WRITE, w, options_.timeout_ms);
      if (!r.ok()) return r.error();
      const Response& x = r.value();
      if (x.payload.size() < 2 ||
          (x.result != METRO_FW_RES_SUCCESS && x.result != METRO_FW_RES_INVALID_OFFSET)) {
        return Refused(METRO_FW_OP_CAL_WRITE, x.result, fmt::format("offset {}", offset));
      }
      const size_t received = Get16(x.payload, 0);
      if (x.result == METRO_FW_RES_INVALID_OFFSET && ++resumes > options_.max_retries) {
        return MakeError(fmt::format(
            "CAL_WRITE: the tag answered INVALID_OFFSET {} times in one pass (last: offset {} "
            "sent, received_len {}); at most {} resumes (--retries) are allowed",
            resumes, offset, received, options_.max_retries));
      }
      // Contiguous transfer: continue where the tag says it is (resume after a gap).
      const size_t next = x.result == METRO_FW_RES_SUCCESS ? offset + len : received;
      offset = std::min<size_t>(next, total);
      if (progress) progress("write", offset, total);
    }
    Result<Response> g = Transact(METRO_FW_OP_CAL_GET_CRC, {}, options_.timeout_ms);
    if (!g.ok()) return g.error();
    if (g.value().result != METRO_FW_RES_SUCCESS || g.value().payload.size() < 6) {
      return Refused(METRO_FW_OP_CAL_GET_CRC, g.value().result);
    }
    const uint16_t have = Get16(g.value().payload, 0);
    const uint32_t have_crc = Get32(g.value().payload, 2);
    if (have == total && have_crc == crc) break;
    if (pass == 1) {
      // Every CAL_WRITE was acknowledged twice over: the tag's answer contradicts them.
      contradiction_ = TagContradiction::kCrcDiffers;
      return MakeError(
          fmt::format("CAL_GET_CRC: the tag acknowledged every byte but holds {} bytes with CRC-32 "
                      "0x{:08X}, expected {} bytes with 0x{:08X}, after a full resend",
                      have, have_crc, total, crc));
    }
  }

  commit_ = CommitState::kUnknown;  // from the first EXECUTE frame on, the tag may commit
  Result<Response> e = Transact(METRO_FW_OP_CAL_EXECUTE, {}, options_.execute_timeout_ms);
  int slot = -1;
  if (e.ok() && e.value().result == METRO_FW_RES_SUCCESS && e.value().payload.size() >= 5) {
    commit_ = CommitState::kCommitted;
    slot = e.value().payload[0];
    if (Get32(e.value().payload, 1) != seq) {
      // SUCCESS for another seq than the one sent: what the tag holds is unknown.
      commit_ = CommitState::kUnknown;
      contradiction_ = TagContradiction::kSeqDiffers;
      return MakeError(fmt::format("CAL_EXECUTE: the tag answered SUCCESS with seq {}, sent {}",
                                   Get32(e.value().payload, 1), seq));
    }
  } else if (e.ok() && e.value().result != METRO_FW_RES_FLASH_ERROR &&
             e.value().result != METRO_FW_RES_SUCCESS) {
    commit_ = CommitState::kNotDone;  // refused before the update touched the flash
    return Refused(METRO_FW_OP_CAL_EXECUTE, e.value().result);
  } else {
    // No answer, or FLASH_ERROR (which may come after the commit word was written): ask the
    // tag which calibration is live.
    const Error what = e.ok() ? Refused(METRO_FW_OP_CAL_EXECUTE, e.value().result) : e.error();
    Result<TagInfo> info = GetInfo();
    if (!info.ok()) return what;  // commit_ stays kUnknown
    // GET_INFO reports the blob's own CRC word (over [0, total_len - 4)).
    if (info.value().active_seq == seq && info.value().active_crc32 == Get32(blob, total - 4u)) {
      commit_ = CommitState::kCommitted;
      slot = info.value().active_slot;
    } else if (info.value().active_seq < seq) {
      commit_ = CommitState::kNotDone;
      return MakeError(fmt::format("{}; GET_INFO: the tag still holds seq {}", what.message,
                                   info.value().active_seq));
    } else if (info.value().active_seq == seq) {
      // The pushed seq with other bytes than were acknowledged.
      contradiction_ = TagContradiction::kCrcDiffers;
      return MakeError(fmt::format(
          "{}; GET_INFO: the tag holds seq {} with CRC-32 0x{:08X}, but the blob sent as seq {} "
          "has 0x{:08X}",
          what.message, seq, info.value().active_crc32, seq, Get32(blob, total - 4u)));
    } else {
      return MakeError(fmt::format("{}; GET_INFO: the tag holds seq {} with CRC-32 0x{:08X}",
                                   what.message, info.value().active_seq,
                                   info.value().active_crc32));
    }
  }
  if (Status s = ReadBack(blob, progress); !s.ok()) return s.error();
  return slot;
}

Status PushClient::ReadBack(const std::vector<uint8_t>& blob, const PushProgress& progress) {
  const size_t total = blob.size();
  for (size_t offset = 0; offset < total; offset += options_.chunk_bytes) {
    const size_t len = std::min(options_.chunk_bytes, total - offset);
    std::vector<uint8_t> q;
    Put16(q, static_cast<uint16_t>(offset));
    q.push_back(static_cast<uint8_t>(len));
    Result<Response> r = Transact(METRO_FW_OP_CAL_READ, q, options_.timeout_ms);
    if (!r.ok()) return r.error();
    if (r.value().result != METRO_FW_RES_SUCCESS || r.value().payload.size() != len) {
      return Refused(METRO_FW_OP_CAL_READ, r.value().result, fmt::format("offset {}", offset));
    }
    for (size_t i = 0; i < len; ++i) {
      if (r.value().payload[i] != blob[offset + i]) {
        contradiction_ = TagContradiction::kReadBackDiffers;
        return MakeError(
            fmt::format("read-back: byte {} of the active slot is 0x{:02X}, sent 0x{:02X}",
                        offset + i, r.value().payload[i], blob[offset + i]));
      }
    }
    if (progress) progress("verify", offset + len, total);
  }
  return Status::Ok();
}

PushSummary PushCalibration(serial::ByteStream* stream, const Calibration& calibration,
                            BlobFromCalibrationOptions blob_options,
                            std::optional<uint64_t> expect_device_id, const PushOptions& options,
                            const PushProgress& progress) {
  PushSummary s;
  PushClient client(stream, options);
  Result<TagInfo> info = client.GetInfo();
  s.stats = client.stats();
  if (!info.ok()) {
    s.message = "no tag: " + info.error().message;
    return s;
  }
  s.tag = info.value();
  s.tag_answered = true;
  if (s.tag.fmt_major != 1) {
    s.message =
        fmt::format("the tag reads blob format {}.x; this tool writes 1.0", s.tag.fmt_major);
    return s;
  }
  if (expect_device_id && *expect_device_id != s.tag.device_id) {
    s.input_error = true;
    s.message = fmt::format("the tag on the link is {}, not {}: nothing was written",
                            FormatDeviceId(s.tag.device_id), FormatDeviceId(*expect_device_id));
    return s;
  }
  blob_options.device_id = s.tag.device_id;
  if (blob_options.seq == 0) {
    if (s.tag.active_seq >= kSeqMax) {
      s.message = fmt::format(
          "the tag's seq is exhausted ({}); only the wired path (a factory HEX) resets it",
          s.tag.active_seq);
      return s;
    }
    blob_options.seq = s.tag.active_seq + 1;
  }
  s.seq = blob_options.seq;
  Result<BlobContents> contents =
      BlobContentsFromCalibration(calibration, blob_options, &s.warnings);
  Result<std::vector<uint8_t>> blob =
      contents.ok() ? WriteBlob(contents.value()) : Result<std::vector<uint8_t>>(contents.error());
  if (!blob.ok()) {
    s.input_error = true;
    s.message = blob.error().message;
    return s;
  }
  s.blob = blob.value();
  if (s.tag.active_slot >= 0 && s.tag.active_seq == s.seq &&
      s.tag.active_crc32 == Get32(s.blob, s.blob.size() - 4)) {
    // The same push again (after an unknown outcome): nothing to write, only to compare.
    s.already_held = true;
    s.commit = CommitState::kCommitted;
    s.slot = s.tag.active_slot;
    Status back = client.ReadBack(s.blob, progress);
    s.stats = client.stats();
    if (!back.ok()) {
      s.contradiction = client.contradiction();
      if (s.contradiction != TagContradiction::kNone) {
        s.contradiction_detail = back.error().message;
        s.message = fmt::format(
            "the tag contradicts itself: GET_INFO reports seq {} with this blob's CRC-32, but "
            "{}; what it runs is unknown until its flash is read over SWD",
            s.seq, back.error().message);
      } else {
        s.message = fmt::format("the tag holds seq {} with this blob's CRC-32, but {}", s.seq,
                                back.error().message);
      }
      return s;
    }
    s.ok = true;
    s.message = fmt::format(
        "tag {} already holds this calibration: seq {} in slot {}, {} bytes read back "
        "identical; nothing written",
        FormatDeviceId(s.tag.device_id), s.seq, s.slot == 0 ? "A" : "B", s.blob.size());
    return s;
  }
  if (s.blob.size() > s.tag.max_len) {
    s.message = fmt::format("the blob has {} bytes; the tag takes at most {}", s.blob.size(),
                            s.tag.max_len);
    return s;
  }
  Result<int> slot = client.Push(s.blob, progress);
  s.stats = client.stats();
  s.commit = client.commit_state();
  s.contradiction = client.contradiction();
  if (!slot.ok()) {
    if (s.contradiction != TagContradiction::kNone) {
      // Neither a refusal nor a lost answer: the tag's word cannot be trusted.
      s.contradiction_detail = slot.error().message;
      s.message = fmt::format(
          "the tag contradicts itself ({}) pushing seq {}: {}; what it runs is unknown until "
          "its flash is read over SWD",
          TagContradictionName(s.contradiction), s.seq, slot.error().message);
    } else if (s.commit == CommitState::kUnknown) {
      s.message =
          fmt::format("outcome unknown: the tag may hold seq {} ({})", s.seq, slot.error().message);
    } else if (s.commit == CommitState::kCommitted) {
      s.message = fmt::format("the tag committed seq {}, but the read-back did not finish ({})",
                              s.seq, slot.error().message);
    } else {
      s.message = slot.error().message;
    }
    return s;
  }
  s.slot = slot.value();
  s.ok = true;
  s.message =
      fmt::format("tag {} calibrated: seq {} in slot {}, {} bytes read back identical",
                  FormatDeviceId(s.tag.device_id), s.seq, s.slot == 0 ? "A" : "B", s.blob.size());
  if (s.seq == kSeqMax) {
    s.message += fmt::format(
        "; seq {} is the last: the next update needs the wired path (it restarts at 1)", kSeqMax);
  }
  return s;
}

std::string PushReadBackText(const PushSummary& s) {
  if (s.ok) return "verified: every byte read back equal";
  switch (s.contradiction) {
    case TagContradiction::kReadBackDiffers: {
      const std::string prefix = "read-back: ";
      const std::string& d = s.contradiction_detail;
      return "differs: " + (d.rfind(prefix, 0) == 0 ? d.substr(prefix.size()) : d);
    }
    case TagContradiction::kCrcDiffers:
    case TagContradiction::kSeqDiffers:
      return "not read back: the tag contradicted itself (" +
             TagContradictionName(s.contradiction) + "): " + s.contradiction_detail;
    case TagContradiction::kNone:
      break;
  }
  return s.commit == CommitState::kCommitted ? "committed, read-back not finished"
         : s.commit == CommitState::kUnknown ? "outcome unknown"
                                             : "not committed";
}

uint32_t WiredPathSeq(const PushSummary& s) {
  const uint64_t seq = s.seq != 0 ? uint64_t{s.seq} : uint64_t{s.tag.active_seq} + 1;
  return seq >= 1 && seq <= kSeqMax ? static_cast<uint32_t>(seq) : 1u;
}

std::string PushRecoveryAdvice(const PushSummary& s, const std::string& port,
                               const std::string& calibration_path, int sensor) {
  if (s.ok || s.input_error || !s.tag_answered) return "";
  std::string out;
  // A tag that contradicted itself would answer a second push alike: only SWD tells.
  if (s.contradiction == TagContradiction::kNone &&
      (s.commit == CommitState::kUnknown || s.commit == CommitState::kCommitted)) {
    out += fmt::format(
        "to find out: calibrate push --port {} {} --sensor {} --device-id {} --seq {} (a tag "
        "that holds this blob is only read back and compared; one that does not gets seq {})\n",
        port, calibration_path, sensor, FormatDeviceId(s.tag.device_id), s.seq, s.seq);
  }
  const uint32_t seq = WiredPathSeq(s);
  out += fmt::format(
      "to program over SWD instead: calibrate blob {} --sensor {} --device-id {} --seq {} -o "
      "tag.bin --hex tag.hex && {}\n",
      calibration_path, sensor, FormatDeviceId(s.tag.device_id), seq, NrfjprogCommand("tag.hex"));
  if (seq == 1 && s.tag.active_seq >= kSeqMax) {
    out += fmt::format(
        "the tag's seq space is exhausted ({}): the HEX erases both slot pages, so seq 1 is "
        "the only calibration afterwards\n",
        s.tag.active_seq);
  }
  return out;
}

}  // namespace metro::blob
