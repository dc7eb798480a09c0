// calibrate blob CALIBRATION.json --sensor N -o tag.bin [--hex tag.hex] [--all]: the blob the
// tag's firmware loads (docs/calibration-blob.md).
// Its flags are bound in main.cpp, the program's one translation unit with CLI11.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "registry_hooks.hpp"

namespace metro::calibrate_app {

struct BlobOptions {
  std::string calibration;
  int sensor = 0;
  std::string device_id;
  uint32_t seq = 1;
  std::string output;
  std::string hex;
  std::string slot_address = "0x3B000";
  int dlpf_cfg = 3;
  std::optional<double> t_valid_min_c;
  std::optional<double> t_valid_max_c;
  std::string profile;  // "" = the tags file's, else mpu6050
  std::string tags;     // --tags FILE
  bool all = false;     // --all: every tag of calibration.json into the directory -o
  std::optional<double> accel_fs_g;
  std::optional<double> gyro_fs_dps;
  bool accept_rejected_model = false;  // --accept-rejected-model (issue #36)
  RegistryCliOptions registry;         // --registry, --station, --operator (docs/registry.md)
};

int RunBlobCommand(const BlobOptions& o);

}  // namespace metro::calibrate_app
