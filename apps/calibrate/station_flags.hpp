// The flags of `calibrate station`.
// Included by main.cpp only: the program's one translation unit with CLI11 (issue #39).
#pragma once

#include <CLI/CLI.hpp>
#include <memory>
#include <string>
#include <vector>

#include "blob_flags.hpp"
#include "cli_flags.hpp"
#include "common_flags.hpp"
#include "fit_flags.hpp"
#include "push_flags.hpp"
#include "station_command.hpp"

namespace metro::calibrate_app {

inline void AddStationCommand(CLI::App& app, int* exit_code) {
  auto o = std::make_shared<StationCliOptions>();
  CLI::App* sub = app.add_subcommand(
      "station",
      "guided live calibration: read raw counts from a port or a growing file, guide the "
      "operator pose by pose until every constant's u meets its target, then fit, certificate, "
      "blob, push and registry (docs/station.md)");
  sub->add_option("--port", o->port, "serial port, pseudo-terminal or growing file of raw lines")
      ->required();
  sub->add_option("--format", o->format,
                  "the stream's line format: raw (ax,ay,az,gx,gy,gz[,t_ms])");
  sub->add_option("--rate-hz", o->station.rate_hz, "the stream's sample rate [Hz]")->required();
  AddTagsOption(sub, &o->tags);
  sub->get_option("--tags")->required();
  sub->add_option("--sensor", o->station.sensor, "the tag's number in the tags file")->required();
  sub->add_option("--protocol", o->protocol, "six-face (default), ferraris or sphere")
      ->check(CLI::IsMember({"six-face", "ferraris", "sphere"}));
  sub->add_option("--model", o->model, "both sensors' model: full (default), scale or bias")
      ->check(CLI::IsMember({"full", "scale", "bias"}));
  sub->add_option("--target-u-accel-mg", o->station.target_u_accel_mg,
                  "target u (k = 1) of every accelerometer constant, as its error at 1 g [mg] "
                  "(default 0.5)");
  sub->add_option("--target-u-gyro-dps", o->station.target_u_gyro_dps,
                  "target u (k = 1) of every gyroscope constant, as its error at "
                  "--gyro-reference-dps [deg/s] (default 0.05)");
  sub->add_option(
      "--gyro-reference-dps", o->station.gyro_reference_dps,
      "the rate at which the gyroscope's scale and cross-axis u are stated (default 100)");
  sub->add_option("--accel-fs-g", o->station.accel_fs_g,
                  "accelerometer full scale [g] (default 2)");
  sub->add_option("--gyro-fs-dps", o->station.gyro_fs_dps,
                  "gyroscope full scale [deg/s] (default 250)");
  sub->add_option("--min-dwell-s", o->station.min_dwell_s, "shortest hold accepted (default 1.5)");
  sub->add_option("-o,--output-dir", o->out_dir,
                  "directory of the record, calibration.json, certificate.html, tag.bin, tag.hex "
                  "(default .)")
      ->check(CLI::ExistingDirectory);
  sub->add_flag("--push", o->push, "push the blob to the tag and read it back");
  sub->add_option("--push-port", o->push_port, "the central's serial port (default: --port)");
  sub->add_flag("--json-events", o->json_events, "one JSON object per event on stdout");
  sub->add_flag("--no-view", o->no_view, "one line per event even on a terminal");
  sub->add_option("--baud", o->reader.baud, "a serial port's baud rate (default 115200)");
  sub->add_option("--idle-timeout-s", o->reader.idle_timeout_s,
                  "no data for this long ends the stream (default 10)");
  sub->add_option("--reconnect-s", o->reader.reconnect_s,
                  "how long a lost port is waited for (default 60)");
  AddRegistryOptions(sub, &o->registry);
  // fit, blob and push after the stop: their own command lines, parsed as the program does.
  o->run_calibrate = [](const std::vector<std::string>& args) {
    CLI::App calibrate{"calibrate"};
    int code = kExitOk;
    AddFitCommand(calibrate, &code);
    AddBlobCommand(calibrate, &code);
    AddPushCommand(calibrate, &code);
    calibrate.require_subcommand(1);
    std::vector<std::string> reversed(args.rbegin(), args.rend());
    try {
      calibrate.parse(reversed);
    } catch (const CLI::ParseError& e) {
      return calibrate.exit(e) == 0 ? kExitOk : kExitUsage;
    }
    return code;
  };
  sub->callback([o, exit_code] { *exit_code = RunStation(*o); });
}

}  // namespace metro::calibrate_app
