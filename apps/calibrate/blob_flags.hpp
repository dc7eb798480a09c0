// The flags of `calibrate blob`.
// Included by main.cpp only: the program's one translation unit with CLI11 (issue #39).
#pragma once

#include <CLI/CLI.hpp>
#include <memory>

#include "blob_command.hpp"
#include "cli_flags.hpp"
#include "common_flags.hpp"

namespace metro::calibrate_app {

inline void AddBlobCommand(CLI::App& app, int* exit_code) {
  auto o = std::make_shared<BlobOptions>();
  CLI::App* sub = app.add_subcommand(
      "blob",
      "write a tag's calibration blob (docs/calibration-blob.md) and, with --hex, the Intel "
      "HEX for nrfjprog");
  sub->add_option("calibration", o->calibration, "calibration.json")
      ->required()
      ->check(CLI::ExistingFile);
  sub->add_option("--sensor", o->sensor, "the tag in calibration.json (or --all)");
  sub->add_option("--device-id", o->device_id,
                  "the tag's FICR DEVICEID: 16 hex digits DEVICEID[1] then DEVICEID[0], or the "
                  "two words nrfjprog --memrd 0x10000060 --n 8 prints (DEVICEID[0] DEVICEID[1]), "
                  "with or without 0x (default: the tags file's, else calibration.json's)");
  AddTagsOption(sub, &o->tags);
  sub->add_flag("--all", o->all,
                "every tag of calibration.json: -o names a directory, DIR/tag<N>.bin and .hex, "
                "device IDs from --tags or calibration.json");
  sub->add_option("--seq", o->seq, "blob sequence number, 1..4294967294 (default 1)")
      ->check(CLI::Range(1u, 0xFFFFFFFEu));
  sub->add_option("-o,--output", o->output,
                  "tag.bin to write (- for stdout, not a terminal); with --all a directory")
      ->required();
  sub->add_option("--hex", o->hex,
                  "also write this Intel HEX: blob at slot A, tombstone at B (- for stdout)");
  sub->add_option("--slot-address", o->slot_address,
                  "slot A address in the HEX (default 0x3B000); slot B is the next page");
  sub->add_option("--dlpf-cfg", o->dlpf_cfg, "the tag firmware's MPU6050 DLPF_CFG (default 3)")
      ->check(CLI::Range(0, 6));
  sub->add_option("--t-valid-min-c", o->t_valid_min_c,
                  "lower end of the temperature validity range the tag clamps to (default: the "
                  "fitted span - 5 degC; lower is extrapolation, with a warning)");
  sub->add_option("--t-valid-max-c", o->t_valid_max_c,
                  "upper end of the temperature validity range (default: the fitted span + 5 "
                  "degC)");
  AddSensorProfileOptions(sub, &o->profile, &o->accel_fs_g, &o->gyro_fs_dps);
  sub->add_flag("--accept-rejected-model", o->accept_rejected_model,
                "write constants calibration.json marks model_rejected (a model the data reject "
                "or an exact fit; docs/calibration-model.md) anyway");
  AddRegistryOptions(sub, &o->registry);
  sub->callback([o, exit_code] { *exit_code = RunBlobCommand(*o); });
}

}  // namespace metro::calibrate_app
