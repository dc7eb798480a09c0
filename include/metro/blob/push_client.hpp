// The PC side of the calibration push protocol (docs/calibration-blob.md section 7): SLIP
// framing, CRC-16 frames, the transfer in 16-byte CAL_WRITE chunks, ACK/NAK with retries and
// timeouts, and the read-back comparison after CAL_EXECUTE.
//
// The client talks through a ByteStream (a serial port to the BLE central, a pseudo-terminal
// to the simulated tag, or a test fake), so it is tested without a tty. Frames are built and
// SLIP-encoded, and checked, by the firmware's own C functions (metro_fw_frame_encode /
// metro_fw_frame_parse), so both ends share one definition of the wire format.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "metro/blob/from_calibration.hpp"
#include "metro/core/status.hpp"
#include "metro/serial/byte_stream.hpp"

namespace metro::blob {

// SLIP (RFC 1055) decoder, one byte at a time. Frames longer than max_frame bytes, or with an
// ESC not followed by ESC_END/ESC_ESC, are reported as bad (empty vector plus bad = true).
class SlipDecoder {
 public:
  explicit SlipDecoder(size_t max_frame) : max_frame_(max_frame) {}
  struct Frame {
    std::vector<uint8_t> bytes;
    bool bad = false;
  };
  // Returns a frame when `byte` is the END that closes a non-empty (or bad) frame.
  std::optional<Frame> Feed(uint8_t byte);

 private:
  size_t max_frame_;
  std::vector<uint8_t> buf_;
  bool escape_ = false;
  bool bad_ = false;
};

struct PushOptions {
  int timeout_ms = 1000;          // Wait for each response (BLE round trip and flash work).
  int execute_timeout_ms = 3000;  // CAL_EXECUTE erases and programs a page first.
  int max_retries = 5;            // Resends of one request after a timeout or NAK.
  size_t chunk_bytes = 16;        // CAL_WRITE / CAL_READ data bytes per frame, 1..16.
  size_t link_write_bytes = 20;   // Encoded bytes per write: one BLE NUS payload (ATT MTU 23).

  bool IsValid(std::string* why) const;
};

// GET_INFO.
struct TagInfo {
  uint8_t fmt_major = 0;
  uint8_t fmt_minor = 0;
  int active_slot = -1;  // 0 A, 1 B, -1 none
  uint16_t max_len = 0;
  uint64_t device_id = 0;  // (DEVICEID[1] << 32) | DEVICEID[0]
  uint32_t active_seq = 0;
  uint32_t active_crc32 = 0;
};

struct PushStats {
  int requests = 0;        // Distinct requests.
  int frames_sent = 0;     // Including resends.
  int retries = 0;         // Resends after a timeout or NAK.
  int naks = 0;            // NAK frames received.
  int timeouts = 0;        // Waits that expired.
  int ignored_frames = 0;  // Stale, duplicate or corrupted responses skipped.
};

// What the tag holds after CAL_EXECUTE was sent, as far as the PC knows.
enum class CommitState {
  kNotSent,    // CAL_EXECUTE was never sent: the tag keeps its calibration.
  kNotDone,    // The tag refused the update, or GET_INFO afterwards shows its old seq.
  kUnknown,    // Sent, and neither an answer nor GET_INFO came back: the tag may hold the seq.
  kCommitted,  // The tag answered SUCCESS, or GET_INFO shows the pushed seq and CRC-32.
};

// A tag that contradicts what it acknowledged (issue #37: a lying tag's push was labelled
// "UNVERIFIED ... the read-back did not finish", or FAILED like a refusal). Frames are CRC-16
// checked and retried, so this is no link fault: the tag's own word cannot be trusted, and
// what it runs is unknown until its flash is read out over SWD.
enum class TagContradiction {
  kNone,
  // It acknowledged the blob (CAL_EXECUTE answered SUCCESS, or GET_INFO showed the pushed seq
  // and CRC-32) but CAL_READ returns other bytes.
  kReadBackDiffers,
  // It acknowledged every CAL_WRITE but CAL_GET_CRC reports another length or CRC-32 (after a
  // full resend), or GET_INFO reports the pushed seq with another CRC-32.
  kCrcDiffers,
  // CAL_EXECUTE answered SUCCESS naming another seq (version) than the pushed blob's.
  kSeqDiffers,
};

// "read-back differs", "CRC-32 differs", "seq differs" ("" for kNone).
std::string TagContradictionName(TagContradiction contradiction);

// Name of a push result code, e.g. "STALE_SEQ" (0x05).
std::string PushResultName(uint8_t result);

// bytes_done of bytes_total have been acknowledged (CAL_WRITE, then read back).
using PushProgress = std::function<void(const char* phase, size_t bytes_done, size_t bytes_total)>;

class PushClient {
 public:
  // `stream` must outlive the client.
  PushClient(serial::ByteStream* stream, PushOptions options);

  Result<TagInfo> GetInfo();
  // CAL_CREATE, CAL_WRITE (resuming at the tag's received_len on INVALID_OFFSET, at most
  // max_retries times per pass whatever the tag answers), CAL_GET_CRC (one full resend on a
  // mismatch), CAL_EXECUTE, then CAL_READ of every byte compared with `blob`. Returns the slot
  // written. Errors name the step and the tag's result, e.g. "CAL_CREATE: the tag answered
  // STALE_SEQ". When CAL_EXECUTE gets no answer (link lost, retries spent) or FLASH_ERROR, the
  // tag may have committed: GET_INFO asks which seq it holds; the pushed seq and CRC-32 there
  // mean the update is live and the read-back follows. commit_state() says what is known.
  Result<int> Push(const std::vector<uint8_t>& blob, const PushProgress& progress = {});
  // CAL_READ of every byte of the active slot, compared with `blob`.
  Status ReadBack(const std::vector<uint8_t>& blob, const PushProgress& progress = {});
  Status Abort();

  const PushStats& stats() const { return stats_; }
  CommitState commit_state() const { return commit_; }
  // Set by Push or ReadBack when the tag contradicted what it acknowledged (the error says how).
  TagContradiction contradiction() const { return contradiction_; }

 private:
  struct Response {
    uint8_t result = 0;
    std::vector<uint8_t> payload;  // After the result byte.
  };
  Result<Response> Transact(uint8_t op, const std::vector<uint8_t>& payload, int timeout_ms);
  Status SendFrame(const std::vector<uint8_t>& enc);  // SLIP-encoded, in NUS-sized writes

  serial::ByteStream* stream_;
  PushOptions options_;
  uint8_t txn_;
  PushStats stats_;
  SlipDecoder decoder_;
  std::vector<uint8_t> rx_;  // Bytes read but not yet decoded.
  size_t rx_pos_ = 0;
  CommitState commit_ = CommitState::kNotSent;
  TagContradiction contradiction_ = TagContradiction::kNone;
};

// What `calibrate push` reports.  Defaults read as failure.
struct PushSummary {
  bool ok = false;
  bool input_error = false;  // The calibration could not become a blob (exit 2, not 1).
  // kUnknown: "outcome unknown: the tag may hold seq N"; kCommitted without ok: the new
  // calibration is live but the read-back did not finish.
  CommitState commit = CommitState::kNotSent;
  bool already_held = false;  // The tag already held this blob (--seq N): only read back.
  // Not kNone: the tag contradicted what it acknowledged (never ok; `message` says how).
  TagContradiction contradiction = TagContradiction::kNone;
  std::string contradiction_detail;  // How, in one line: "read-back: byte 156 of ...".
  std::string message;               // Final status, one line.
  TagInfo tag;                       // From GET_INFO (valid once the tag answered).
  bool tag_answered = false;
  uint32_t seq = 0;  // Of the pushed blob.
  int slot = -1;     // Written by the tag.
  std::vector<uint8_t> blob;
  PushStats stats;
  // The blob's validity-range warnings ("sensor N accel: ...", BlobContentsFromCalibration).
  std::vector<std::string> warnings;
};

// calibrate push: GET_INFO, then the blob of blob_options.sensor built for the tag's device id
// with seq = blob_options.seq if not 0, else the tag's active seq + 1, then Push. When
// expect_device_id is set, a tag with another id is refused before anything is written. A tag
// whose active seq and CRC-32 already are the blob's (a push repeated with --seq N after an
// unknown outcome) is only read back (already_held). An active seq of kSeqMax cannot be
// exceeded: refused before anything is sent (the wired path restarts the seq space).
PushSummary PushCalibration(serial::ByteStream* stream, const Calibration& calibration,
                            BlobFromCalibrationOptions blob_options,
                            std::optional<uint64_t> expect_device_id, const PushOptions& options,
                            const PushProgress& progress = {});

// What the read-back found, as the registry's push record keeps it (docs/registry.md):
// "verified: every byte read back equal", "differs: byte 156 of the active slot is 0x4F, sent
// 0x54" (a tag that acknowledged the blob), "not read back: the tag reported seq 5 for seq 4"
// or "... another CRC-32 ..." (a tag that contradicted itself before), "committed, read-back
// not finished", "outcome unknown" or "not committed".
std::string PushReadBackText(const PushSummary& summary);

// The seq for the wired path (`calibrate blob --seq S --hex` and nrfjprog --sectorerase, which
// erases both slot pages: the blob in A, the tombstone in B): the pushed seq, else the tag's
// active seq + 1, and 1 past the end of the seq space (an exhausted tag restarts at 1). Always
// in 1..kSeqMax, so the advice never names a seq `calibrate blob` refuses.
uint32_t WiredPathSeq(const PushSummary& summary);

// The lines `calibrate push` prints after a push that did not end OK: how to find out what the
// tag holds (outcome unknown, or committed but not read back), and the wired path with
// WiredPathSeq. Empty for an input error or when no tag answered. `port` and
// `calibration_path` as given on the command line.
std::string PushRecoveryAdvice(const PushSummary& summary, const std::string& port,
                               const std::string& calibration_path, int sensor);

}  // namespace metro::blob
