// characterize convert INPUT... -o session.csv [--from auto|receiver|csv|imutk]
#include <fmt/format.h>

#include "commands.hpp"
#include "metro/core/file.hpp"
#include "metro/io/session_io.hpp"
#include "output.hpp"

namespace metro::apps {
namespace {

struct ConvertOptions {
  std::vector<std::string> inputs;
  std::string from = "auto";
  std::string output;
  double frame_period_s = kReceiverFramePeriodS;
  bool lenient = false;
};

int RunConvert(const ConvertOptions& o) {
  LoadOptions load;
  load.lenient = o.lenient;
  load.frame_period_s = o.frame_period_s;
  Result<Session> session = MakeError("no input");
  if (o.from == "imutk") {
    if (o.inputs.size() != 2) {
      PrintError(MakeError("--from imutk takes two inputs: ACC GYRO"));
      return kExitUsage;
    }
    session = LoadImuTk(o.inputs[0], o.inputs[1], load);
  } else {
    if (o.inputs.size() != 1) {
      PrintError(MakeError(fmt::format(
          "convert takes one input (or ACC GYRO with --from imutk), got {}", o.inputs.size())));
      return kExitUsage;
    }
    load.format = o.from == "receiver" ? SessionFormat::kReceiver
                  : o.from == "csv"    ? SessionFormat::kCsv
                                       : SessionFormat::kAuto;
    session = LoadSession(o.inputs[0], load);
  }
  if (Status s = CheckOutputPath(o.output, o.inputs); !s.ok()) {
    PrintError(s.error());
    return kExitUsage;
  }
  if (!session.ok()) {
    PrintError(session.error());
    return kExitUsage;
  }
  const Session& s = session.value();
  // Provenance and the frame counts, which session.csv rows cannot carry, as comments.
  std::string text = fmt::format("# metro convert: {} ({}, sha256 {})\n", s.path,
                                 SessionFormatName(s.format), s.sha256);
  if (s.format == SessionFormat::kReceiver) {
    text += fmt::format("# frame_period_s {}\n", s.frame_period_s);
    for (const Tag& t : s.tags) {
      text += fmt::format("# sensor {}: frames {} fresh {} stale {} never {}\n", t.sensor,
                          t.counts.frames, t.counts.fresh, t.counts.stale, t.counts.never);
    }
  }
  if (s.rejected_rows > 0) text += fmt::format("# rejected_rows {}\n", s.rejected_rows);
  text += FormatSessionCsv(s, true);
  if (Status w = WriteFileAtomically(o.output, text); !w.ok()) {
    PrintError(w.error());
    return kExitFailed;
  }
  int64_t observations = 0;
  for (const Tag& t : s.tags) observations += static_cast<int64_t>(t.size());
  fmt::print(stderr, "wrote {}: {} tags, {} observations\n", o.output, s.tags.size(), observations);
  return kExitOk;
}

}  // namespace

void AddConvertCommand(CLI::App& app, int* exit_code) {
  auto o = std::make_shared<ConvertOptions>();
  CLI::App* sub = app.add_subcommand(
      "convert", "turn a receiver capture or imu_tk's two files into canonical session.csv");
  sub->add_option("inputs", o->inputs, "INPUT (or ACC GYRO with --from imutk)")
      ->required()
      ->check(CLI::ExistingFile);
  sub->add_option("--from", o->from, "input format")
      ->check(CLI::IsMember({"auto", "receiver", "csv", "imutk"}))
      ->capture_default_str();
  sub->add_option("-o,--output", o->output, "session.csv to write")->required();
  sub->add_option("--frame-period-s", o->frame_period_s, "receiver frame period in seconds")
      ->check(CLI::PositiveNumber);
  sub->add_flag("--lenient", o->lenient, "skip malformed rows instead of stopping");
  sub->callback([o, exit_code] { *exit_code = RunConvert(*o); });
}

}  // namespace metro::apps
