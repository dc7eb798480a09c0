// The flags of `calibrate registry history|drift|due|export`.
// Included by main.cpp only: the program's one translation unit with CLI11 (issue #39).
#pragma once

#include <CLI/CLI.hpp>
#include <memory>

#include "cli_flags.hpp"
#include "registry_command.hpp"

namespace metro::calibrate_app {

inline void AddRegistryCommand(CLI::App& app, int* exit_code) {
  auto o = std::make_shared<RegistryQueryOptions>();
  CLI::App* reg = app.add_subcommand(
      "registry", "query the calibration registry: history, drift, due, export (docs/registry.md)");
  reg->require_subcommand(1);
  auto url = [&](CLI::App* sub) {
    sub->add_option("--registry", o->url,
                    "the registry: a SQLite file or postgresql://... (default: $METRO_REGISTRY)");
  };
  CLI::App* history = reg->add_subcommand("history", "every calibration of a device, oldest first");
  url(history);
  history->add_option("--device-id", o->device_id, "the tag's device ID (16 hex digits)")
      ->required();
  history->add_flag("--json", o->json, "JSON: {\"device_id\", \"calibrations\": [...]}");
  history->callback([o, exit_code] { *exit_code = RunRegistryHistory(*o); });

  CLI::App* drift = reg->add_subcommand(
      "drift", "change of each constant between a device's last two calibrations, with E_n");
  url(drift);
  drift->add_option("--device-id", o->device_id, "the tag's device ID (16 hex digits)")->required();
  drift->add_flag("--json", o->json, "JSON: {\"device_id\", \"constants\": [...]}");
  drift->callback([o, exit_code] { *exit_code = RunRegistryDrift(*o); });

  CLI::App* due = reg->add_subcommand("due", "devices whose recalibration interval has run out");
  url(due);
  due->add_option("--interval-days", o->interval_days,
                  "recalibration interval [days] (default 365)");
  due->add_option("--at", o->at_utc, "judge at this ISO 8601 UTC time (default now)");
  due->add_flag("--all", o->all, "list every device with its due date");
  due->add_flag("--json", o->json,
                R"(JSON: {"at_utc", "interval_days", "devices": [{"device_id", "due", ...}]})");
  due->callback([o, exit_code] { *exit_code = RunRegistryDue(*o); });

  CLI::App* exported = reg->add_subcommand("export",
                                           "every calibration as CSV (one row per constant) "
                                           "or JSON");
  url(exported);
  exported->add_option("--format", o->format, "csv or json")->check(CLI::IsMember({"csv", "json"}));
  exported->add_option("-o,--output", o->output, "file to write (default - : stdout)");
  exported->callback([o, exit_code] { *exit_code = RunRegistryExport(*o); });
}

}  // namespace metro::calibrate_app
