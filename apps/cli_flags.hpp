// The command-line bindings both programs share: --version, --quiet, the session input's
// check and the load flags (load_cli.hpp). CLI11 is header-only and costs seconds of compile
// time in every translation unit that includes it, so only each program's main.cpp includes
// this header (issue #39): the commands themselves are plain options structs and Run
// functions.
#pragma once

#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <string>

#include "load_cli.hpp"
#include "metro/core/version.hpp"
#include "metro/io/ros_log.hpp"
#include "unix_cli.hpp"

namespace metro::apps {

// --version: "<program> (metro) <version>" on stdout, exit 0 (metro/core/version.hpp).
inline void AddVersionFlag(CLI::App& app, const std::string& program) {
  app.set_version_flag("--version", fmt::format("{} ({}) {}", program, kToolName, kVersion),
                       "print the version and exit");
}

// -q,--quiet on `app` and on each of its subcommands (so call it after adding them): it may
// be given before or after the subcommand's name.
inline void AddQuietFlag(CLI::App& app) {
  const char* help = "no progress, notes or tables: results, warnings and errors only";
  app.add_flag("-q,--quiet", QuietFlag(), help);
  for (CLI::App* sub : app.get_subcommands([](CLI::App*) { return true; })) {
    sub->add_flag("-q,--quiet", QuietFlag(), help);
  }
}

// CLI11 check of a session input: an existing file, a ROS 2 bag folder (with its
// metadata.yaml), or `-` (stdin).
inline CLI::Validator ExistingFileOrStdin() {
  return CLI::Validator(
      [](std::string& path) -> std::string {
        if (IsStdio(path) || IsRosbag2Path(path)) return std::string();
        return CLI::ExistingFile(path);
      },
      "FILE|-");
}

// Registers --format, --topic, --time, --time-order, --frame-period-s, --lenient, --column,
// --columns-file, --rate-hz and, with `full_scale_flags`, --accel-fs-g and --gyro-fs-dps (calibrate
// fit has its own).
inline void AddLoadCliOptions(CLI::App* app, LoadCliOptions* o, bool full_scale_flags = true) {
  app->add_option("--format", o->format,
                  "input format (auto: detected; csv is session.csv in any dialect)")
      ->check(CLI::IsMember({"auto", "csv", "receiver", "euroc", "raw", "phyphox", "sensorlogger",
                             "phone", "ulog", "mcap", "rosbag1", "rosbag2", "dataflash"}))
      ->capture_default_str();
  app->add_option("--topic", o->library.topics,
                  "ULog input: an IMU topic to read (sensor_combined, sensor_accel, sensor_gyro, "
                  "vehicle_imu), each instance one tag, NAME[K] instance K only (default: "
                  "sensor_combined, else sensor_accel and sensor_gyro); MCAP and ROS bags: a "
                  "sensor_msgs/Imu topic, e.g. /imu/data (default: the log's one IMU topic); "
                  "ArduPilot DataFlash: IMU, IMU2, IMU3, or IMU[K] for instance K of an IMU "
                  "message with an I column (default: all); repeatable, each topic one tag");
  app->add_option("--time", o->time,
                  "MCAP and ROS bags: the sample time, header (the message's header.stamp) or "
                  "receive (the time the recorder logged it)")
      ->check(CLI::IsMember({"header", "receive"}))
      ->capture_default_str();
  app->add_option("--time-order", o->time_order,
                  "MCAP, ROS bags, ULog: times out of order or repeated are sorted (repeats after "
                  "the first dropped, both counted in input.notes) or refused")
      ->check(CLI::IsMember({"sort", "refuse"}))
      ->capture_default_str();
  app->add_option("--frame-period-s", o->library.frame_period_s,
                  "receiver frame period in seconds (default 3281/32768 = 0.10013)")
      ->check(CLI::PositiveNumber);
  app->add_flag("--lenient", o->library.lenient,
                "skip malformed rows (counted in input.rejected_rows) instead of stopping");
  app->add_option("--column", o->columns,
                  "map a header name to a canonical column, 'SRC=DST' (SRC= leaves it out); "
                  "repeatable");
  app->add_option("--columns-file", o->columns_file, "a file of SRC=DST mappings, one per line")
      ->check(CLI::ExistingFile);
  app->add_option("--rate-hz", o->library.rate_hz,
                  "a file without a time column: sample k of each tag is at k / R seconds")
      ->check(CLI::PositiveNumber);
  if (full_scale_flags) {
    app->add_option("--accel-fs-g", o->library.accel_fs_g,
                    "raw accelerometer counts: full scale in g (adds ax_g.. beside ax_lsb..)")
        ->check(CLI::PositiveNumber);
    app->add_option("--gyro-fs-dps", o->library.gyro_fs_dps,
                    "raw gyroscope counts: full scale in deg/s (adds gx_dps.. beside gx_lsb..)")
        ->check(CLI::PositiveNumber);
  }
}

}  // namespace metro::apps
