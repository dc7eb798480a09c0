// calibrate blob calibration.json --sensor N [--device-id ID] [--tags FILE] [--seq N] -o tag.bin
// calibrate blob calibration.json --all --tags FILE -o DIR   (every tag: DIR/tag<N>.bin, .hex)
//   [--hex tag.hex] [--slot-address ADDR] [--dlpf-cfg N] [--t-valid-min-c C] [--t-valid-max-c C]
//   [--profile mpu6050|generic] [--accel-fs-g G] [--gyro-fs-dps D]
#include "blob_command.hpp"

#include <fmt/format.h>
#include <sys/stat.h>

#include <memory>
#include <optional>
#include <utility>
#include <vector>

#include "commands.hpp"
#include "metro/blob/from_calibration.hpp"
#include "metro/blob/intel_hex.hpp"
#include "metro/calibration/calibration_io.hpp"
#include "metro/core/file.hpp"
#include "registry_hooks.hpp"
#include "tags_cli.hpp"
#include "unix_cli.hpp"

namespace metro::calibrate_app {
namespace {

int RunBlobAll(const BlobOptions& b);

// The chip the blob is bound to (docs/calibration-blob.md 1.1): --device-id, else the tags
// file's or calibration.json's device_id.
Result<uint64_t> BlobDeviceId(const BlobOptions& b, const std::optional<TagRegistry>& tags,
                              const Calibration& cal) {
  Result<std::optional<uint64_t>> resolved = ResolveDeviceId(b.device_id, tags, cal, b.sensor);
  if (!resolved.ok()) return resolved.error();
  if (!resolved.value()) {
    return MakeError(fmt::format(
        "no device ID for sensor {}: give --device-id, or --tags FILE with its device_id (the "
        "blob is bound to one chip, docs/calibration-blob.md 1.1)",
        b.sensor));
  }
  return *resolved.value();
}

// The blob's options from the flags and the tags file's profile.
blob::BlobFromCalibrationOptions BlobOptionsFor(const BlobOptions& b,
                                                const std::optional<TagRegistry>& tags,
                                                uint64_t device_id) {
  blob::BlobFromCalibrationOptions o;
  o.sensor = b.sensor;
  o.device_id = device_id;
  o.t_valid_min_c = b.t_valid_min_c;
  o.t_valid_max_c = b.t_valid_max_c;
  o.seq = b.seq;
  o.dlpf_cfg = static_cast<uint8_t>(b.dlpf_cfg);
  o.profile = ResolveProfile(b.profile, tags, b.sensor);
  o.accel_fs_g = b.accel_fs_g;
  o.gyro_fs_dps = b.gyro_fs_dps;
  o.accept_rejected_model = b.accept_rejected_model;
  return o;
}

// What was written: the blob (size, tag, seq, CRC), the temperature range the tag clamps to,
// and the HEX's layout with the command that programs it.
void NoteBlobWritten(const BlobOptions& b, const blob::BlobContents& contents, size_t size,
                     uint64_t device_id, uint32_t crc, uint32_t slot_a) {
  apps::Note(fmt::format("wrote {}: {} bytes, sensor {}, device {}, seq {}, CRC-32 0x{:08X}\n",
                         apps::IsStdio(b.output) ? "stdout" : b.output, size, b.sensor,
                         blob::FormatDeviceId(device_id), b.seq, crc));
  for (const auto& [sensor, name] :
       {std::pair{&contents.accel, "accel"}, std::pair{&contents.gyro, "gyro"}}) {
    if (*sensor) {
      apps::Note(fmt::format("{}: the tag clamps the temperature to {:.2f} .. {:.2f} degC\n", name,
                             (*sensor)->t_valid_min_c, (*sensor)->t_valid_max_c));
    }
  }
  if (b.hex.empty()) return;
  apps::Note(fmt::format("wrote {}: blob at 0x{:05X} (slot A), tombstone at 0x{:05X} (slot B)\n",
                         apps::IsStdio(b.hex) ? "stdout" : b.hex, slot_a,
                         slot_a + blob::kPageSize));
  if (!apps::IsStdio(b.hex)) {
    apps::Note(fmt::format("program with: {}\n", blob::NrfjprogCommand(b.hex)));
  }
}

// The blob's contents with the firmware's checks, and its bytes; its warnings printed unless
// `quiet_check` (a check before the blob is built again to be written).
Result<std::pair<blob::BlobContents, std::vector<uint8_t>>> BuildBlob(
    const Calibration& cal, const blob::BlobFromCalibrationOptions& o, bool quiet_check = false) {
  std::vector<std::string> warnings;
  Result<blob::BlobContents> contents = blob::BlobContentsFromCalibration(cal, o, &warnings);
  if (!contents.ok()) return contents.error();
  if (!quiet_check) {
    for (const std::string& w : warnings) apps::PrintWarning(w);
  }
  Result<std::vector<uint8_t>> bytes = blob::WriteBlob(contents.value());
  if (!bytes.ok()) return bytes.error();
  return std::make_pair(std::move(contents).value(), std::move(bytes).value());
}

// One tag's blob (and HEX) from the loaded inputs: built with the firmware's checks, written
// (the two replaced together or not at all: a .bin beside the HEX of an older blob would
// program another calibration than the one inspected), noted and recorded in the registry.
int WriteTagBlob(const BlobOptions& b, const std::optional<TagRegistry>& tags,
                 const Calibration& cal, uint64_t device_id, uint32_t slot_a, Registry* registry) {
  auto built = BuildBlob(cal, BlobOptionsFor(b, tags, device_id));
  if (!built.ok()) {
    apps::PrintErrorText(CalibrationErrorText(b.calibration, built.error()));
    return apps::ExitCodeFor(built.error());
  }
  const auto& [contents, v] = built.value();
  std::string hex;
  if (!b.hex.empty()) {
    Result<std::string> image =
        blob::WriteIntelHex(blob::FactoryImage(v, slot_a, slot_a + blob::kPageSize));
    METRO_CHECK(image.ok());  // two sorted, disjoint pages
    hex = std::move(image).value();
  }
  if (Status w = apps::WriteOutputs(
          {{b.output, std::string_view(reinterpret_cast<const char*>(v.data()), v.size())},
           {b.hex, hex}});
      !w.ok()) {
    apps::PrintErrorText(w.error().ToString());
    return apps::ExitCodeFor(w.error());
  }
  const uint32_t crc = blob::Crc32(v.data(), v.size() - 4);
  NoteBlobWritten(b, contents, v.size(), device_id, crc, slot_a);
  return RecordBlobResult(registry, cal, b.calibration, b.sensor, contents, device_id, b.seq, crc,
                          b.output, b.registry);
}

// calibration.json, loaded (a failure printed, its exit code in *exit_code: nullopt).
std::optional<Calibration> LoadCalibrationOption(const BlobOptions& b, int* exit_code) {
  Result<Calibration> cal = LoadCalibration(b.calibration);
  if (cal.ok()) return std::move(cal).value();
  apps::PrintErrorText(cal.error().ToString());
  *exit_code = apps::ExitCodeFor(cal.error());
  return std::nullopt;
}

// --slot-address, checked (a failure printed, its exit code in *exit_code: nullopt).
std::optional<uint32_t> SlotAddressOption(const BlobOptions& b, int* exit_code) {
  Result<uint32_t> slot_a = ParseSlotAddress(b.slot_address);
  if (slot_a.ok()) return slot_a.value();
  apps::PrintErrorText(slot_a.error().message);
  *exit_code = apps::ExitCodeFor(slot_a.error());
  return std::nullopt;
}

int RunBlob(const BlobOptions& b) {
  if (b.all) return RunBlobAll(b);
  if (b.sensor < 1) {
    apps::PrintErrorText("--sensor N names the tag in calibration.json (or --all for every tag)");
    return kExitUsage;
  }
  Result<std::optional<TagRegistry>> tags = LoadTagsOption(b.tags);
  if (!tags.ok()) return apps::PrintErrorExit(tags.error());
  int rc = kExitOk;
  const std::optional<uint32_t> slot_a = SlotAddressOption(b, &rc);
  if (!slot_a) return rc;
  for (Status s : {apps::CheckOutputs({{"-o", b.output}, {"--hex", b.hex}},
                                      {{"CALIBRATION", b.calibration}, {"--tags", b.tags}},
                                      RegistryFiles(b.registry.url)),
                   apps::CheckBinaryStdout(b.output)}) {
    if (!s.ok()) return apps::PrintErrorExit(s.error());
  }
  const std::optional<Calibration> cal = LoadCalibrationOption(b, &rc);
  if (!cal) return rc;
  const Result<uint64_t> id = BlobDeviceId(b, tags.value(), *cal);
  if (!id.ok()) return apps::PrintErrorExit(id.error());
  OpenedRegistry registry = OpenRegistryOption(b.registry);
  if (registry.exit_code != 0) return registry.exit_code;
  return WriteTagBlob(b, tags.value(), *cal, id.value(), *slot_a, registry.registry.get());
}

// --all: the one-tag options of every tag of calibration.json, each with its device ID (tags
// file or calibration.json) and representable in a blob, and every file of every tag checked
// (a DIR/tag<N>.bin that is a symlink to the tags file or to calibration.json is refused),
// before anything is written.
Result<std::vector<BlobOptions>> EveryTagBlob(const BlobOptions& b,
                                              const std::optional<TagRegistry>& tags,
                                              const Calibration& cal) {
  std::vector<BlobOptions> each;
  std::vector<apps::NamedPath> outputs;
  for (const TagCalibration& t : cal.tags) {
    BlobOptions one = b;
    one.all = false;
    one.sensor = t.sensor;
    const Result<std::optional<uint64_t>> id = ResolveDeviceId("", tags, cal, t.sensor);
    if (!id.ok()) return id.error().WithContext(fmt::format("sensor {}", t.sensor));
    if (!id.value()) {
      return MakeError(
          fmt::format("sensor {}: no device ID in the tags file or calibration.json", t.sensor));
    }
    if (auto built = BuildBlob(cal, BlobOptionsFor(one, tags, *id.value()), /*quiet_check=*/true);
        !built.ok()) {
      Error e = built.error();
      e.message = CalibrationErrorText(b.calibration, built.error());
      e.file.clear();
      return e;
    }
    one.device_id = blob::FormatDeviceId(*id.value());
    one.output = fmt::format("{}/tag{}.bin", b.output, t.sensor);
    one.hex = fmt::format("{}/tag{}.hex", b.output, t.sensor);
    outputs.push_back({fmt::format("-o (sensor {})", one.sensor), one.output});
    outputs.push_back({fmt::format("-o (sensor {} HEX)", one.sensor), one.hex});
    each.push_back(std::move(one));
  }
  if (Status s = apps::CheckOutputs(outputs, {{"CALIBRATION", b.calibration}, {"--tags", b.tags}},
                                    RegistryFiles(b.registry.url));
      !s.ok()) {
    return s.error();
  }
  return each;
}

// --all: every tag of calibration.json, each with its device ID (tags file or calibration.json),
// checked together before any file is written, then one blob and HEX per tag in the directory.
// calibration.json and the tags file are read once.
int RunBlobAll(const BlobOptions& b) {
  if (b.sensor != 0 || !b.device_id.empty() || !b.hex.empty()) {
    apps::PrintErrorText(
        "--all writes every tag: drop --sensor, --device-id and --hex (DIR/tag<N>.hex is "
        "written beside each DIR/tag<N>.bin)");
    return kExitUsage;
  }
  Result<std::optional<TagRegistry>> tags = LoadTagsOption(b.tags);
  if (!tags.ok()) return apps::PrintErrorExit(tags.error());
  struct stat st {};
  if (apps::IsStdio(b.output) || ::stat(b.output.c_str(), &st) != 0 || !S_ISDIR(st.st_mode)) {
    apps::PrintErrorText(fmt::format(
        "-o {}: --all writes into a directory; expected an existing directory", b.output));
    return kExitUsage;
  }
  int rc = kExitOk;
  const std::optional<Calibration> cal = LoadCalibrationOption(b, &rc);
  if (!cal) return rc;
  Result<std::vector<BlobOptions>> each = EveryTagBlob(b, tags.value(), *cal);
  if (!each.ok()) {
    apps::PrintErrorText(each.error().ToString() + " (nothing written)");
    return apps::ExitCodeFor(each.error());
  }
  const std::optional<uint32_t> slot_a = SlotAddressOption(b, &rc);
  if (!slot_a) return rc;
  OpenedRegistry registry = OpenRegistryOption(b.registry);
  if (registry.exit_code != 0) return registry.exit_code;
  std::string table =
      fmt::format("{:>6}  {:<16}  {:<16}  {}\n", "sensor", "name", "device", "blob");
  for (const BlobOptions& one : each.value()) {
    const uint64_t id = blob::ParseDeviceId(one.device_id).value();
    rc = WriteTagBlob(one, tags.value(), *cal, id, *slot_a, registry.registry.get());
    if (rc != kExitOk) return rc;
    table += fmt::format("{:>6}  {:<16}  {:<16}  {}\n", one.sensor,
                         EscapeControlChars(tags.value() ? tags.value()->Name(one.sensor)
                                                         : TagRegistry::Default().Name(one.sensor)),
                         one.device_id, EscapeControlChars(one.output));
  }
  apps::Note(table);
  return kExitOk;
}

}  // namespace

int RunBlobCommand(const BlobOptions& o) { return RunBlob(o); }

}  // namespace metro::calibrate_app
