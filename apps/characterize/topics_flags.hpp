// The flags of `characterize topics`.
// Included by main.cpp only: the program's one translation unit with CLI11 (issue #39).
#pragma once

#include <CLI/CLI.hpp>
#include <memory>

#include "cli_flags.hpp"
#include "topics_command.hpp"

namespace metro::apps {

inline void AddTopicsCommand(CLI::App& app, int* exit_code) {
  auto o = std::make_shared<TopicsOptions>();
  CLI::App* sub = app.add_subcommand(
      "topics",
      "list the topics of a PX4 ULog (name, multi id, messages, message size, rate, dropouts, "
      "appended data) or of an MCAP file, a ROS 1 bag or a ROS 2 bag folder (topic, message "
      "type, messages, rate, chunks); choose IMU topics with --topic");
  sub->add_option("file", o->file,
                  "a PX4 ULog (.ulg), an MCAP file (.mcap), a ROS 1 bag (.bag) or a ROS 2 bag "
                  "folder (or its metadata.yaml)")
      ->required()
      ->check(CLI::ExistingPath);
  sub->add_flag("--lenient", o->lenient,
                "read the complete messages of a truncated file, counting the loss");
  sub->callback([o, exit_code] { *exit_code = RunTopics(*o); });
}

}  // namespace metro::apps
