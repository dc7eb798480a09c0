#include "registry_hooks.hpp"

#include <fmt/format.h>

#include "commands.hpp"
#include "metro/core/file.hpp"
#include "unix_cli.hpp"

namespace metro::calibrate_app {

std::vector<apps::NamedPath> RegistryFiles(const std::string& flag) {
  const std::string url = Registry::UrlFromFlagOrEnvironment(flag);
  const std::string file = Registry::FileOf(url);
  if (file.empty()) return {};
  return {{flag.empty() ? "METRO_REGISTRY" : "--registry", file}};
}

OpenedRegistry OpenRegistryOption(const RegistryCliOptions& o) {
  OpenedRegistry out;
  const std::string url = Registry::UrlFromFlagOrEnvironment(o.url);
  if (url.empty()) return out;
  Result<std::unique_ptr<Registry>> r = Registry::Open(url);
  if (!r.ok()) {
    apps::PrintError(r.error());
    out.exit_code = kExitUsage;
    return out;
  }
  out.registry = std::move(r).value();
  return out;
}

int RegistryResult(const Status& recorded, const std::string& what) {
  if (!recorded.ok()) {
    apps::PrintErrorText("registry: " + recorded.error().ToString());
    // Recorded after the outputs were written: a failure is a write that failed (exit 1).
    return apps::ExitCodeFor(recorded.error().WithKind(ErrorKind::kIo));
  }
  apps::Note(fmt::format("registry: recorded {}\n", what));
  return kExitOk;
}

Result<std::string> FileCertificateId(const std::string& calibration_path) {
  Result<std::string> sha = Sha256File(calibration_path);
  if (!sha.ok()) return sha.error();
  return sha.value().substr(0, 16);
}

int RecordAppliedCalibration(Registry* registry, const Calibration& calibration,
                             const std::string& calibration_path,
                             const RegistryCliOptions& options) {
  if (registry == nullptr) return kExitOk;
  Result<std::string> id = FileCertificateId(calibration_path);
  if (!id.ok()) return RegistryResult(id.status(), "");
  return RegistryResult(
      registry->RecordCalibration(calibration, id.value(), options.Context()).status(),
      "the calibration applied, certificate " + id.value());
}

int RecordBlobResult(Registry* registry, const Calibration& calibration,
                     const std::string& calibration_path, int sensor,
                     const blob::BlobContents& contents, uint64_t device_id, uint32_t seq,
                     uint32_t crc, const std::string& file, const RegistryCliOptions& options) {
  if (registry == nullptr) return kExitOk;
  Result<std::string> id = FileCertificateId(calibration_path);
  if (!id.ok()) return RegistryResult(id.status(), "");
  RegistryBlob b;
  b.device_id = device_id;
  b.seq = seq;
  b.crc = crc;
  b.file = file;
  if (contents.accel) {
    b.accel_t_valid_min_c = contents.accel->t_valid_min_c;
    b.accel_t_valid_max_c = contents.accel->t_valid_max_c;
  }
  if (contents.gyro) {
    b.gyro_t_valid_min_c = contents.gyro->t_valid_min_c;
    b.gyro_t_valid_max_c = contents.gyro->t_valid_max_c;
  }
  return RegistryResult(
      registry->RecordBlob(calibration, id.value(), sensor, b, options.Context()),
      fmt::format("blob seq {} for device {}", seq, blob::FormatDeviceId(device_id)));
}

int RecordPushResult(Registry* registry, const Calibration& calibration,
                     const std::string& calibration_path, int sensor,
                     const blob::PushSummary& summary, std::optional<uint64_t> expected_device,
                     const std::string& port, const RegistryCliOptions& options) {
  if (registry == nullptr) return kExitOk;
  Result<std::string> id = FileCertificateId(calibration_path);
  if (!id.ok()) return RegistryResult(id.status(), "");
  std::optional<uint64_t> device = expected_device;
  if (summary.tag_answered) device = summary.tag.device_id;
  if (!device) {
    apps::PrintText(stderr,
                    "warning: registry: the push was not recorded: no tag answered and no "
                    "--device-id was given\n");
    return kExitOk;
  }
  RegistryPush p;
  p.device_id = *device;
  p.port = port;
  p.ok = summary.ok;
  p.result = summary.message;
  p.readback = blob::PushReadBackText(summary);
  const bool lied = summary.contradiction != blob::TagContradiction::kNone;
  return RegistryResult(registry->RecordPush(calibration, id.value(), sensor, p, options.Context()),
                        fmt::format("push to device {} ({})", blob::FormatDeviceId(*device),
                                    summary.ok ? "OK"
                                    : lied     ? "MISMATCH: the tag contradicted itself"
                                               : "failed"));
}

}  // namespace metro::calibrate_app
