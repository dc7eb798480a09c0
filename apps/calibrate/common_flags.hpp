// The flags several calibrate commands share: --tags, --profile and the full scales, --spec,
// --registry, --station, --operator.
// Included by main.cpp only: the program's one translation unit with CLI11 (issue #39).
#pragma once

#include <CLI/CLI.hpp>
#include <optional>
#include <string>

#include "cli_flags.hpp"
#include "conformity_cli.hpp"
#include "registry_hooks.hpp"
#include "tags_cli.hpp"

namespace metro::calibrate_app {

inline void AddTagsOption(CLI::App* sub, std::string* tags) {
  sub->add_option("--tags,--tag-registry", *tags,
                  "tags file: per sensor its name, device_id (either word order) and profile "
                  "(docs/formats.md \"Tags file\")")
      ->check(CLI::ExistingFile);
}

// --profile mpu6050|generic, --accel-fs-g G, --gyro-fs-dps D of `blob` and `push`: the nominal
// sensitivity a blob section declares (metro::blob::SensorProfile, docs/calibration-blob.md 10).
inline void AddSensorProfileOptions(CLI::App* sub, std::string* profile,
                                    std::optional<double>* accel_fs_g,
                                    std::optional<double>* gyro_fs_dps) {
  sub->add_option("--profile", *profile,
                  "the IMU: mpu6050 (its datasheet sensitivity at the declared or matching "
                  "full-scale setting) or generic (another IMU: 32768 / the declared full scale, "
                  "else the calibration's own); default: the tags file's, else mpu6050")
      ->check(CLI::IsMember({"mpu6050", "generic"}));
  sub->add_option("--accel-fs-g", *accel_fs_g,
                  "declared accelerometer full scale [g] (mpu6050: 2, 4, 8 or 16; default: the "
                  "setting M matches)");
  sub->add_option("--gyro-fs-dps", *gyro_fs_dps,
                  "declared gyroscope full scale [deg/s] (mpu6050: 250, 500, 1000 or 2000; "
                  "default: the setting M matches)");
}

inline void AddRegistryOptions(CLI::App* sub, RegistryCliOptions* o) {
  sub->add_option("--registry", o->url,
                  "record this in the calibration registry: a SQLite file or "
                  "postgresql://... (default: $METRO_REGISTRY; docs/registry.md)");
  sub->add_option("--station", o->station, "station name recorded with a calibration");
  sub->add_option("--operator", o->operator_name, "operator recorded with a calibration");
}

inline void AddSpecOptions(CLI::App* sub, SpecCliOptions* o) {
  sub->add_option("--spec", o->spec,
                  "SPEC.json: tolerance limits per constant and a decision rule; writes a "
                  "statement of conformity (docs/conformity.md)")
      ->check(CLI::ExistingFile);
  sub->add_flag("--fail-on-nonconformity", o->fail_on_nonconformity,
                "exit 1 when any constant's decision is fail (with --spec)");
}

}  // namespace metro::calibrate_app
