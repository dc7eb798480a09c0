// calibrate push CALIBRATION.json --port DEV --sensor N [--all]: the blob pushed to the tag over
// the receiver's serial link and read back (docs/calibration-blob.md section 7).
// Its flags are bound in main.cpp, the program's one translation unit with CLI11.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "registry_hooks.hpp"

namespace metro::calibrate_app {

struct PushCliOptions {
  std::string port;
  std::string calibration;
  int sensor = 0;
  std::string device_id;
  uint32_t seq = 0;
  int dlpf_cfg = 3;
  std::optional<double> t_valid_min_c;
  std::optional<double> t_valid_max_c;
  int timeout_ms = 1000;
  int retries = 5;
  std::string profile;  // "" = the tags file's, else mpu6050
  std::optional<double> accel_fs_g;
  std::optional<double> gyro_fs_dps;
  bool accept_rejected_model = false;  // --accept-rejected-model (issue #36)
  std::string tags;                    // --tags FILE
  bool any_device = false;             // --any-device: write to whichever tag answers
  bool all = false;                    // --all: every tag of calibration.json, one after another
  RegistryCliOptions registry;         // --registry, --station, --operator (docs/registry.md)
};

int RunPushCommand(const PushCliOptions& o);

}  // namespace metro::calibrate_app
