// The flags of `characterize convert`.
// Included by main.cpp only: the program's one translation unit with CLI11 (issue #39).
#pragma once

#include <CLI/CLI.hpp>
#include <memory>

#include "cli_flags.hpp"
#include "convert_command.hpp"

namespace metro::apps {

inline void AddConvertCommand(CLI::App& app, int* exit_code) {
  auto o = std::make_shared<ConvertOptions>();
  CLI::App* sub = app.add_subcommand(
      "convert",
      "turn any readable session (receiver capture, EuRoC, raw prints, phyphox, Sensor Logger, PX4 "
      "ULog, MCAP, ROS 1 and ROS 2 bags, imu_tk's two files) into canonical session.csv; several "
      "files are joined on time");
  sub->add_option("inputs", o->inputs,
                  "INPUT, several files of one recording (joined on time), or ACC GYRO with "
                  "--imutk; - reads stdin")
      ->required()
      ->check(ExistingFileOrStdin());
  sub->add_option("-o,--output", o->output, "session.csv to write (- for stdout)")->required();
  // The load flags, --format among them, as every command that loads a session has them.
  AddLoadCliOptions(sub, &o->load);
  CLI::Option* format = sub->get_option("--format");
  CLI::Option* imutk =
      sub->add_flag("--imutk", o->imutk, "the inputs are imu_tk's two files: ACC GYRO")
          ->excludes(format);
  sub->add_option("--from", o->from, "the older spelling of --format (--from imutk: --imutk)")
      ->check(CLI::IsMember({"auto", "receiver", "csv", "imutk", "euroc", "raw", "phyphox",
                             "sensorlogger", "phone", "ulog"}))
      ->excludes(format)
      ->excludes(imutk);
  sub->callback([o, exit_code] { *exit_code = RunConvert(*o); });
}

}  // namespace metro::apps
