// characterize topics FILE [--lenient]: the topics of a PX4 ULog, an MCAP file, a ROS 1 or 2
// bag or an ArduPilot DataFlash log (docs/cli.md "topics").
#pragma once

#include <string>

namespace metro::apps {

struct TopicsOptions {
  std::string file;
  bool lenient = false;
};

int RunTopics(const TopicsOptions& o);

}  // namespace metro::apps
