// calibrate station --port DEV --format raw --rate-hz R --tags FILE --sensor N
//   [--protocol six-face|ferraris|sphere] [--target-u-accel-mg X] [--target-u-gyro-dps Y]
//   [-o DIR] [--registry URL] [--push [--push-port DEV]] [--json-events] [--no-view]
// The guided live calibration (issue #44, docs/station.md): the guide is metro/station; after
// its stop, the same `calibrate fit`, `blob` and `push` run on the record it wrote.
// Its flags are bound in station_flags.hpp, which main.cpp includes.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "metro/station/station.hpp"
#include "metro/station/stream_reader.hpp"
#include "registry_hooks.hpp"

namespace metro::calibrate_app {

struct StationCliOptions {
  std::string port;
  std::string format = "raw";
  std::string protocol = "six-face";
  std::string model = "full";
  std::string tags;
  std::string out_dir = ".";
  std::string push_port;  // Default: --port.
  bool push = false;
  bool json_events = false;
  bool no_view = false;
  station::StationOptions station;
  station::StreamReaderOptions reader;
  RegistryCliOptions registry;
  // A `calibrate` command line (fit, blob, push) run in-process exactly as typed: bound by the
  // program's command line (station_flags.hpp), which is the one place that parses them.
  std::function<int(const std::vector<std::string>& args)> run_calibrate;
};

int RunStation(StationCliOptions c);

}  // namespace metro::calibrate_app
