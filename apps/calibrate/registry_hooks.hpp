// `--registry URL` (or METRO_REGISTRY), `--station`, `--operator` on calibrate fit, blob, push
// and apply: what the command made is recorded in the calibration registry (docs/registry.md).
// The hooks the commands call; the work is metro/registry/registry.hpp.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "metro/blob/from_calibration.hpp"
#include "metro/blob/push_client.hpp"
#include "metro/registry/registry.hpp"
#include "unix_cli.hpp"

namespace metro::calibrate_app {

struct RegistryCliOptions {
  std::string url;  // --registry; empty: METRO_REGISTRY; empty too: no registry
  std::string station;
  std::string operator_name;

  RecordContext Context() const { return {station, operator_name, ""}; }
};

// The registry as apps::CheckOutputs sees it (an `updated` file: read and written in place,
// so no output or input of the command may be it): the SQLite file of --registry FLAG, else
// of METRO_REGISTRY, named by what gave it; none for a PostgreSQL URL or without a registry.
std::vector<apps::NamedPath> RegistryFiles(const std::string& flag);

// Before the command's work: the registry (nullptr without one). A URL that cannot be opened
// or a schema newer than the program: printed, exit_code 2.
struct OpenedRegistry {
  std::unique_ptr<Registry> registry;
  int exit_code = 0;
};
OpenedRegistry OpenRegistryOption(const RegistryCliOptions& options);

// After the work: prints a failed record ("error: registry: ...") and returns 1; else notes
// what was recorded and returns 0.
int RegistryResult(const Status& recorded, const std::string& what);

// The certificate id of a calibration.json read back: the first 16 hex digits of the SHA-256
// of its bytes (what `fit` recorded it under and printed on its certificate).
Result<std::string> FileCertificateId(const std::string& calibration_path);

// `calibrate apply`: the calibration applied.
int RecordAppliedCalibration(Registry* registry, const Calibration& calibration,
                             const std::string& calibration_path,
                             const RegistryCliOptions& options);

// `calibrate blob`: the blob just written (nothing without a registry).
int RecordBlobResult(Registry* registry, const Calibration& calibration,
                     const std::string& calibration_path, int sensor,
                     const blob::BlobContents& contents, uint64_t device_id, uint32_t seq,
                     uint32_t crc, const std::string& file, const RegistryCliOptions& options);

// `calibrate push`: the push's outcome, for the device that answered (else --device-id; a
// push to an unknown device is not recorded, with a warning).
int RecordPushResult(Registry* registry, const Calibration& calibration,
                     const std::string& calibration_path, int sensor,
                     const blob::PushSummary& summary, std::optional<uint64_t> expected_device,
                     const std::string& port, const RegistryCliOptions& options);

}  // namespace metro::calibrate_app
