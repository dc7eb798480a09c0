// calibrate push --port /dev/ttyX calibration.json --sensor N [--device-id HEX16] [--seq N]
//   [--timeout-ms MS] [--retries N] [--profile mpu6050|generic] [--accel-fs-g G] [--gyro-fs-dps D]
#include "push_command.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "cli_progress.hpp"
#include "commands.hpp"
#include "metro/blob/from_calibration.hpp"
#include "metro/blob/push_client.hpp"
#include "metro/calibration/calibration_io.hpp"
#include "metro/serial/serial_port.hpp"
#include "registry_hooks.hpp"
#include "tags_cli.hpp"

namespace metro::calibrate_app {
namespace {

int RunPushAll(const PushCliOptions& c);

// The tags file (--tags) and calibration.json of a push; false (said on stderr) when either
// cannot be read.
bool LoadPushInputs(const PushCliOptions& c, std::optional<TagRegistry>* tags, Calibration* cal) {
  Result<std::optional<TagRegistry>> t = LoadTagsOption(c.tags);
  if (!t.ok()) {
    apps::PrintError(t.error());
    return false;
  }
  Result<Calibration> loaded = LoadCalibration(c.calibration);
  if (!loaded.ok()) {
    apps::PrintErrorText(loaded.error().ToString());
    return false;
  }
  *tags = std::move(t).value();
  *cal = std::move(loaded).value();
  return true;
}

// The tag the push must reach (docs/calibration-blob.md 1.1): a push to a tag whose device ID
// is not known is refused unless --any-device (whichever tag answers, whatever the tags file or
// calibration.json say: nullopt).
Result<std::optional<uint64_t>> PushTarget(const PushCliOptions& c,
                                           const std::optional<TagRegistry>& tags,
                                           const Calibration& cal) {
  Result<std::optional<uint64_t>> resolved = ResolveDeviceId(c.device_id, tags, cal, c.sensor);
  if (!resolved.ok()) return resolved;
  if (c.any_device && !c.device_id.empty()) {
    return MakeError("--any-device and --device-id contradict each other: give one");
  }
  if (c.any_device) return std::optional<uint64_t>();
  if (!resolved.value()) {
    return MakeError(fmt::format(
        "no device ID known for sensor {}: give --device-id, --tags FILE with its device_id, or "
        "--any-device to write to whichever tag answers (nothing sent; {} not opened)",
        c.sensor, c.port));
  }
  return resolved;
}

// The blob's options from the flags and the tags file's profile.
blob::BlobFromCalibrationOptions PushBlobOptions(const PushCliOptions& c,
                                                 const std::optional<TagRegistry>& tags) {
  blob::BlobFromCalibrationOptions bo;
  bo.sensor = c.sensor;
  bo.seq = c.seq;
  bo.dlpf_cfg = static_cast<uint8_t>(c.dlpf_cfg);
  bo.t_valid_min_c = c.t_valid_min_c;
  bo.t_valid_max_c = c.t_valid_max_c;
  bo.profile = ResolveProfile(c.profile, tags, c.sensor);
  bo.accel_fs_g = c.accel_fs_g;
  bo.gyro_fs_dps = c.gyro_fs_dps;
  bo.accept_rejected_model = c.accept_rejected_model;
  return bo;
}

// Whether the blob format can represent the constants does not depend on the tag's device id or
// seq: checked with the firmware's own rules (WriteBlob) before any port is opened. The push
// builds the blob again for the tag that answers.
Status CheckBlobWritable(const Calibration& cal, blob::BlobFromCalibrationOptions trial) {
  trial.seq = 1;
  Result<blob::BlobContents> contents = blob::BlobContentsFromCalibration(cal, trial);
  if (!contents.ok()) return contents.error();
  return blob::WriteBlob(contents.value()).status();
}

// The push over the open port, with one progress bar per phase ("write 320/540 B") on a
// terminal only.
blob::PushSummary PushOverPort(serial::SerialPort* port, const Calibration& cal,
                               const blob::BlobFromCalibrationOptions& bo,
                               const std::optional<uint64_t>& expect, const PushCliOptions& c) {
  blob::PushOptions po;
  po.timeout_ms = c.timeout_ms;
  po.execute_timeout_ms = 3 * c.timeout_ms;  // CAL_EXECUTE erases and programs a page
  po.max_retries = c.retries;
  TerminalProgress bar(stderr, apps::CliProgressOptions());
  std::string phase_shown;
  size_t done_shown = 0;
  const blob::PushProgress progress = [&](const char* phase, size_t done, size_t total) {
    if (phase_shown != phase) {
      bar.BeginPhase(phase, static_cast<int64_t>(total), "B");
      phase_shown = phase;
      done_shown = 0;
    }
    if (done > done_shown) {
      bar.Advance(static_cast<int64_t>(done - done_shown));
      done_shown = done;
    }
  };
  blob::PushSummary s = blob::PushCalibration(port, cal, bo, expect, po, progress);
  bar.Finish();
  return s;
}

// What the tag and the link did: notes (not under --quiet), except on failure; the warnings
// always.
void PrintPushLink(const blob::PushSummary& s) {
  for (const std::string& w : s.warnings) apps::PrintWarning(w);
  const bool notes = !s.ok || !apps::Quiet();
  if (s.tag_answered && notes) {
    apps::PrintText(
        stderr, fmt::format("tag {}: format {}.{}, active slot {}, seq {}\n",
                            blob::FormatDeviceId(s.tag.device_id), s.tag.fmt_major, s.tag.fmt_minor,
                            s.tag.active_slot < 0 ? "none" : (s.tag.active_slot == 0 ? "A" : "B"),
                            s.tag.active_seq));
  }
  if (notes) {
    apps::PrintText(
        stderr, fmt::format("link: {} requests, {} frames sent, {} retries, {} NAKs, {} timeouts\n",
                            s.stats.requests, s.stats.frames_sent, s.stats.retries, s.stats.naks,
                            s.stats.timeouts));
  }
}

// The verdict for --all's table.
std::string PushOutcome(const blob::PushSummary& s) {
  if (s.ok) {
    return fmt::format("OK: seq {} in slot {}, read back identical", s.seq,
                       s.slot == 0 ? "A" : "B");
  }
  if (s.contradiction != blob::TagContradiction::kNone) {
    return "MISMATCH: " + blob::TagContradictionName(s.contradiction);
  }
  return s.commit == blob::CommitState::kUnknown     ? "outcome unknown"
         : s.commit == blob::CommitState::kCommitted ? "UNVERIFIED"
                                                     : "FAILED";
}

// The result, one line (a newline in the message, from a port or file name, is escaped), and
// on failure what to do next; the exit code. An unknown outcome or a live but unchecked
// calibration is not a failure to write: the message says what the tag may hold
// (docs/calibration-blob.md section 11). A tag that contradicted what it acknowledged is
// neither (issue #37).
int FinishPush(const blob::PushSummary& s, const PushCliOptions& c, int recorded) {
  const std::string message = EscapeControlChars(s.message);
  if (s.ok) {
    apps::Note(fmt::format("OK: {}\n", message));
    return recorded;
  }
  if (s.contradiction != blob::TagContradiction::kNone) {
    apps::PrintText(stderr, fmt::format("MISMATCH: {}\n", message));
  } else if (s.commit == blob::CommitState::kUnknown) {
    apps::PrintText(stderr, message + "\n");
  } else if (s.commit == blob::CommitState::kCommitted) {
    apps::PrintText(stderr, fmt::format("UNVERIFIED: {}\n", message));
  } else {
    apps::PrintText(stderr, fmt::format("FAILED: {}\n", message));
  }
  // One command per line: the port and file names are data (escaped).
  apps::PrintText(stderr, blob::PushRecoveryAdvice(s, EscapeControlChars(c.port),
                                                   EscapeControlChars(c.calibration), c.sensor));
  return s.input_error ? kExitUsage : kExitFailed;
}

// The registry of --registry, opened on first use (after the checks that need none, so a push
// refused before the port is opened never touches it) and kept for every tag of --all.
class PushRegistry {
 public:
  explicit PushRegistry(const RegistryCliOptions& options) : options_(options) {}
  // False (said on stderr, the exit code in *exit_code) when it cannot be opened; *registry is
  // null without --registry.
  bool Get(Registry** registry, int* exit_code) {
    if (!opened_) opened_ = OpenRegistryOption(options_);
    *exit_code = opened_->exit_code;
    *registry = opened_->registry.get();
    return opened_->exit_code == 0;
  }

 private:
  const RegistryCliOptions& options_;
  std::optional<OpenedRegistry> opened_;
};

// One tag's push from the loaded inputs: its device, the blob checked before the port is
// opened, the push and its read-back, recorded. `outcome`, when not null, receives the final
// line's verdict for --all's table.
int PushTag(const PushCliOptions& c, const std::optional<TagRegistry>& tags, const Calibration& cal,
            PushRegistry* registry, std::string* outcome) {
  if (cal.FindTag(c.sensor) == nullptr) {
    apps::PrintErrorText(CalibrationErrorText(c.calibration, NoSensorError(cal, c.sensor)) +
                         fmt::format(" (nothing sent; {} not opened)", c.port));
    return kExitUsage;
  }
  Result<std::optional<uint64_t>> expect = PushTarget(c, tags, cal);
  if (!expect.ok()) return apps::PrintErrorExit(expect.error());
  const blob::BlobFromCalibrationOptions bo = PushBlobOptions(c, tags);
  if (Status w = CheckBlobWritable(cal, bo); !w.ok()) {
    apps::PrintErrorText(fmt::format("{} (nothing sent; {} not opened)",
                                     CalibrationErrorText(c.calibration, w.error()), c.port));
    return apps::ExitCodeFor(w.error());
  }
  Registry* reg = nullptr;
  if (int rc = kExitOk; !registry->Get(&reg, &rc)) return rc;
  Result<std::unique_ptr<serial::SerialPort>> port = serial::SerialPort::Open(c.port);
  if (!port.ok()) {
    apps::PrintErrorText(port.error().ToString());
    // The tag cannot be reached through the port: the push failed (exit 1,
    // docs/calibration-blob.md).
    return apps::ExitCodeFor(port.error().WithKind(ErrorKind::kFailed));
  }
  const blob::PushSummary s = PushOverPort(port.value().get(), cal, bo, expect.value(), c);
  PrintPushLink(s);
  const int recorded =
      RecordPushResult(reg, cal, c.calibration, c.sensor, s, expect.value(), c.port, c.registry);
  if (outcome != nullptr) *outcome = PushOutcome(s);
  return FinishPush(s, c, recorded);
}

int RunPush(const PushCliOptions& c) {
  if (c.all) return RunPushAll(c);
  if (c.sensor < 1) {
    apps::PrintErrorText("--sensor N names the tag in calibration.json (or --all for every tag)");
    return kExitUsage;
  }
  std::optional<TagRegistry> tags;
  Calibration cal;
  if (!LoadPushInputs(c, &tags, &cal)) return kExitUsage;
  PushRegistry registry(c.registry);
  return PushTag(c, tags, cal, &registry, nullptr);
}

// --all: the one-tag options of every tag of calibration.json, each with its device ID; a tag
// without one stops the run before the port is opened (false, said on stderr, the exit code
// in *exit_code).
bool EveryTagPush(const PushCliOptions& c, const std::optional<TagRegistry>& tags,
                  const Calibration& cal, std::vector<PushCliOptions>* each, int* exit_code) {
  for (const TagCalibration& t : cal.tags) {
    Result<std::optional<uint64_t>> id = ResolveDeviceId("", tags, cal, t.sensor);
    if (!id.ok() || !id.value()) {
      const Error e = id.ok()
                          ? MakeError(fmt::format("sensor {}: no device ID in the tags file or "
                                                  "calibration.json (nothing sent; {} not opened)",
                                                  t.sensor, c.port))
                          : id.error().WithContext(fmt::format("sensor {}", t.sensor));
      apps::PrintErrorText(id.ok() ? e.message : e.ToString() + " (nothing sent)");
      *exit_code = apps::ExitCodeFor(e);
      return false;
    }
    PushCliOptions one = c;
    one.all = false;
    one.sensor = t.sensor;
    one.device_id = blob::FormatDeviceId(*id.value());
    each->push_back(std::move(one));
  }
  return true;
}

// --all: every tag of calibration.json over the one port, in sensor order, each to its own
// device (the central must have that tag selected, docs/calibration-blob.md 1.1; another tag
// on the link is refused before anything is written), each read back; then a table. Tags
// without a device ID stop the run before the port is opened. calibration.json and the tags
// file are read once.
int RunPushAll(const PushCliOptions& c) {
  if (c.sensor != 0 || !c.device_id.empty() || c.any_device || c.seq != 0) {
    apps::PrintErrorText(
        "--all pushes every tag to its own device: drop --sensor, --device-id, --any-device and "
        "--seq (each tag gets its active seq + 1)");
    return kExitUsage;
  }
  std::optional<TagRegistry> tags;
  Calibration cal;
  if (!LoadPushInputs(c, &tags, &cal)) return kExitUsage;
  std::vector<PushCliOptions> each;
  if (int rc = kExitOk; !EveryTagPush(c, tags, cal, &each, &rc)) return rc;
  PushRegistry registry(c.registry);
  int worst = kExitOk;
  std::string table =
      fmt::format("{:>6}  {:<16}  {:<16}  {}\n", "sensor", "name", "device", "result");
  for (const PushCliOptions& one : each) {
    apps::Note(fmt::format("== sensor {}, device {}\n", one.sensor, one.device_id));
    std::string outcome;
    const int rc = PushTag(one, tags, cal, &registry, &outcome);
    if (outcome.empty()) outcome = rc == kExitUsage ? "refused (see above)" : "failed (see above)";
    worst = std::max(worst, rc);
    // One row per tag: the name is the tags file's data (escaped).
    table += fmt::format(
        "{:>6}  {:<16}  {:<16}  {}\n", one.sensor,
        EscapeControlChars(tags ? tags->Name(one.sensor) : TagRegistry::Default().Name(one.sensor)),
        one.device_id, outcome);
  }
  // The table is the result: on stdout.
  apps::PrintText(stdout, table);
  return worst;
}

}  // namespace

int RunPushCommand(const PushCliOptions& o) { return RunPush(o); }

}  // namespace metro::calibrate_app
