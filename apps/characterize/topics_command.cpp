// characterize topics FILE [--lenient]: the topics of a PX4 ULog (name, multi id, message
// count, size, rate), its dropouts and appended data (docs/cli.md "topics").
#include <memory>

#include "commands.hpp"
#include "metro/io/ulog.hpp"
#include "output.hpp"

namespace metro::apps {
namespace {

struct TopicsOptions {
  std::string file;
  bool lenient = false;
};

int RunTopics(const TopicsOptions& o) {
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

}  // namespace

void AddTopicsCommand(CLI::App& app, int* exit_code) {
  auto o = std::make_shared<TopicsOptions>();
  CLI::App* sub = app.add_subcommand(
      "topics",
      "list a PX4 ULog's topics: name, multi id, messages, message size, rate; then its "
      "dropouts and appended data (choose IMU topics with --topic)");
  sub->add_option("file", o->file, "a PX4 ULog file (.ulg)")->required()->check(CLI::ExistingFile);
  sub->add_flag("--lenient", o->lenient,
                "read the complete messages of a truncated file, counting the loss");
  sub->callback([o, exit_code] { *exit_code = RunTopics(*o); });
}

}  // namespace metro::apps
