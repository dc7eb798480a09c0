// characterize topics FILE [--lenient]: the topics of a PX4 ULog (name, multi id, message
// count, size, rate), its dropouts and appended data; of an MCAP file or a ROS 1 or 2 bag
// (topic, message type, count, rate, chunks) (docs/cli.md "topics").
#include "topics_command.hpp"

#include <memory>

#include "metro/io/dataflash.hpp"
#include "metro/io/ros_log.hpp"
#include "metro/io/session_io.hpp"
#include "metro/io/ulog.hpp"
#include "output.hpp"

namespace metro::apps {
namespace {

int RunULogTopics(const TopicsOptions& o) {
  ULogReadOptions options;
  options.lenient = o.lenient;
  options.keep_topics = {""};  // Counts only: no data message kept.
  Result<ULog> log = ReadULog(o.file, options);
  if (!log.ok()) return PrintErrorExit(log.error());
  for (const std::string& p : log.value().problems) Note("warning: " + p + " (skipped)\n");
  if (Status s = WriteOutput("-", FormatULogTopics(log.value())); !s.ok()) {
    return PrintErrorExit(s.error());
  }
  return kExitOk;
}

int RunDataFlashTopics(const TopicsOptions& o) {
  Result<DataFlash> log = ReadDataFlash(o.file, {o.lenient, {}});
  if (!log.ok()) return PrintErrorExit(log.error());
  for (const std::string& p : log.value().problems) Note("warning: " + p + "\n");
  if (Status s = WriteOutput("-", FormatDataFlashTopics(log.value())); !s.ok()) {
    return PrintErrorExit(s.error());
  }
  return kExitOk;
}

}  // namespace

int RunTopics(const TopicsOptions& o) {
  Result<SessionFormat> format = DetectSessionFormat(o.file);
  if (!format.ok()) return PrintErrorExit(format.error());
  RosLogReadOptions options;
  options.lenient = o.lenient;
  Result<RosLog> log = MakeError(o.file, 0, "not read");
  switch (format.value()) {
    case SessionFormat::kULog:
      return RunULogTopics(o);
    case SessionFormat::kDataFlash:
      return RunDataFlashTopics(o);
    case SessionFormat::kMcap:
      log = ReadMcap(o.file, options, nullptr);
      break;
    case SessionFormat::kRosbag1:
      log = ReadRosbag1(o.file, options, nullptr);
      break;
    case SessionFormat::kRosbag2:
      log = ReadRosbag2(o.file, options, nullptr);
      break;
    default:
      return PrintErrorExit(MakeError(
          o.file, 0,
          fmt::format("{} input has no topics; expected a PX4 ULog, an MCAP file, a ROS 1 bag, "
                      "a ROS 2 bag folder or an ArduPilot DataFlash log",
                      SessionFormatName(format.value()))));
  }
  if (!log.ok()) return PrintErrorExit(log.error());
  for (const std::string& p : log.value().problems) Note("warning: " + p + " (skipped)\n");
  if (Status s = WriteOutput("-", FormatRosTopics(log.value())); !s.ok()) {
    return PrintErrorExit(s.error());
  }
  return kExitOk;
}

}  // namespace metro::apps
