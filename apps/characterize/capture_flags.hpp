// The flags of `characterize capture`.
// Included by main.cpp only: the program's one translation unit with CLI11 (issue #39).
#pragma once

#include <CLI/CLI.hpp>
#include <memory>

#include "capture_command.hpp"
#include "cli_flags.hpp"

namespace metro::apps {

inline void AddCaptureCommand(CLI::App& app, int* exit_code) {
  auto o = std::make_shared<CaptureCliOptions>();
  CLI::App* sub = app.add_subcommand(
      "capture", "record the central receiver's serial stream, with a live per-tag view");
  sub->add_option("--port", o->port, "the receiver's serial port, e.g. /dev/ttyACM0")->required();
  sub->add_option("--baud", o->baud, "baud rate (8N1, raw)")->capture_default_str();
  sub->add_option("--duration-s", o->duration_s, "stop after this many seconds (0: at Ctrl-C)")
      ->check(CLI::NonNegativeNumber);
  sub->add_option("-o,--output", o->output,
                  "the capture file (never replaced without --force); with --analyze: the "
                  "JSON report");
  sub->add_option("--capture", o->capture, "the capture file when -o names the report");
  sub->add_flag("--force", o->force, "replace an existing capture file");
  CLI::Option* on = sub->add_flag(
      "--reconnect", o->reconnect,
      "reopen the port when it returns after an unplug (default without --duration-s)");
  sub->add_flag("--no-reconnect", o->no_reconnect,
                "finish the capture when the port disappears (default with --duration-s)")
      ->excludes(on);
  sub->add_option("--frame-period-s", o->frame_period_s,
                  "the receiver's frame period for the live statistics and --analyze")
      ->capture_default_str();
  sub->add_flag("--analyze", o->analyze,
                "then the full Type A report of the capture (--settle auto)");
  sub->add_option("--tags,--tag-registry", o->tags,
                  "tags file naming the tags (docs/formats.md \"Tags file\"): below the live "
                  "view and the final table, and in the --analyze report")
      ->check(CLI::ExistingFile);
  sub->callback([o, exit_code] { *exit_code = RunCaptureCommand(*o); });
}

}  // namespace metro::apps
