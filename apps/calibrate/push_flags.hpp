// The flags of `calibrate push`.
// Included by main.cpp only: the program's one translation unit with CLI11 (issue #39).
#pragma once

#include <CLI/CLI.hpp>
#include <memory>

#include "cli_flags.hpp"
#include "common_flags.hpp"
#include "push_command.hpp"

namespace metro::calibrate_app {

inline void AddPushCommand(CLI::App& app, int* exit_code) {
  auto o = std::make_shared<PushCliOptions>();
  CLI::App* sub = app.add_subcommand(
      "push",
      "send a tag's calibration over the central's serial link (230400 8N1) with the push "
      "protocol, then read it back");
  sub->add_option("--port", o->port, "serial device of the BLE central, e.g. /dev/ttyACM0")
      ->required();
  sub->add_option("calibration", o->calibration, "calibration.json")
      ->required()
      ->check(CLI::ExistingFile);
  sub->add_option("--sensor", o->sensor, "the tag in calibration.json (or --all)");
  sub->add_option("--device-id", o->device_id,
                  "the tag's FICR DEVICEID (16 hex digits DEVICEID[1] DEVICEID[0], or nrfjprog "
                  "--memrd's two words DEVICEID[0] DEVICEID[1]); another tag is refused. "
                  "Default: the tags file's, else calibration.json's");
  AddTagsOption(sub, &o->tags);
  sub->add_flag("--all", o->all,
                "every tag of calibration.json, each to its device (--tags or calibration.json), "
                "read back, then a table (sensor, name, device, result)");
  sub->add_flag("--any-device", o->any_device,
                "no device ID is known: write to whichever tag answers (else refused)");
  sub->add_option("--seq", o->seq, "blob seq (default: the tag's active seq + 1)")
      ->check(CLI::Range(1u, 0xFFFFFFFEu));
  sub->add_option("--dlpf-cfg", o->dlpf_cfg, "the tag firmware's MPU6050 DLPF_CFG (default 3)")
      ->check(CLI::Range(0, 6));
  sub->add_option("--t-valid-min-c", o->t_valid_min_c,
                  "lower end of the temperature validity range the tag clamps to (default: the "
                  "fitted span - 5 degC; lower is extrapolation, with a warning)");
  sub->add_option("--t-valid-max-c", o->t_valid_max_c,
                  "upper end of the temperature validity range (default: the fitted span + 5 "
                  "degC)");
  sub->add_option("--timeout-ms", o->timeout_ms, "wait for each answer (default 1000)")
      ->check(CLI::Range(1, 60000));
  sub->add_option("--retries", o->retries, "resends of one request (default 5)")
      ->check(CLI::Range(0, 100));
  AddSensorProfileOptions(sub, &o->profile, &o->accel_fs_g, &o->gyro_fs_dps);
  sub->add_flag("--accept-rejected-model", o->accept_rejected_model,
                "send constants calibration.json marks model_rejected (a model the data reject "
                "or an exact fit; docs/calibration-model.md) anyway");
  AddRegistryOptions(sub, &o->registry);
  sub->callback([o, exit_code] { *exit_code = RunPushCommand(*o); });
}

}  // namespace metro::calibrate_app
