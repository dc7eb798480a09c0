// The flags of `calibrate inspect`.
// Included by main.cpp only: the program's one translation unit with CLI11 (issue #39).
#pragma once

#include <CLI/CLI.hpp>
#include <memory>

#include "cli_flags.hpp"
#include "common_flags.hpp"
#include "inspect_command.hpp"

namespace metro::calibrate_app {

inline void AddInspectCommand(CLI::App& app, int* exit_code) {
  auto o = std::make_shared<InspectCliOptions>();
  CLI::App* sub = app.add_subcommand(
      "inspect",
      "decode and validate a calibration blob (.bin) or programmer image (.hex) with the tag "
      "firmware's rules; exit 0 valid, 1 no valid calibration, 2 unreadable");
  sub->add_option("file", o->input, "tag.bin or tag.hex")->required()->check(CLI::ExistingFile);
  sub->add_option("--device-id", o->device_id,
                  "check against this tag (16 hex digits DEVICEID[1] DEVICEID[0], or nrfjprog "
                  "--memrd's words DEVICEID[0] DEVICEID[1]); default: each blob's own id");
  AddTagsOption(sub, &o->tags);
  sub->add_option("--sensor", o->sensor,
                  "with --tags: check the blob against this tag's device_id");
  sub->add_option("--slot-address", o->slot_address,
                  "slot A address in a .hex (default 0x3B000); slot B is the next page");
  sub->add_flag("--json", o->json, "print JSON instead of text");
  sub->callback([o, exit_code] { *exit_code = RunInspect(*o); });
}

}  // namespace metro::calibrate_app
