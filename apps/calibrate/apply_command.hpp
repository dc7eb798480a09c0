// calibrate apply CALIBRATION.json SESSION -o OUT.csv: a calibration applied to a session.
// Its flags are bound in main.cpp, the program's one translation unit with CLI11.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "registry_hooks.hpp"

namespace metro::calibrate_app {

struct ApplyOptions {
  std::string calibration;
  std::vector<std::string> inputs;  // SESSION, or ACC GYRO with --imutk.
  std::string output;
  bool imutk = false;
  std::optional<double> t_valid_min_c;  // As given to `calibrate blob`.
  std::optional<double> t_valid_max_c;
  RegistryCliOptions registry;  // --registry: records the calibration applied (docs/registry.md)
  std::string tags;  // --tags FILE: checks calibration.json's device IDs, names the tags.
};

int RunApply(const ApplyOptions& o);

}  // namespace metro::calibrate_app
